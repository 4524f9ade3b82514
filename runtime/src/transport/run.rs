//! Run identity: service names and the per-run iceoryx2 configuration.

use std::path::PathBuf;

use iceoryx2::config::Config;
use iceoryx2::prelude::{FileName, SemanticString, ServiceName};

use super::{Ipc, TransportError};

/// Where POSIX shared memory lives on Linux; iceoryx2 names its segments with the config prefix.
const SHM_DIR: &str = "/dev/shm";

/// The identity of one swarm run.
///
/// It scopes service names (`hnav/<run-id>/<topic>`) and the iceoryx2 file prefix
/// (`hnav_<run-id>_`), so runs never meet. Allowed: 1 to 48 ASCII letters, digits, `-`, `_`.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct RunId(String);

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
        Ok(Self(id.to_string()))
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
        Self(format!("{tag}-{}-{:x}", std::process::id(), nanos))
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

    /// The iceoryx2 file prefix of this run.
    pub fn prefix(&self) -> String {
        format!("hnav_{}_", self.0)
    }
}

impl core::fmt::Display for RunId {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(&self.0)
    }
}

/// The iceoryx2 configuration of a run: the defaults with the run's own file prefix.
///
/// Every process of a run must build its nodes with this config (the transport does), and
/// tools that inspect a run (`Node::list`) must pass it too: other prefixes are invisible.
pub fn run_config(run: &RunId) -> Config {
    let mut config = Config::default();
    // A RunId holds only [A-Za-z0-9_-], which is always a valid file name.
    if let Ok(prefix) = FileName::new(run.prefix().as_bytes()) {
        config.global.prefix = prefix;
    }
    config
}

/// The shared-memory files of a run that exist now in `/dev/shm`.
pub fn run_shm_files(run: &RunId) -> Vec<PathBuf> {
    let prefix = run.prefix();
    let Ok(dir) = std::fs::read_dir(SHM_DIR) else {
        return Vec::new();
    };
    dir.filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
        .map(|e| e.path())
        .collect()
}

/// Removes what a finished run left behind: stale resources of dead nodes, then the run's
/// global management segment, then any file of the run still in `/dev/shm`.
///
/// Call it only when no process of the run is alive any more (the supervisor after the last
/// child was reaped, a test after its children exited): it returns an error and removes
/// nothing if a live node of the run is found. Returns the number of files removed in the
/// last step, which is 0 when every process exited cleanly.
pub fn purge_run(run: &RunId) -> Result<usize, TransportError> {
    let config = run_config(run);
    let report = super::node::cleanup_dead_nodes_in(&config)?;
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
    for file in run_shm_files(run) {
        if std::fs::remove_file(&file).is_ok() {
            tracing::debug!(file = %file.display(), "removed stale shared memory");
            removed += 1;
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
