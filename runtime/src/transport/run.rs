//! Run identity: service names and the per-run iceoryx2 configuration.

use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use iceoryx2::config::Config;
use iceoryx2::prelude::{FileName, Path as IoxPath, SemanticString, ServiceName};

use super::nodes::cleanup_dead_nodes_in;
use super::{Ipc, TransportError};

/// Where POSIX shared memory lives on Linux; iceoryx2 names its segments with the config prefix.
const SHM_DIR: &str = "/dev/shm";

/// The environment variable naming this process's iceoryx2 domain: processes of one run
/// meet only within one domain. Unset on a single host. Two "hosts" on one machine (the
/// bridge's tests) set it apart, so that only the Zenoh bridge links them.
pub const DOMAIN_ENV: &str = "HNAV_DOMAIN";

/// The identity of one swarm run.
///
/// It scopes service names (`hnav/<run-id>/<topic>`) and the iceoryx2 file prefix
/// (`hnav_<run-id>_`, or `hnav_<run-id>.<domain>_` in a [domain](DOMAIN_ENV)), so runs never
/// meet. Allowed: 1 to 48 ASCII letters, digits, `-`, `_` (a domain: 1 to 16 of them).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct RunId(String, Option<String>);

impl RunId {
    /// Longest accepted id: keeps file names of the form `<prefix><hash>...` far below 255 bytes.
    pub const MAX_LEN: usize = 48;

    /// Validates a run id.
    pub fn new(id: &str) -> Result<Self, TransportError> {
        let bad = |why| TransportError::InvalidRunId {
            id: id.to_string(),
            why,
        };
        if id.is_empty() {
            return Err(bad("empty"));
        }
        if id.len() > Self::MAX_LEN {
            return Err(bad("longer than 48 characters"));
        }
        if !id
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_')
        {
            return Err(bad("only ASCII letters, digits, '-' and '_' are allowed"));
        }
        Ok(Self(id.to_string(), domain_from_env()?))
    }

    /// The same run in iceoryx2 domain `domain` instead of the environment's.
    pub fn in_domain(self, domain: &str) -> Result<Self, TransportError> {
        valid_domain(domain)?;
        Ok(Self(self.0, Some(domain.to_string())))
    }

    /// The iceoryx2 domain this id is in, if any.
    pub fn domain(&self) -> Option<&str> {
        self.1.as_deref()
    }

    /// A fresh id that no other run on this machine uses: `<tag>-<pid>-<nanoseconds>`.
    pub fn unique(tag: &str) -> Self {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos() as u64)
            .unwrap_or(0);
        let tag: String = tag
            .chars()
            .filter(|c| c.is_ascii_alphanumeric())
            .take(16)
            .collect();
        let id = format!("{tag}-{}-{:x}", std::process::id(), nanos);
        Self(id, domain_from_env().ok().flatten())
    }

    /// The id as text.
    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// The full service name of a topic in this run: `hnav/<run-id>/<topic>`.
    pub fn service_name(&self, topic: &str) -> Result<ServiceName, TransportError> {
        let name = format!("hnav/{}/{}", self.0, topic);
        ServiceName::new(&name).map_err(|e| TransportError::InvalidName {
            name,
            why: super::error::in_words(&format!("{e:?}")),
        })
    }

    /// The iceoryx2 file prefix of this run (in its domain).
    pub fn prefix(&self) -> String {
        match &self.1 {
            None => format!("hnav_{}_", self.0),
            // `.` is in no run id, so no other run's prefix starts like this one.
            Some(domain) => format!("hnav_{}.{domain}_", self.0),
        }
    }
}

/// The domain [`DOMAIN_ENV`] names, if it is set and not empty.
fn domain_from_env() -> Result<Option<String>, TransportError> {
    match std::env::var(DOMAIN_ENV) {
        Ok(d) if !d.is_empty() => valid_domain(&d).map(|()| Some(d)),
        Ok(_) | Err(std::env::VarError::NotPresent) => Ok(None),
        Err(std::env::VarError::NotUnicode(d)) => Err(TransportError::InvalidRunId {
            id: d.to_string_lossy().into_owned(),
            why: "HNAV_DOMAIN is not UTF-8",
        }),
    }
}

/// Whether `d` can name an iceoryx2 domain ([`DOMAIN_ENV`]): 1 to 16 ASCII letters, digits,
/// `-` and `_`. A host of a run across hosts is named so too, so that hosts sharing a
/// machine can take their names as their domains.
pub fn is_domain_name(d: &str) -> bool {
    (1..=16).contains(&d.len())
        && d.bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_')
}

