//! Where the coordinator's decisions become final ([`DecisionLog`]): its own consensus log (a
//! single coordinator), or the Raft cluster of its replicas (`coordinator.replicas` 3 or 5).
//!
//! A single coordinator appends a record and it is final once the append returns (durable by
//! the fsync policy). A replica that leads proposes the record instead; it is final once a
//! majority of the replicas holds it durably ([`RaftLog::settled`]), and only then may its
//! Commit leave. A replica that follows applies the leader's committed records
//! ([`RaftLog::take_applied`]) to its own state, so that it is ready to lead.

use std::rc::Rc;
use std::time::Instant;

use hnav_runtime::consensus_log::{LogWriter, Record};

use super::error::CoordinatorError;
use crate::replication::{RaftLink, RaftLog};

/// The log the coordinator's decisions are final in.
pub(super) enum DecisionLog {
    /// A single coordinator's consensus log.
    Single(LogWriter),
    /// A replica's Raft log.
    Replicated(Box<RaftLog>),
}

impl DecisionLog {
    /// Makes `record` final (single) or proposes it (the leading replica).
    pub(super) fn append(&mut self, record: &Record) -> Result<(), CoordinatorError> {
        match self {
            DecisionLog::Single(log) => {
                log.append(record)?;
            }
            DecisionLog::Replicated(raft) => raft.propose(record)?,
        }
        Ok(())
    }

    /// Makes everything appended durable now.
    pub(super) fn sync(&mut self) -> Result<(), CoordinatorError> {
        match self {
            DecisionLog::Single(log) => log.sync()?,
            DecisionLog::Replicated(raft) => raft.sync()?,
        }
        Ok(())
    }

    /// A replica's Raft log, none for a single coordinator.
    pub(super) fn raft(&mut self) -> Option<&mut RaftLog> {
        match self {
            DecisionLog::Replicated(r) => Some(r),
            DecisionLog::Single(_) => None,
        }
    }

    fn raft_ref(&self) -> Option<&RaftLog> {
        match self {
            DecisionLog::Replicated(r) => Some(r),
            DecisionLog::Single(_) => None,
        }
    }

    /// The Raft term of this replica, 0 for a single coordinator: what its commits carry.
    pub(super) fn term(&self) -> u32 {
        self.raft_ref()
            .map_or(0, |r| u32::try_from(r.term()).unwrap_or(u32::MAX))
    }

    /// This replica's id, 0 for a single coordinator: what its progress names as leader.
    pub(super) fn replica_id(&self) -> u64 {
        self.raft_ref().map_or(0, RaftLog::id)
    }

    /// A replica's Raft link, whose `raft/<id>` inbox wakes its loop (none for a single
    /// coordinator).
    pub(super) fn link(&self) -> Option<Rc<RaftLink>> {
        self.raft_ref().map(RaftLog::link)
    }

    /// The latest a replica may wait: its next Raft tick (none for a single coordinator).
    pub(super) fn deadline(&self) -> Option<Instant> {
        self.raft_ref().map(RaftLog::deadline)
    }

    /// Role and term, for the replica's log lines.
    pub(super) fn role(&self) -> Option<(&'static str, u64)> {
        self.raft_ref().map(|r| (r.role().name(), r.term()))
    }
}
