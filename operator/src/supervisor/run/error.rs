//! What can stop `hnav run` from happening at all.

use std::path::{Path, PathBuf};

use crate::supervisor::child::ChildError;
use crate::supervisor::registry::RegistryError;
use crate::supervisor::run_dir::RunDirError;
use crate::supervisor::startup::StartupError;
use hnav_runtime::consensus_log::LogError;
use hnav_runtime::scenario::ScenarioError;
use hnav_runtime::transport::TransportError;

/// What can stop a run from happening at all.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario is unusable.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The transport failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// A process could not be started.
    #[error(transparent)]
    Child(#[from] ChildError),
    /// The run directory could not be prepared or the summary written.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// The thread that removes dead nodes' resources could not be started.
    #[error("cannot start the dead-node sweeper thread: {0}")]
    Sweeper(std::io::Error),
    /// The options name no run directory.
    #[error("start-up failed: no run directory")]
    NoRunDir,
    /// A process did not come up.
    #[error("start-up failed: {0}")]
    Startup(#[from] StartupError),
    /// The run id is taken by a live run (or the registry is unusable).
    #[error(transparent)]
    Registry(#[from] RegistryError),
    /// The run directory is held by a live run, or holds a finished run's outputs.
    #[error(transparent)]
    RunDir(#[from] RunDirError),
    /// A process stopped because the run directory's disk is full
    /// ([`EXIT_NO_SPACE`](hnav_runtime::launch::EXIT_NO_SPACE)); it is not restarted, the run ends.
    #[error("no space left on device: {node} stopped writing {writes}; the run cannot go on (a restart would meet the same full disk)")]
    NoSpace {
        /// The process's node name (`coordinator`, `agent-3`, ...).
        node: String,
        /// What it writes there.
        writes: String,
    },
    /// A child's exit descriptor could not be duplicated for the watch (out of descriptors,
    /// say).
    #[error("cannot watch the run's processes for their exits: {0}")]
    ExitFd(#[source] std::io::Error),
    /// The consensus log could not be read for the summary.
    #[error(transparent)]
    Log(#[from] LogError),
}

/// Maps an I/O error on `path` to [`RunError::Io`].
pub(super) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + '_ {
    move |source| RunError::Io {
        path: path.to_path_buf(),
        source,
    }
}
