//! Every way the coordinator process stops short: its transport, its log, its replication, or
//! a run it cannot serve.

use hnav_runtime::consensus_log::LogError;
use hnav_runtime::msg::MAX_AGENTS;
use hnav_runtime::transport::TransportError;

use crate::replication::ReplicaError;

/// What stopped or broke the coordinator.
#[derive(Debug, thiserror::Error)]
pub enum CoordinatorError {
    /// The transport failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// The consensus log failed: no commit may be published without it.
    #[error(transparent)]
    Log(#[from] LogError),
    /// The log belongs to another scenario or seed.
    #[error("the log in {dir} was written for another run: {what}")]
    ForeignLog {
        /// The log directory.
        dir: String,
        /// What differs.
        what: String,
    },
    /// The swarm is larger than a run may be.
    #[error("{0} agents; a run holds at most {MAX_AGENTS}")]
    TooManyAgents(usize),
    /// The replica's Raft peer, journal or link failed.
    #[error(transparent)]
    Replica(#[from] ReplicaError),
    /// This replica decided as leader of a term it lost: it exits, to be restarted from its
    /// journal as a follower.
    #[error("deposed: led in term {term}, the cluster is in term {now}; restarting from the log")]
    Deposed {
        /// The term it led.
        term: u64,
        /// The term it is in now.
        now: u64,
    },
}
