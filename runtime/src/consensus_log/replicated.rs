//! A replica's log (format version [`REPLICATED_VERSION`]): the Raft log of one coordinator
//! replica, stored in the same segments, frames and writer as a single coordinator's log.
//!
//! After its [`Header`](Record::Header) a replica's log holds only two kinds of records:
//! [`Record::Raft`], one Raft entry with its term and index (its data is a decided record in
//! the payload encoding, or empty for a new leader's empty entry), and [`Record::RaftState`],
//! the replica's hard state (term, vote, commit index) from there on. The log is append-only:
//! when Raft overwrites an uncommitted suffix (a follower that had entries of a deposed
//! leader), the new entry is appended with the old index, and reading takes the last entry
//! written for each index, dropping everything after an overwritten one.
//!
//! [`resolve`] turns the stored records into the decided ones: the header, then the records
//! of every entry up to the last stored commit index, in index order. That is the sequence a
//! single coordinator logs for the same decisions, so the summary, `hnav log show`, `replay`
//! and the exports read a replica's log as they read a single log ([`read_decided`]). A run
//! with replicas keeps one log per replica in `DIR/log/<id>/`; [`read_decided`] given
//! `DIR/log` takes the replica that has decided the most.

use std::path::{Path, PathBuf};

use super::error::LogError;
use super::frame::decode_record;
use super::reader::read_log;
use super::record::{RaftEntryRecord, RaftStateRecord, Record, SnapshotRecord};
use super::segment::list_segments;
use super::snapshot::AppliedState;
use super::REPLICATED_VERSION;

/// A replica's log, read and resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct Resolved {
    /// The header, then the decided records in Raft order (entries up to `state.commit`).
    pub records: Vec<Record>,
    /// For each of `records` after the header: the (term, index) of the entry it came from.
    pub entries: Vec<(u64, u64)>,
    /// The last hard state stored (zeros if none was).
    pub state: RaftStateRecord,
    /// The last entry's index, committed or not.
    pub last_index: u64,
    /// The log's current Raft entries (overwritten ones dropped, and those the snapshot
    /// stands for), for a restarted replica's storage.
    pub raft: Vec<RaftEntryRecord>,
    /// The log's snapshot, if it was compacted: it stands for every entry up to its index.
    pub snapshot: Option<SnapshotRecord>,
    /// The snapshot's state, decoded: what `records` come after.
    pub compacted: Option<AppliedState>,
}

impl Resolved {
    /// Entries stored after the commit index: the replica holds them, but did not know them
    /// committed when it last stored its state.
    pub fn uncommitted(&self) -> u64 {
        self.last_index.saturating_sub(self.state.commit)
    }
}

/// Whether `records` (a log read whole) are a replica's log: its header says
/// [`REPLICATED_VERSION`].
pub fn is_replicated(records: &[Record]) -> bool {
    matches!(records.first(), Some(Record::Header(h)) if h.version == REPLICATED_VERSION)
}

