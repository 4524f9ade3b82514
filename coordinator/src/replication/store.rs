//! Raft's storage of a replica ([`Store`]): the library's `MemStorage`, and the snapshot the
//! replica compacted its log behind.
//!
//! `MemStorage` keeps a snapshot's index and term but not its data: what it would send a
//! replica too far behind is an empty snapshot. The [`Store`] answers Raft's request for a
//! snapshot with the one the replica took or installed last, its data the encoded
//! [`AppliedState`](hnav_runtime::consensus_log::AppliedState); everything else is
//! `MemStorage`'s.

use std::cell::RefCell;
use std::rc::Rc;

use raft::eraftpb::{ConfState, Entry, HardState, Snapshot};
use raft::storage::{MemStorage, RaftState, Storage};
use raft::{GetEntriesContext, StorageError};

/// A replica's Raft log in memory, and its last snapshot; clones share both (a restart over
/// the same storage).
#[derive(Clone)]
pub struct Store {
    mem: MemStorage,
    snapshot: Rc<RefCell<Snapshot>>,
}

impl Store {
    /// An empty log of a cluster of `voters`.
    pub fn new(voters: &[u64]) -> Self {
        Store {
            mem: MemStorage::new_with_conf_state(ConfState::from((voters.to_vec(), Vec::new()))),
            snapshot: Rc::default(),
        }
    }

    /// The entries, hard state and compaction, as the library keeps them.
    pub fn mem(&self) -> &MemStorage {
        &self.mem
    }

    /// Its last snapshot's index (0 before the first).
    pub fn snapshot_index(&self) -> u64 {
        self.snapshot.borrow().get_metadata().index
    }

    /// Its last snapshot (empty before the first).
    pub fn last_snapshot(&self) -> Snapshot {
        self.snapshot.borrow().clone()
    }

    /// Replaces everything up to `snapshot`'s index with it, keeping the entries after it
    /// (`tail`) and the hard state `hs` (its commit index at least the snapshot's).
    pub fn compact_to(
        &self,
        snapshot: Snapshot,
        tail: &[Entry],
        hs: HardState,
    ) -> Result<(), raft::Error> {
        {
            let mut w = self.mem.wl();
            w.apply_snapshot(snapshot.clone())?;
            w.append(tail)?;
            w.set_hardstate(hs);
        }
        *self.snapshot.borrow_mut() = snapshot;
        Ok(())
    }
}

impl Storage for Store {
    fn initial_state(&self) -> raft::Result<RaftState> {
        self.mem.initial_state()
    }

    fn entries(
        &self,
        low: u64,
        high: u64,
        max_size: impl Into<Option<u64>>,
        context: GetEntriesContext,
    ) -> raft::Result<Vec<Entry>> {
        self.mem.entries(low, high, max_size, context)
    }

    fn term(&self, idx: u64) -> raft::Result<u64> {
        self.mem.term(idx)
    }

    fn first_index(&self) -> raft::Result<u64> {
        self.mem.first_index()
    }

    fn last_index(&self) -> raft::Result<u64> {
        self.mem.last_index()
    }

    fn snapshot(&self, _request_index: u64, _to: u64) -> raft::Result<Snapshot> {
        let snapshot = self.snapshot.borrow();
        if snapshot.get_metadata().index == 0 {
            // Nothing compacted: Raft asks only when it lacks entries, which cannot be then.
            return Err(raft::Error::Store(
                StorageError::SnapshotTemporarilyUnavailable,
            ));
        }
        Ok(snapshot.clone())
    }
}
