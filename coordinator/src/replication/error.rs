//! Every way a replica can fail: its Raft peer, its journal, its link, or a message.

/// Why a replica could not be made, or could not take a message or a proposal.
#[derive(Debug, thiserror::Error)]
pub enum ReplicaError {
    /// The replica's id is 0 (Raft's "nobody") or not among the voters.
    #[error("replica id {id} is not one of the voters {voters:?} (ids start at 1)")]
    NotAVoter {
        /// The id asked for.
        id: u64,
        /// The cluster's voters.
        voters: Vec<u64>,
    },
    /// A proposal reached a replica that is not the leader: only the leader decides rounds.
    #[error("replica {id} is not the leader (the leader is {leader})")]
    NotLeader {
        /// This replica.
        id: u64,
        /// The leader it knows of, 0 for none.
        leader: u64,
    },
    /// A message from the wire that is no Raft message.
    #[error("a Raft message that does not decode ({0})")]
    Decode(String),
    /// A message that does not encode (protobuf refused it, it is too large for its topic,
    /// or it is addressed to no other voter).
    #[error("a Raft message that does not go out ({0})")]
    Encode(String),
    /// The HNAV transport failed under a `raft/<i>` topic.
    #[error("raft transport: {0}")]
    Transport(#[from] hnav_runtime::transport::TransportError),
    /// The Raft library refused (a bad configuration, a message for another cluster, a
    /// storage error).
    #[error("raft: {0}")]
    Raft(#[from] raft::Error),
    /// The replica's journal (its consensus log) failed: nothing may be acknowledged.
    #[error(transparent)]
    Log(#[from] hnav_runtime::consensus_log::LogError),
    /// The journal in the replica's log directory belongs to another run.
    #[error("the replica log in {dir} was written for another run: {what}")]
    ForeignLog {
        /// The log directory.
        dir: String,
        /// What differs.
        what: String,
    },
}