/// Resolves a replica's log read from `dir`: the current entries (the last written for each
/// index), the last hard state, and the decided records. A log that is not a replica's comes
/// back as it is, with no entries.
pub fn resolve(dir: &Path, records: Vec<Record>) -> Result<Resolved, LogError> {
    if !is_replicated(&records) {
        return Ok(Resolved {
            records,
            entries: Vec::new(),
            state: RaftStateRecord::default(),
            last_index: 0,
            raft: Vec::new(),
            snapshot: None,
            compacted: None,
        });
    }
    let bad = |index: u64, what: String| LogError::Raft {
        dir: dir.to_path_buf(),
        index,
        what,
    };
    let mut raft: Vec<RaftEntryRecord> = Vec::new();
    let mut state = RaftStateRecord::default();
    let mut snapshot: Option<(SnapshotRecord, AppliedState)> = None;
    let mut it = records.into_iter();
    let header = it.next().expect("is_replicated saw a header");
    for r in it {
        let base = snapshot.as_ref().map_or((0, 0), |(s, _)| (s.index, s.term));
        match r {
            Record::Raft(e) => {
                let next = raft.last().map_or(base.0 + 1, |l| l.index + 1);
                if e.index <= base.0 {
                    let what = format!("at or before the snapshot at {}", base.0);
                    return Err(bad(e.index, what));
                }
                if e.index > next {
                    return Err(bad(e.index, format!("skips indices (expected {next})")));
                }
                // An entry at an index already written replaces it and all after it.
                raft.truncate((e.index - base.0 - 1) as usize);
                let prev = raft.last().map_or(base, |p| (p.index, p.term));
                if prev.1 > e.term {
                    let what = format!("term {} after term {} at {}", e.term, prev.1, prev.0);
                    return Err(bad(e.index, what));
                }
                raft.push(e);
            }
            Record::RaftState(s) => state = s,
            Record::Snapshot(s) => {
                if s.index < base.0 || (s.index == base.0 && s.term < base.1) {
                    let what = format!("snapshot after the snapshot at {}", base.0);
                    return Err(bad(s.index, what));
                }
                let applied = s.applied().map_err(|p| bad(s.index, p.to_string()))?;
                // It stands for every entry up to its index; later ones stay (a compacted
                // log rewrites them after it).
                let keep = raft.iter().position(|e| e.index > s.index);
                raft.drain(..keep.unwrap_or(raft.len()));
                snapshot = Some((s, applied));
            }
            other => {
                let what = format!("a {} record outside a Raft entry", other.kind());
                return Err(bad(raft.last().map_or(0, |l| l.index), what));
            }
        }
    }
    if let Some((s, _)) = snapshot.as_ref().filter(|(s, _)| state.commit < s.index) {
        let what = format!("commit index {} below the snapshot", state.commit);
        return Err(bad(s.index, what));
    }
    let mut decided = vec![header];
    let mut entries = Vec::new();
    for e in raft
        .iter()
        .filter(|e| e.index <= state.commit && !e.data.is_empty())
    {
        let record = decode_record(&e.data).map_err(|p| bad(e.index, p.to_string()))?;
        if matches!(
            record,
            Record::Header(_) | Record::Raft(_) | Record::RaftState(_) | Record::Snapshot(_)
        ) {
            let what = format!("holds a {} record, not a decision", record.kind());
            return Err(bad(e.index, what));
        }
        decided.push(record);
        entries.push((e.term, e.index));
    }
    let last_index = raft
        .last()
        .map_or(snapshot.as_ref().map_or(0, |(s, _)| s.index), |l| l.index);
    let (snapshot, compacted) = snapshot.map_or((None, None), |(s, a)| (Some(s), Some(a)));
    Ok(Resolved {
        records: decided,
        entries,
        state,
        last_index,
        raft,
        snapshot,
        compacted,
    })
}

/// The decided records of a run's log, wherever they are.
#[derive(Clone, Debug, PartialEq)]
pub struct Decided {
    /// The header, then the decided records, as a single coordinator logs them.
    pub records: Vec<Record>,
    /// The log they were read from (`DIR/log`, or `DIR/log/<id>` of a replica).
    pub dir: PathBuf,
    /// The replica's id, for a run with replicas.
    pub replica: Option<u64>,
    /// What the records a compacted log no longer holds add up to (its snapshot's state):
    /// `records` are those after it.
    pub compacted: Option<AppliedState>,
}

impl Decided {
    /// Decided records in all, those the snapshot stands for included (the header not
    /// counted).
    pub fn decided(&self) -> u64 {
        let before = self.compacted.as_ref().map_or(0, |c| c.records);
        before + self.records.len().saturating_sub(1) as u64
    }

    /// The last round decided, whether its record is here or compacted.
    pub fn last_round(&self) -> u64 {
        let here = self.records.iter().filter_map(Record::round).max();
        let before = self.compacted.as_ref().map_or(0, |c| c.round);
        here.unwrap_or(0).max(before)
    }
}

