//! A run's hold on its output directory.
//!
//! `hnav run` takes an exclusive lock on [`LOCK_FILE`] in the run directory before it
//! changes anything there and keeps it until the run has ended (the kernel drops it if the
//! supervisor dies). The lock file names the run id and the supervisor's pid, so a second run
//! on the same directory is refused with an error naming the live one.
//!
//! A directory that holds a finished run's output ([`RUN_OUTPUTS`]) is not reused silently:
//! without `--force` the claim is refused; with it, exactly those outputs are removed
//! (never anything else a user keeps there), since a log left in place would make the new
//! coordinator resume the old run.

use std::path::{Path, PathBuf};

use hnav_runtime::file_lock::{try_lock, FileLock, TryLock};
use hnav_runtime::transport::RunId;

/// The lock file in the run directory.
pub const LOCK_FILE: &str = ".hnav-run.lock";

/// What a run writes into its directory: the consensus log, the agents' and the sim's
/// checkpoints, the processes' output, the summary, the event journal, the coordinator's
/// counts of dropped candidates, the sim's and the coordinator's criteria, the recording,
/// the copy of the map, the report and how the run was started (for `hnav log replay`).
/// `--force` removes these and nothing else (a restarted coordinator or sim reads its own
/// file back, so an earlier run's must not be left).
pub const RUN_OUTPUTS: [&str; 14] = [
    "log",
    "agents",
    "sim.ckpt.0",
    "sim.ckpt.1",
    "logs",
    "summary.json",
    "events.jsonl",
    hnav_runtime::rejected::FILE,
    hnav_runtime::criteria::files::SIM_FILE,
    hnav_runtime::criteria::files::LATENCY_FILE,
    crate::recording::DIR,
    crate::report::MAP_FILE,
    crate::report::FILE,
    crate::invocation::FILE,
];

/// Why a run directory cannot be claimed.
#[derive(Debug, thiserror::Error)]
pub enum RunDirError {
    /// A live run holds the directory.
    #[error("{}: in use by a live run (run {}, supervisor pid {}); wait for it to end, stop it, or pass another --out", dir.display(), run.as_deref().unwrap_or("unknown"), pid.as_deref().unwrap_or("unknown"))]
    Live {
        /// The directory.
        dir: PathBuf,
        /// The live run's id, as its lock file names it.
        run: Option<String>,
        /// Its supervisor's pid, as its lock file names it.
        pid: Option<String>,
    },
    /// The directory holds the output of a finished run.
    #[error("{}: holds the output of an earlier run ({found}); pass --force to replace it, or another --out", dir.display())]
    Finished {
        /// The directory.
        dir: PathBuf,
        /// The outputs found, comma-separated.
        found: String,
    },
    /// A file operation failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
}

/// A claimed run directory; the claim lasts until [`RunDir::release`] or the process's end.
#[derive(Debug)]
pub struct RunDir {
    lock: FileLock,
}

impl RunDir {
    /// Claims `dir` (created if missing) for `run`: refused while another run holds it, and
    /// refused when it holds an earlier run's outputs unless `force`, which removes them.
    pub fn claim(dir: &Path, run: &RunId, force: bool) -> Result<RunDir, RunDirError> {
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| RunDirError::Io { path, source }
        };
        let lock_path = dir.join(LOCK_FILE);
        let fields = [
            ("run", run.as_str().to_string()),
            ("pid", std::process::id().to_string()),
        ];
        let lock = match try_lock(&lock_path, &fields).map_err(io(&lock_path))? {
            TryLock::Acquired(lock) => lock,
            TryLock::Held(holder) => {
                return Err(RunDirError::Live {
                    dir: dir.to_path_buf(),
                    run: holder.get("run").map(str::to_string),
                    pid: holder.get("pid").map(str::to_string),
                })
            }
        };
        let found: Vec<&str> = RUN_OUTPUTS
            .into_iter()
            .filter(|name| dir.join(name).symlink_metadata().is_ok())
            .collect();
        if !found.is_empty() && !force {
            // Leave the directory as it was: no lock file of ours either.
            let _ = lock.remove();
            return Err(RunDirError::Finished {
                dir: dir.to_path_buf(),
                found: found.join(", "),
            });
        }
        for name in found {
            let p = dir.join(name);
            let removed = if p.symlink_metadata().is_ok_and(|m| m.is_dir()) {
                std::fs::remove_dir_all(&p)
            } else {
                std::fs::remove_file(&p)
            };
            removed.map_err(io(&p))?;
        }
        Ok(RunDir { lock })
    }

    /// Ends the claim and removes the lock file.
    pub fn release(self) -> Result<(), RunDirError> {
        let path = self.lock.path().to_path_buf();
        self.lock
            .remove()
            .map_err(|source| RunDirError::Io { path, source })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_live_claim_refuses_a_second_and_outputs_need_force() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("out");
        let a = RunId::new("a").unwrap();
        let b = RunId::new("b").unwrap();
        let claim = RunDir::claim(&dir, &a, false).unwrap();
        let err = RunDir::claim(&dir, &b, true).unwrap_err().to_string();
        assert!(
            err.contains("run a,") && err.contains(&format!("pid {}", std::process::id())),
            "{err}"
        );
        std::fs::create_dir_all(dir.join("log")).unwrap();
        std::fs::write(dir.join("summary.json"), "{}").unwrap();
        std::fs::write(dir.join("notes.txt"), "mine").unwrap();
        claim.release().unwrap();
        let err = RunDir::claim(&dir, &b, false).unwrap_err().to_string();
        assert!(
            err.contains("--force") && err.contains("log, summary.json"),
            "{err}"
        );
        assert!(dir.join("log").exists() && !dir.join(LOCK_FILE).exists());
        let claim = RunDir::claim(&dir, &b, true).unwrap();
        assert!(!dir.join("log").exists() && !dir.join("summary.json").exists());
        assert_eq!(
            std::fs::read_to_string(dir.join("notes.txt")).unwrap(),
            "mine"
        );
        claim.release().unwrap();
    }
}
