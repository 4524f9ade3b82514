//! A replica's Raft log on disk: the consensus-log segments of `DIR/log/<id>/`, in the
//! replica format ([`hnav_runtime::consensus_log::replicated`]).
//!
//! Raft reads its log from the library's `MemStorage`; the [`Journal`] is what makes it
//! survive the process. Every entry and hard state Raft hands out in a `Ready` is written
//! here, and the [`Replica`](super::peer::Replica) flushes the journal (one `fdatasync` under the
//! fsync policy `every-record`) before it releases the messages that acknowledge them: a vote
//! or an append is acknowledged only once it is durable. A hard state that only moves the
//! commit index is written with the next flush, not synced on its own: Raft recovers a
//! commit index it lost from the leader.
//!
//! On open the log is read whole, overwritten entries are dropped, and the `MemStorage` a
//! restarted replica runs on is rebuilt from what is left: its snapshot, entries, term, vote
//! and commit index. Raft then hands the committed entries after the snapshot out again, so
//! the coordinator's state is rebuilt from the snapshot's state and then by applying them,
//! exactly as a follower applies the leader's.
//!
//! A replica that compacts ([`Journal::compact`]) writes its log anew: header, snapshot, hard
//! state and the entries after the snapshot, replacing the old segments whole or not at all
//! ([`LogWriter::replace`]).
//!
//! The journal writes on a [`Disk`]: the machine's ([`RealDisk`]) in the coordinator, a
//! simulated one that fails writes and fsyncs and loses power in the simulation
//! ([`sim`](super::sim)).

use std::path::Path;

use hnav_runtime::consensus_log::{
    resolve, AppliedState, LogWriter, RaftEntryRecord, RaftStateRecord, Record, RunHeader,
    SnapshotRecord, WriterOptions, REPLICATED_VERSION,
};
use hnav_runtime::durable::{Disk, RealDisk};
use hnav_runtime::scenario::FsyncPolicy;
use raft::eraftpb::{ConfState, Entry, HardState, Snapshot};

use super::error::ReplicaError;
use super::store::Store;

/// What a journal held when it was opened: Raft's storage, and the state of the snapshot
/// the log starts with (none if it was never compacted).
pub type Opened<D> = (Journal<D>, Store, Option<AppliedState>);

/// A replica's durable Raft log, written on the disk `D`.
pub struct Journal<D: Disk = RealDisk> {
    log: LogWriter<D>,
    /// Records written at the next [`flush`](Journal::flush).
    pending: Vec<Record>,
    /// Whether `pending` holds something Raft needs durable before it speaks (an entry, a
    /// new term or a vote), rather than only a newer commit index.
    must_sync: bool,
    last: HardState,
    /// The log's header, the first record of every rewrite.
    header: RunHeader,
    /// The applied state at the snapshot the log starts with (of nothing, before the first).
    base: AppliedState,
}

impl Journal {
    /// Opens (or creates) the log in `dir` for a replica of `voters`, whose header is
    /// `header` (its version is set to [`REPLICATED_VERSION`]); returns the journal and the
    /// storage Raft runs on, holding what the log held.
    pub fn open(
        dir: &Path,
        header: RunHeader,
        fsync: FsyncPolicy,
        voters: &[u64],
    ) -> Result<Opened<RealDisk>, ReplicaError> {
        Journal::open_on(RealDisk, dir, header, WriterOptions::new(fsync), voters)
    }
}

impl<D: Disk> Journal<D> {
    /// [`Journal::open`] on `disk`, its log written as `options` say.
    pub fn open_on(
        disk: D,
        dir: &Path,
        mut header: RunHeader,
        options: WriterOptions,
        voters: &[u64],
    ) -> Result<Opened<D>, ReplicaError> {
        header.version = REPLICATED_VERSION;
        let (mut log, recovered) = LogWriter::open_on(disk, dir, options)?;
        if recovered.truncated_bytes > 0 {
            tracing::warn!(
                bytes = recovered.truncated_bytes,
                dir = %dir.display(),
                "cut a torn tail off the replica's log"
            );
        }
        match recovered.records.first() {
            None => {
                log.append(&Record::Header(header.clone()))?;
            }
            Some(Record::Header(h)) if *h == header => {}
            Some(other) => {
                let what = match other {
                    Record::Header(_) => "its header differs".to_string(),
                    r => format!("it starts with a {} record", r.kind()),
                };
                return Err(ReplicaError::ForeignLog {
                    dir: dir.display().to_string(),
                    what,
                });
            }
        }
        let resolved = resolve(dir, recovered.records)?;
        let storage = Store::new(voters);
        if let Some(s) = &resolved.snapshot {
            storage.compact_to(raft_snapshot(s), &[], HardState::default())?;
        }
        let entries: Vec<Entry> = resolved.raft.into_iter().map(entry).collect();
        let state = resolved.state;
        let mut hs = HardState::default();
        hs.set_term(state.term);
        hs.set_vote(state.vote);
        // A commit index past the entries this replica holds cannot be its own (a torn tail
        // took them): it learns the rest from the leader.
        hs.set_commit(state.commit.min(resolved.last_index));
        {
            let mut w = storage.mem().wl();
            w.append(&entries)?;
            w.set_hardstate(hs.clone());
        }
        let compacted = resolved.compacted;
        let journal = Journal {
            log,
            pending: Vec::new(),
            must_sync: false,
            last: hs,
            base: compacted
                .clone()
                .unwrap_or_else(|| AppliedState::new(&header)),
            header,
        };
        Ok((journal, storage, compacted))
    }

