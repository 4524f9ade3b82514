//! A replica's snapshots: the one it takes every `snapshot_entries` committed entries, its
//! journal compacted behind it, and the one its leader sends when it is too far behind.

use raft::eraftpb::{EntryType, Snapshot};
use raft::{GetEntriesContext, Storage};

use hnav_runtime::consensus_log::{decode_record, AppliedState};
use hnav_runtime::durable::Disk;

use super::super::error::ReplicaError;
use super::super::store::Store;
use super::Replica;

impl<D: Disk> Replica<D> {
    /// Installs the snapshot a leader sent (this replica lacked the entries it stands for):
    /// durable in the journal first, then Raft's storage; the committed entries not yet taken
    /// are superseded by its state.
    pub(super) fn install(
        &mut self,
        store: &Store,
        snapshot: Snapshot,
    ) -> Result<(), ReplicaError> {
        let state = decode_state(&snapshot)?;
        let mut hs = store.mem().rl().hard_state().clone();
        let meta = snapshot.get_metadata();
        let index = meta.index;
        hs.term = hs.term.max(meta.term);
        hs.commit = hs.commit.max(meta.index);
        if let Some(j) = &mut self.journal {
            j.compact(&snapshot, state.clone(), &hs, &[])?;
        }
        tracing::info!(
            index = meta.index,
            term = meta.term,
            "installed the leader's snapshot"
        );
        store.compact_to(snapshot, &[], hs)?;
        self.committed.clear();
        self.installed = Some((index, state));
        self.installs += 1;
        Ok(())
    }

    /// Takes a snapshot at the applied index and compacts the journal behind it, once
    /// `snapshot_entries` entries were applied since the last one (a durable replica only:
    /// one in memory has no journal to bound).
    pub(super) fn compact_if_due(&mut self) -> Result<(), ReplicaError> {
        let Some(j) = &mut self.journal else {
            return Ok(());
        };
        let store = self.node.store().clone();
        let base = store.snapshot_index();
        let applied = self.node.raft.raft_log.applied;
        if self.snapshot_entries == 0 || applied < base + self.snapshot_entries {
            return Ok(());
        }
        let started = std::time::Instant::now();
        let ctx = || GetEntriesContext::empty(false);
        let mut state = j.base().clone();
        for e in store.entries(base + 1, applied + 1, None, ctx())? {
            if e.get_entry_type() == EntryType::EntryNormal && !e.data.is_empty() {
                let record = decode_record(&e.data).map_err(|p| {
                    ReplicaError::Decode(format!("committed entry {}: {p}", e.index))
                })?;
                state.fold(&record);
            }
        }
        let last = store.last_index()?;
        let tail = store.entries(applied + 1, last + 1, None, ctx())?;
        let mut snapshot = Snapshot {
            data: state.encode().into(),
            ..Snapshot::default()
        };
        let meta = snapshot.mut_metadata();
        meta.index = applied;
        meta.term = store.term(applied)?;
        meta.set_conf_state(store.initial_state()?.conf_state);
        let hs = store.mem().rl().hard_state().clone();
        let (records, bytes) = (state.records, snapshot.data.len());
        j.compact(&snapshot, state, &hs, &tail)?;
        store.compact_to(snapshot, &tail, hs)?;
        tracing::info!(
            index = applied,
            records,
            state_bytes = bytes,
            ms = started.elapsed().as_secs_f64() * 1e3,
            "took a snapshot and compacted the journal behind it"
        );
        Ok(())
    }
}

/// The applied state a snapshot holds.
pub(super) fn decode_state(snapshot: &Snapshot) -> Result<AppliedState, ReplicaError> {
    AppliedState::decode(&snapshot.data).map_err(|p| {
        let index = snapshot.get_metadata().index;
        ReplicaError::Decode(format!("snapshot at index {index}: {p}"))
    })
}
