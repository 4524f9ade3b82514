//! Where `tests/docs.rs` runs a page's marked blocks ([`super::runnable`]): a directory that
//! looks like the repository root to the commands of the docs.
//!
//! `scenarios/` and `maps/` are links to the repository's; `target/release/` and
//! `target/debug/` hold links to the workspace binaries the test was built with (so
//! `target/release/hnav` runs the test build's `hnav`, which starts the process binaries
//! beside its real path); a run writes `target/hnav-out/` inside the sandbox. The run
//! registry is the sandbox's own (`HNAV_RUNS_DIR`) and every run is in an iceoryx2 domain of
//! its own (`HNAV_DOMAIN`), so the fixed run ids of the docs (`--run rep`) meet no other
//! run, and whatever a failed block leaves in shared memory is found by its domain and
//! removed ([`Sandbox::purge`]).

use std::io::Read;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use hnav_runtime::transport::{purge_run, RunId};
use nix::sys::signal::{killpg, Signal};
use nix::unistd::Pid;

use super::runnable::{Action, Step};

/// How long one block may run.
pub const BLOCK_TIMEOUT: Duration = Duration::from_secs(120);

/// One page's sandbox.
pub struct Sandbox {
    dir: PathBuf,
    domain: String,
}

/// What a block did.
#[derive(Debug)]
pub struct Ran {
    /// Its exit code (`None`: killed, or timed out).
    pub code: Option<i32>,
    /// Standard output and error, interleaved as written.
    pub output: String,
}

impl Sandbox {
    /// Makes the sandbox in the empty directory `dir`, for the repository at `root` and the
    /// binaries in `bin_dir`; `tag` (letters and digits) names its iceoryx2 domain.
    pub fn new(dir: &Path, root: &Path, bin_dir: &Path, tag: &str) -> std::io::Result<Sandbox> {
        use std::os::unix::fs::symlink;
        for name in ["scenarios", "maps"] {
            symlink(root.join(name), dir.join(name))?;
        }
        for profile in ["release", "debug"] {
            let target = dir.join("target").join(profile);
            std::fs::create_dir_all(&target)?;
            for entry in std::fs::read_dir(bin_dir)? {
                let entry = entry?;
                let name = entry.file_name();
                let text = name.to_string_lossy();
                if text.starts_with("hnav") && !text.contains('.') && entry.file_type()?.is_file() {
                    symlink(entry.path(), target.join(&name))?;
                }
            }
        }
        std::fs::create_dir_all(dir.join("runs"))?;
        let tag: String = tag
            .chars()
            .filter(char::is_ascii_alphanumeric)
            .take(8)
            .collect();
        Ok(Sandbox {
            dir: dir.to_path_buf(),
            domain: format!("d{tag}{}", std::process::id() % 10_000_000),
        })
    }

    /// Does `step`: writes or appends its file, or runs it.
    pub fn apply(&self, step: &Step) -> std::io::Result<Option<Ran>> {
        match &step.action {
            Action::File(name) => std::fs::write(self.dir.join(name), &step.text).map(|()| None),
            Action::Append(name) => {
                use std::io::Write;
                std::fs::OpenOptions::new()
                    .append(true)
                    .open(self.dir.join(name))?
                    .write_all(step.text.as_bytes())
                    .map(|()| None)
            }
            Action::Run(_) => self.run(&step.text).map(Some),
        }
    }

    /// Runs `script` with `sh -e` in the sandbox, in a process group of its own that is
    /// killed after [`BLOCK_TIMEOUT`].
    pub fn run(&self, script: &str) -> std::io::Result<Ran> {
        let (reader, writer) = std::io::pipe()?;
        let mut child = Command::new("sh")
            .arg("-e")
            .arg("-c")
            .arg(script)
            .current_dir(&self.dir)
            .env("HNAV_RUNS_DIR", self.dir.join("runs"))
            .env("HNAV_DOMAIN", &self.domain)
            .stdin(Stdio::null())
            .stdout(writer.try_clone()?)
            .stderr(writer)
            .process_group(0)
            .spawn()?;
        let pgid = Pid::from_raw(child.id() as i32);
        let (tx, rx) = mpsc::channel();
        let mut reader = reader;
        std::thread::spawn(move || {
            let mut output = String::new();
            let _ = reader.read_to_string(&mut output);
            let _ = tx.send(output);
        });
        let (code, output) = match rx.recv_timeout(BLOCK_TIMEOUT) {
            Ok(output) => (child.wait()?.code(), output),
            Err(_) => {
                let _ = killpg(pgid, Signal::SIGKILL);
                let _ = child.wait();
                let output = rx.recv_timeout(Duration::from_secs(10)).unwrap_or_default();
                (None, format!("{output}\n(killed after {BLOCK_TIMEOUT:?})"))
            }
        };
        Ok(Ran { code, output })
    }

    /// Removes what runs of the sandbox's domain left in shared memory and iceoryx2's
    /// directory (nothing, when every run ended well).
    pub fn purge(&self) {
        let marker = format!(".{}_", self.domain);
        let Ok(entries) = std::fs::read_dir("/dev/shm") else {
            return;
        };
        let mut runs: Vec<String> = entries
            .flatten()
            .filter_map(|e| {
                let name = e.file_name().to_string_lossy().into_owned();
                let rest = name.strip_prefix("hnav_")?;
                let end = rest.find(&marker)?;
                Some(rest[..end].to_string())
            })
            .collect();
        runs.sort();
        runs.dedup();
        for run in runs {
            if let Ok(id) = RunId::new(&run).and_then(|r| r.in_domain(&self.domain)) {
                if let Err(e) = purge_run(&id) {
                    eprintln!("cleanup of run {run} in domain {}: {e}", self.domain);
                }
            }
        }
    }
}

impl Drop for Sandbox {
    fn drop(&mut self) {
        self.purge();
    }
}