/// The replicas' log directories under `dir` (`DIR/log/<id>/`), by id; empty for a single
/// coordinator's log.
pub fn replica_dirs(dir: &Path) -> Result<Vec<(u64, PathBuf)>, LogError> {
    let entries = std::fs::read_dir(dir).map_err(|e| LogError::io(dir, e))?;
    let mut out = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| LogError::io(dir, e))?;
        let name = entry.file_name();
        let id = name.to_str().and_then(|n| n.parse::<u64>().ok());
        if let Some(id) = id.filter(|_| entry.path().is_dir()) {
            out.push((id, entry.path()));
        }
    }
    out.sort();
    Ok(out)
}

/// Reads the decided records of the log in `dir`: a single coordinator's log as it is, a
/// replica's log resolved; and for a directory of replica logs (`DIR/log` of a run with
/// replicas) the replica that decided the most (the lowest id among equals).
pub fn read_decided(dir: impl AsRef<Path>) -> Result<Decided, LogError> {
    let dir = dir.as_ref();
    let replicas = if list_segments(dir)?.is_empty() {
        replica_dirs(dir)?
    } else {
        Vec::new()
    };
    if replicas.is_empty() {
        return read_one(dir, None);
    }
    let mut best: Option<Decided> = None;
    for (id, sub) in replicas {
        let d = read_one(&sub, Some(id))?;
        if best.as_ref().is_none_or(|b| d.decided() > b.decided()) {
            best = Some(d);
        }
    }
    Ok(best.expect("at least one replica"))
}

fn read_one(dir: &Path, replica: Option<u64>) -> Result<Decided, LogError> {
    let resolved = resolve(dir, read_log(dir)?.records)?;
    Ok(Decided {
        records: resolved.records,
        dir: dir.to_path_buf(),
        replica,
        compacted: resolved.compacted,
    })
}

/// The file in a replica's log directory saying its Raft role and term, as it last saw them
/// (`hnav ps` shows it; the log's readers ignore it).
pub const ROLE_FILE: &str = "raft-role.json";

/// A replica's Raft role and term ([`ROLE_FILE`]).
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ReplicaRole {
    /// `leader`, `follower`, `candidate` or `pre-candidate`.
    pub role: String,
    /// Its term.
    pub term: u64,
}

impl ReplicaRole {
    /// Replaces the role file in the replica's log directory `dir`, whole or not at all.
    pub fn write(&self, dir: &Path) -> std::io::Result<()> {
        let text = serde_json::to_string(self).map_err(std::io::Error::other)?;
        crate::durable::replace_file(&dir.join(ROLE_FILE), text.as_bytes())
    }

