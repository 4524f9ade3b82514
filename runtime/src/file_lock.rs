//! Exclusive, non-blocking advisory locks on files (`flock(2)` through
//! [`File::try_lock`]).
//!
//! A run owns its directory, its run id and its consensus log by holding such a lock for its
//! lifetime. The kernel releases a flock when the last descriptor of the open file goes away,
//! so a holder killed by SIGKILL never leaves a lock behind, and a newcomer never has to guess
//! from pids whether a lock is still meant.
//!
//! The lock file holds a short text naming its holder (`key=value` lines, e.g. the run id and
//! the pid), so that a refused newcomer can say who holds it. A holder may remove the file
//! when it is done ([`FileLock::remove`]); a newcomer that opened the file just before it was
//! removed would then hold a lock nobody else can see, so [`try_lock`] checks after locking
//! that the path still names the file it locked, and starts again if not.
//!
//! A lock this very process released can still be held for a moment: a child forked by
//! another thread (a `Command` spawning a process) holds a copy of every descriptor until it
//! execs, and close-on-exec only closes them then. A lock file naming our own pid as its
//! holder is therefore tried again for up to [`OWN_RELEASE_WAIT`] before it counts as held
//! (`log_cli::summary` reopened its own log while a sibling test spawned `hnav`, and was
//! refused, at a load average of 5).

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{self, Read, Seek, Write};
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

/// A lock held on a file; released when dropped (or when the process dies).
#[derive(Debug)]
pub struct FileLock {
    /// Held, never read: the lock lives as long as this descriptor.
    _file: File,
    path: PathBuf,
}

impl FileLock {
    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Removes the lock file, then releases the lock: the next holder creates a new file.
    /// A file already gone is not an error.
    pub fn remove(self) -> io::Result<()> {
        match std::fs::remove_file(&self.path) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(()),
            Err(e) => Err(e),
        }
    }
}

/// What [`try_lock`] found.
#[derive(Debug)]
pub enum TryLock {
    /// The lock is ours now, and the file names us.
    Acquired(FileLock),
    /// Someone holds it; their `key=value` lines, as far as they could be read.
    Held(Holder),
}

/// What a lock file says about its holder.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Holder {
    /// The `key=value` pairs of the file, in order.
    pub fields: Vec<(String, String)>,
}

impl Holder {
    /// The value of `key`, if the file names it.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.fields
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    fn parse(text: &str) -> Holder {
        let fields = text
            .lines()
            .filter_map(|l| l.split_once('='))
            .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
            .collect();
        Holder { fields }
    }
}

/// How often [`try_lock`] starts again when the file it locked was removed under it; each
/// attempt needs a holder to remove the file in between, so this is never reached in practice.
const ATTEMPTS: usize = 16;

/// How long a lock whose file names this process is tried again (see the module docs).
pub const OWN_RELEASE_WAIT: std::time::Duration = std::time::Duration::from_millis(500);

/// Takes the exclusive lock on `path` (created if missing, parent directories too) without
/// waiting, and writes `fields` into it as `key=value` lines. When someone else holds it,
/// returns what the file says about them.
pub fn try_lock(path: &Path, fields: &[(&str, String)]) -> io::Result<TryLock> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let own = std::process::id().to_string();
    let patience = std::time::Instant::now() + OWN_RELEASE_WAIT;
    let mut attempts = 0;
    while attempts < ATTEMPTS {
        attempts += 1;
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let mut text = String::new();
                // The holder may be between truncating and writing: an empty holder then.
                let _ = file.read_to_string(&mut text);
                let holder = Holder::parse(&text);
                if holder.get("pid") == Some(own.as_str()) && std::time::Instant::now() < patience {
                    // No event says when a forked child execs: look again shortly.
                    std::thread::sleep(std::time::Duration::from_millis(2));
                    attempts -= 1;
                    continue;
                }
                return Ok(TryLock::Held(holder));
            }
            Err(TryLockError::Error(e)) => return Err(e),
        }
        if !same_file(&file, path)? {
            continue;
        }
        file.set_len(0)?;
        file.rewind()?;
        let text: String = fields.iter().map(|(k, v)| format!("{k}={v}\n")).collect();
        file.write_all(text.as_bytes())?;
        return Ok(TryLock::Acquired(FileLock {
            _file: file,
            path: path.to_path_buf(),
        }));
    }
    Err(io::Error::other(format!(
        "{}: the lock file was replaced {ATTEMPTS} times while being locked",
        path.display()
    )))
}

/// Whether `path` still names the open `file` (same device and inode).
fn same_file(file: &File, path: &Path) -> io::Result<bool> {
    let open = file.metadata()?;
    match std::fs::metadata(path) {
        Ok(now) => Ok(now.dev() == open.dev() && now.ino() == open.ino()),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(false),
        Err(e) => Err(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_is_refused_and_names_the_holder() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sub/x.lock");
        let TryLock::Acquired(lock) = try_lock(&path, &[("pid", "42".into())]).unwrap() else {
            panic!("the first lock is refused");
        };
        match try_lock(&path, &[("pid", "43".into())]).unwrap() {
            TryLock::Held(h) => assert_eq!(h.get("pid"), Some("42")),
            TryLock::Acquired(_) => panic!("two holders of one lock"),
        }
        drop(lock);
        let TryLock::Acquired(again) = try_lock(&path, &[("pid", "44".into())]).unwrap() else {
            panic!("a released lock is refused");
        };
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "pid=44\n");
        again.remove().unwrap();
        assert!(!path.exists());
    }

    #[test]
    fn a_lock_this_process_is_releasing_is_waited_for_and_one_it_keeps_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("own.lock");
        let me = [("pid", std::process::id().to_string())];
        let TryLock::Acquired(lock) = try_lock(&path, &me).unwrap() else {
            panic!("the first lock is refused");
        };
        // As a forked child's copy of the descriptor would, the lock outlives its release by
        // a moment.
        let (tx, rx) = std::sync::mpsc::channel::<()>();
        let late = std::thread::spawn(move || {
            let _ = rx.recv();
            std::thread::sleep(std::time::Duration::from_millis(50));
            drop(lock);
        });
        tx.send(()).unwrap();
        let TryLock::Acquired(mine) = try_lock(&path, &me).unwrap() else {
            panic!("a lock of this process released 50 ms later was refused");
        };
        late.join().unwrap();
        let started = std::time::Instant::now();
        match try_lock(&path, &me).unwrap() {
            TryLock::Held(h) => assert_eq!(h.get("pid"), Some(me[0].1.as_str())),
            TryLock::Acquired(_) => panic!("two holders of one lock"),
        }
        assert!(started.elapsed() >= OWN_RELEASE_WAIT);
        drop(mine);
    }
}