fn valid_domain(d: &str) -> Result<(), TransportError> {
    if is_domain_name(d) {
        Ok(())
    } else {
        Err(TransportError::InvalidRunId {
            id: d.to_string(),
            why: "a domain (HNAV_DOMAIN) is 1 to 16 ASCII letters, digits, '-' and '_'",
        })
    }
}

impl core::fmt::Display for RunId {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(&self.0)
    }
}

/// The environment variable that replaces [`ipc_root`]'s per-user default (a group of users
/// who share runs can point it at one directory they may all write).
pub const IPC_ROOT_ENV: &str = "HNAV_IPC_ROOT";

/// The directory where iceoryx2 keeps this user's node and service files (its
/// `global.root-path`): `$HNAV_IPC_ROOT` if set, else iceoryx2's own `/tmp/iceoryx2/` for
/// root and `/tmp/iceoryx2-<uid>/` for every other user.
///
/// iceoryx2 creates its directory readable by its owner and group only, so one directory
/// for every user would lock out all but the first to run; shared-memory file names are
/// run-scoped already ([`RunId::prefix`]), so per-user directories are all it takes for
/// several users to run side by side.
pub fn ipc_root() -> PathBuf {
    if let Some(dir) = std::env::var_os(IPC_ROOT_ENV).filter(|d| !d.is_empty()) {
        return PathBuf::from(dir);
    }
    match effective_uid() {
        0 => PathBuf::from("/tmp/iceoryx2/"),
        uid => PathBuf::from(format!("/tmp/iceoryx2-{uid}/")),
    }
}

fn effective_uid() -> u32 {
    // SAFETY: geteuid has no preconditions and cannot fail.
    unsafe { libc::geteuid() }
}

/// The iceoryx2 configuration of a run: the defaults with this user's [`ipc_root`] and the
/// run's own file prefix.
///
/// Every process of a run must build its nodes with this config (the transport does), and
/// tools that inspect a run (`Node::list`) must pass it too: other prefixes are invisible.
pub fn run_config(run: &RunId) -> Config {
    let mut config = Config::default();
    // A RunId holds only [A-Za-z0-9_-], which is always a valid file name.
    if let Ok(prefix) = FileName::new(run.prefix().as_bytes()) {
        config.global.prefix = prefix;
    }
    let mut root = ipc_root().into_os_string().into_encoded_bytes();
    if root.last() != Some(&b'/') {
        root.push(b'/');
    }
    match IoxPath::new(&root) {
        Ok(path) => config.global.set_root_path(&path),
        Err(_) => tracing::warn!(
            "{IPC_ROOT_ENV}={} is not a usable path (too long, or not a path); using {}",
            String::from_utf8_lossy(&root),
            config.global.root_path()
        ),
    }
    config
}