    /// The role file of the replica's log directory `dir`, if there is a readable one.
    pub fn read(dir: &Path) -> Option<ReplicaRole> {
        let text = std::fs::read_to_string(dir.join(ROLE_FILE)).ok()?;
        serde_json::from_str(&text).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::consensus_log::frame::encode_record;
    use crate::consensus_log::{EndReason, EndRecord, RunHeader};

    fn header() -> Record {
        Record::Header(RunHeader::tiny(REPLICATED_VERSION))
    }

    fn end(round: u64) -> Record {
        Record::End(EndRecord {
            round,
            at_goal: 0,
            reason: EndReason::Stopped,
        })
    }

    fn entry(term: u64, index: u64, record: Option<&Record>) -> Record {
        let mut data = Vec::new();
        if let Some(r) = record {
            encode_record(r, &mut data).unwrap();
        }
        Record::Raft(RaftEntryRecord { term, index, data })
    }

    fn state(term: u64, commit: u64) -> Record {
        Record::RaftState(RaftStateRecord {
            term,
            vote: 1,
            commit,
        })
    }

    #[test]
    fn decided_records_are_the_committed_entries_with_data_in_index_order() {
        let log = vec![
            header(),
            state(1, 0),
            entry(1, 1, None),
            entry(1, 2, Some(&end(1))),
            entry(1, 3, Some(&end(2))),
            state(1, 2),
        ];
        let r = resolve(Path::new("d"), log).unwrap();
        assert_eq!(r.records, vec![header(), end(1)]);
        assert_eq!(r.entries, vec![(1, 2)]);
        assert_eq!((r.last_index, r.uncommitted()), (3, 1));
    }

    #[test]
    fn a_rewritten_index_replaces_the_suffix_of_a_deposed_leader() {
        let log = vec![
            header(),
            entry(1, 1, Some(&end(1))),
            entry(1, 2, Some(&end(2))),
            entry(1, 3, Some(&end(3))),
            entry(2, 2, Some(&end(9))),
            state(2, 2),
        ];
        let r = resolve(Path::new("d"), log).unwrap();
        assert_eq!(r.records, vec![header(), end(1), end(9)]);
        assert_eq!(r.last_index, 2);
    }

    #[test]
    fn gaps_falling_terms_and_loose_records_are_errors_naming_the_entry() {
        let cases = [
            (
                vec![entry(1, 2, None)],
                "Raft entry 2: skips indices (expected 1)",
            ),
            (
                vec![entry(1, 1, None), entry(1, 3, None)],
                "Raft entry 3: skips indices (expected 2)",
            ),
            (
                vec![entry(2, 1, None), entry(1, 2, None)],
                "Raft entry 2: term 1 after term 2 at 1",
            ),
            (
                vec![entry(1, 1, None), end(1)],
                "Raft entry 1: a end record",
            ),
            (
                vec![entry(1, 1, Some(&header())), state(1, 1)],
                "Raft entry 1: holds a header record",
            ),
        ];
        for (mut tail, want) in cases {
            let mut log = vec![header()];
            log.append(&mut tail);
            let e = resolve(Path::new("d"), log).unwrap_err().to_string();
            assert!(e.starts_with(&format!("d: {want}")), "{e}");
        }
    }

    fn snapshot(index: u64, term: u64, state: Vec<u8>) -> Record {
        Record::Snapshot(SnapshotRecord {
            index,
            term,
            voters: vec![1, 2, 3],
            state,
        })
    }

    fn state_after(records: &[Record]) -> Vec<u8> {
        let Record::Header(h) = header() else {
            unreachable!()
        };
        let mut s = AppliedState::new(&h);
        records.iter().for_each(|r| s.fold(r));
        s.encode()
    }

    #[test]
    fn a_snapshot_stands_for_the_entries_up_to_its_index() {
        let log = vec![
            header(),
            snapshot(4, 2, state_after(&[end(1), end(2)])),
            state(2, 4),
            entry(2, 5, Some(&end(3))),
            entry(3, 6, Some(&end(4))),
            state(3, 5),
        ];
        let r = resolve(Path::new("d"), log).unwrap();
        assert_eq!(r.records, vec![header(), end(3)]);
        assert_eq!(r.entries, vec![(2, 5)]);
        assert_eq!(r.last_index, 6);
        let c = r.compacted.unwrap();
        assert_eq!((c.records, c.end.map(|e| e.round)), (2, Some(2)));
        assert_eq!(r.snapshot.map(|s| s.index), Some(4));
    }

    #[test]
    fn entries_against_the_snapshot_and_a_damaged_state_are_errors_naming_the_index() {
        let good = || state_after(&[end(1)]);
        let cases = [
            (
                vec![snapshot(4, 2, good()), state(2, 4), entry(2, 4, None)],
                "Raft entry 4: at or before the snapshot at 4",
            ),
            (
                vec![snapshot(4, 2, good()), state(2, 4), entry(2, 6, None)],
                "Raft entry 6: skips indices (expected 5)",
            ),
            (
                vec![snapshot(4, 2, good()), state(2, 4), entry(1, 5, None)],
                "Raft entry 5: term 1 after term 2 at 4",
            ),
            (
                vec![snapshot(4, 2, good()), state(2, 3)],
                "Raft entry 4: commit index 3 below the snapshot",
            ),
            (
                vec![snapshot(4, 2, vec![0xff; 3]), state(2, 4)],
                "Raft entry 4: undecodable record: snapshot state",
            ),
        ];
        for (mut tail, want) in cases {
            let mut log = vec![header()];
            log.append(&mut tail);
            let e = resolve(Path::new("d"), log).unwrap_err().to_string();
            assert!(e.starts_with(&format!("d: {want}")), "{e}");
        }
    }
}