    /// The applied state of the snapshot the log starts with.
    pub fn base(&self) -> &AppliedState {
        &self.base
    }

    /// Writes the log anew, whole or not at all, as `snapshot` (its state `state`), the hard
    /// state `hs` and the entries after the snapshot (`tail`): the compaction of a replica
    /// that took a snapshot, or the log of one that installed its leader's (no tail). Durable
    /// when it returns; what was queued is in `hs`.
    pub fn compact(
        &mut self,
        snapshot: &Snapshot,
        state: AppliedState,
        hs: &HardState,
        tail: &[Entry],
    ) -> Result<(), ReplicaError> {
        let meta = snapshot.get_metadata();
        let mut records = Vec::with_capacity(tail.len() + 3);
        records.push(Record::Header(self.header.clone()));
        records.push(Record::Snapshot(SnapshotRecord {
            index: meta.index,
            term: meta.term,
            voters: meta.get_conf_state().voters.clone(),
            state: snapshot.data.to_vec(),
        }));
        records.push(Record::RaftState(RaftStateRecord {
            term: hs.term,
            vote: hs.vote,
            commit: hs.commit,
        }));
        records.extend(tail.iter().map(|e| {
            Record::Raft(RaftEntryRecord {
                term: e.term,
                index: e.index,
                data: e.data.to_vec(),
            })
        }));
        self.log.replace(&records)?;
        self.pending.clear();
        self.must_sync = false;
        self.last = hs.clone();
        self.base = state;
        Ok(())
    }

    /// Records in its log on disk now.
    pub fn records(&self) -> u64 {
        self.log.records()
    }

    /// Queues Raft's new entries (the suffix from their first index on replaces what the log
    /// held there).
    pub fn entries(&mut self, entries: &[Entry]) {
        for e in entries {
            self.pending.push(Record::Raft(RaftEntryRecord {
                term: e.term,
                index: e.index,
                data: e.data.to_vec(),
            }));
        }
        self.must_sync |= !entries.is_empty();
    }

    /// Queues a hard state if it differs from the last one.
    pub fn hard_state(&mut self, hs: &HardState) {
        if *hs == self.last {
            return;
        }
        self.must_sync |= hs.term != self.last.term || hs.vote != self.last.vote;
        self.last = hs.clone();
        self.pending.push(Record::RaftState(RaftStateRecord {
            term: hs.term,
            vote: hs.vote,
            commit: hs.commit,
        }));
    }

    /// Queues a newer commit index.
    pub fn commit(&mut self, commit: u64) {
        let mut hs = self.last.clone();
        hs.set_commit(commit);
        self.hard_state(&hs);
    }

    /// Writes what is queued if Raft needs it durable (then synced as the fsync policy
    /// asks); a queue of commit indices alone waits for the next one.
    pub fn flush(&mut self) -> Result<(), ReplicaError> {
        if self.must_sync {
            self.write()?;
        }
        Ok(())
    }

    /// Writes everything queued and makes the whole log durable now (the end of a run).
    pub fn sync(&mut self) -> Result<(), ReplicaError> {
        self.write()?;
        self.log.sync()?;
        Ok(())
    }

    fn write(&mut self) -> Result<(), ReplicaError> {
        self.log.append_all(&self.pending)?;
        self.pending.clear();
        self.must_sync = false;
        Ok(())
    }
}

/// A stored snapshot as Raft's.
pub fn raft_snapshot(s: &SnapshotRecord) -> Snapshot {
    let mut snap = Snapshot {
        data: s.state.clone().into(),
        ..Snapshot::default()
    };
    let meta = snap.mut_metadata();
    meta.index = s.index;
    meta.term = s.term;
    meta.set_conf_state(ConfState::from((s.voters.clone(), Vec::new())));
    snap
}

/// A stored entry as Raft's.
fn entry(r: RaftEntryRecord) -> Entry {
    Entry {
        term: r.term,
        index: r.index,
        data: r.data.into(),
        ..Entry::default()
    }
}