/// Checks that this process may use the iceoryx2 directory of `config` (and its `nodes/` and
/// `services/`), or create it, before a node is created: iceoryx2 would otherwise report only
/// an `InternalError`, after leaving a management file of the run in `/dev/shm`.
pub(crate) fn check_ipc_root(config: &Config) -> Result<(), TransportError> {
    let root = PathBuf::from(config.global.root_path().to_string());
    let problem = |problem: String| TransportError::IpcRoot {
        dir: root.clone(),
        problem,
    };
    let uid = effective_uid();
    match std::fs::metadata(&root) {
        Ok(m) if !m.is_dir() => return Err(problem("it is not a directory".into())),
        Ok(m) => {
            let is_default = std::env::var_os(IPC_ROOT_ENV).is_none_or(|d| d.is_empty());
            if is_default && uid != 0 && m.uid() != uid {
                return Err(problem(format!(
                    "it belongs to uid {} (mode {:04o}), not to this user (uid {uid}); remove \
                     it, or set {IPC_ROOT_ENV} to a directory of your own",
                    m.uid(),
                    m.mode() & 0o7777
                )));
            }
            for dir in [
                root.clone(),
                root.join(config.global.node.directory.to_string()),
                root.join(config.global.service.directory.to_string()),
            ] {
                if let Err(why) = accessible(&dir, libc::R_OK | libc::W_OK | libc::X_OK) {
                    return Err(TransportError::IpcRoot { dir, problem: why });
                }
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let parent = root
                .parent()
                .filter(|p| !p.as_os_str().is_empty())
                .unwrap_or(std::path::Path::new("/"));
            if let Err(why) = accessible(parent, libc::W_OK | libc::X_OK) {
                return Err(problem(format!(
                    "it does not exist and cannot be created in {}: {why}",
                    parent.display()
                )));
            }
        }
        Err(e) => return Err(problem(e.to_string())),
    }
    Ok(())
}

/// Whether this process may access an existing `dir` in `mode`; a missing one is fine (the
/// node creates it). The error says what is missing, for whom.
fn accessible(dir: &std::path::Path, mode: libc::c_int) -> Result<(), String> {
    let Ok(meta) = std::fs::metadata(dir) else {
        return Ok(());
    };
    let Ok(c_path) = std::ffi::CString::new(dir.as_os_str().as_encoded_bytes()) else {
        return Err("its path holds a NUL byte".into());
    };
    // SAFETY: `c_path` is a valid NUL-terminated string; faccessat only reads it.
    let rc = unsafe { libc::faccessat(libc::AT_FDCWD, c_path.as_ptr(), mode, libc::AT_EACCESS) };
    if rc == 0 {
        return Ok(());
    }
    let wanted = if mode & libc::R_OK != 0 {
        "read, write and enter"
    } else {
        "write and enter"
    };
    Err(format!(
        "permission denied: this user (uid {}) may not {wanted} it (owner uid {}, group {}, \
         mode {:04o})",
        effective_uid(),
        meta.uid(),
        meta.gid(),
        meta.mode() & 0o7777
    ))
}

/// Whether the file `name` is one iceoryx2 made for the run with file prefix `prefix`.
///
/// iceoryx2 follows the prefix with a hash or node id (16 or more hex or decimal digits) or
/// with `node`. The extra check keeps the files of run `a_<hex>...` away from run `a`, whose
/// prefix `hnav_a_` they also start with, unless the longer id itself continues with 16 hex
/// digits or `node` after the underscore.
fn belongs_to_run(name: &[u8], prefix: &str) -> bool {
    let Some(rest) = name.strip_prefix(prefix.as_bytes()) else {
        return false;
    };
    let first = rest
        .split(|&b| b == b'_' || b == b'.')
        .next()
        .unwrap_or_default();
    first == b"node" || (first.len() >= 16 && first.iter().all(u8::is_ascii_hexdigit))
}

/// The files of `dir` (not recursive) that belong to the run with file prefix `prefix`.
fn files_of_run_in(dir: &Path, prefix: &str) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    entries
        .filter_map(Result::ok)
        .filter(|e| belongs_to_run(e.file_name().as_bytes(), prefix))
        .filter(|e| e.file_type().is_ok_and(|t| !t.is_dir()))
        .map(|e| e.path())
        .collect()
}

/// The shared-memory files of a run that exist now in `/dev/shm`.
pub fn run_shm_files(run: &RunId) -> Vec<PathBuf> {
    files_of_run_in(Path::new(SHM_DIR), &run.prefix())
}

/// The files of a run that exist now under iceoryx2's root directory (`/tmp/iceoryx2` by
/// default, or the root of [`run_config`]): event and service files, node monitors, and the
/// files in each of the run's node directories (`nodes/<node id>/`).
pub fn run_iceoryx2_files(run: &RunId) -> Vec<PathBuf> {
    let config = run_config(run);
    let prefix = run.prefix();
    let std_path = |bytes: &[u8]| PathBuf::from(std::ffi::OsStr::from_bytes(bytes));
    let node_dir = std_path(config.global.node_dir().as_bytes());
    let root = std_path(config.global.root_path().as_bytes());
    let mut files = files_of_run_in(&root, &prefix);
    files.extend(files_of_run_in(
        &std_path(config.global.service_dir().as_bytes()),
        &prefix,
    ));
    files.extend(files_of_run_in(&node_dir, &prefix));
    if let Ok(entries) = std::fs::read_dir(&node_dir) {
        for e in entries.filter_map(Result::ok) {
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                files.extend(files_of_run_in(&e.path(), &prefix));
            }
        }
    }
    files
}

/// A throwaway run (a test's, say) whose leftovers are purged ([`purge_run`]) when it is
/// dropped, even when the code that made it panics.
pub struct PurgeOnDrop(pub RunId);

impl Drop for PurgeOnDrop {
    fn drop(&mut self) {
        let _ = purge_run(&self.0);
    }
}

/// Removes what a finished run left behind: stale resources of dead nodes, then the run's
/// global management segment, then any file of the run still in `/dev/shm` or under
/// iceoryx2's root directory ([`run_iceoryx2_files`]; a node directory left empty goes too).
///
/// Call it only when no process of the run is alive any more (the supervisor after the last
/// child was reaped, a test after its children exited, `hnav clean` after a supervisor's
/// death): it returns an error and removes nothing if a live node of the run is found.
/// Returns the number of files removed in the last step, which is 0 when every process
/// exited cleanly.
pub fn purge_run(run: &RunId) -> Result<usize, TransportError> {
    let config = run_config(run);
    let report = cleanup_dead_nodes_in(&config)?;
    if report.alive > 0 {
        return Err(TransportError::Iceoryx {
            op: "purge run",
            service: run.to_string(),
            detail: format!("{} node(s) of the run are still alive", report.alive),
        });
    }
    // SAFETY: no node of this run's config is alive (checked just above, and the caller
    // guarantees no new one is being created), so nothing maps the global management segment.
    let _ = unsafe { iceoryx2::testing::remove_global_mgmt_segment::<Ipc>(&config) };
    let mut removed = 0;
    for file in run_shm_files(run)
        .into_iter()
        .chain(run_iceoryx2_files(run))
    {
        if std::fs::remove_file(&file).is_ok() {
            tracing::debug!(file = %file.display(), "removed a file the run left");
            removed += 1;
        }
        // A node's own directory goes once its last file is gone (this fails, harmlessly,
        // for the shared directories and for a node directory that is not empty yet).
        if let Some(parent) = file
            .parent()
            .filter(|p| p.parent().is_some_and(|pp| pp.ends_with("nodes")))
        {
            let _ = std::fs::remove_dir(parent);
        }
    }
    Ok(removed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_ids_are_validated() {
        assert!(RunId::new("demo-1_a").is_ok());
        assert!(RunId::new("").is_err());
        assert!(RunId::new("a/b").is_err());
        assert!(RunId::new("a b").is_err());
        assert!(RunId::new(&"x".repeat(49)).is_err());
        assert!(RunId::new(&"x".repeat(48)).is_ok());
    }

    #[test]
    fn unique_ids_differ_and_are_valid() {
        let a = RunId::unique("t e/st");
        let b = RunId::unique("t e/st");
        assert_ne!(a, b);
        assert!(RunId::new(a.as_str()).is_ok());
    }

    #[test]
    fn a_domain_gets_a_prefix_of_its_own() {
        let plain = RunId::new("a").unwrap().in_domain("x").unwrap();
        assert_eq!(plain.prefix(), "hnav_a.x_");
        assert_eq!(plain.as_str(), "a");
        assert_eq!(plain.domain(), Some("x"));
        assert!(!belongs_to_run(b"hnav_a.x_node.details", "hnav_a_"));
        assert!(!belongs_to_run(b"hnav_a_node.details", &plain.prefix()));
        for bad in ["", "a.b", "seventeen-chars-x"] {
            assert!(RunId::new("a").unwrap().in_domain(bad).is_err(), "{bad:?}");
        }
    }

    #[test]
    fn files_of_a_longer_run_id_are_not_taken() {
        let hash = "8e87768bd42e4142a6bc3d611ff9f2be43bee772";
        let p = RunId::new("a").unwrap().prefix();
        assert!(belongs_to_run(
            format!("hnav_a_{hash}.service").as_bytes(),
            &p
        ));
        assert!(belongs_to_run(
            format!("hnav_a_{hash}_{hash}.data").as_bytes(),
            &p
        ));
        assert!(belongs_to_run(
            b"hnav_a_1426107235257767498930479707019.event",
            &p
        ));
        assert!(belongs_to_run(b"hnav_a_node.details", &p));
        assert!(!belongs_to_run(
            format!("hnav_a_b_{hash}.service").as_bytes(),
            &p
        ));
        assert!(!belongs_to_run(b"hnav_a_run-1-17f_node.details", &p));
        assert!(!belongs_to_run(b"hnav_ab_node.details", &p));
    }

    #[test]
    fn names_and_prefix_are_run_scoped() {
        let run = RunId::new("r1").unwrap();
        let name = run.service_name("odom/3").unwrap();
        assert_eq!(name.as_str(), "hnav/r1/odom/3");
        assert_eq!(
            run_config(&run).global.prefix,
            FileName::new(b"hnav_r1_").unwrap()
        );
    }
}
