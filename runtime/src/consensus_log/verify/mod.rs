//! [`verify`]: read a whole log and report whether it is intact. Never modifies a file.
//!
//! A log is intact when
//! - it has no corruption and no torn tail, and every segment but the last ends on a record
//!   boundary (the reader's rules);
//! - its first record is a header (of this build's [`FORMAT_VERSION`](super::FORMAT_VERSION))
//!   and no other record is one;
//! - its round records count up from round 1 without a gap, and every other record belongs to
//!   the round the coordinator writes it at (`order`), so a lost round record is named;
//! - no segment but the last lost complete records at its end (`segments`);
//! - it has at most one end record, nothing follows it, and it closes at the last round;
//! - every agent index in it is below the header's agent count and every verdict is known.
//!
//! A replica's log (version [`REPLICATED_VERSION`](super::REPLICATED_VERSION)) must also make
//! a Raft log ([`resolve`]: no skipped index, no falling term, nothing but
//! entries and hard states after the header), and the rules above apply to its decided
//! records (the committed entries), each placed at the entry it came from. A compacted
//! replica's log starts with a snapshot (after the header): its state must decode, the entries
//! after it go on from its index and term, the commit index is not below it, and the rules
//! above go on from its last round.
//!
//! A log without an end record is intact but *not closed* ([`VerifyReport::is_closed`]): the
//! run was cut short (a crash of the whole run, a kill of the supervisor) or is still going.
//! That is a different finding from a damaged log, so it does not change the status.

mod order;
mod segments;

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::error::LogError;
use super::reader::{LogReader, RecordPos, TornTail};
use super::record::{EndRecord, RaftStateRecord, Record};
use super::replicated::{is_replicated, resolve};
use super::segment::segment_name;
use order::OrderCheck;
use segments::SegmentCheck;

/// Records of each kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KindCounts {
    /// Header records.
    pub header: u64,
    /// Round records.
    pub round: u64,
    /// Lifecycle records.
    pub lifecycle: u64,
    /// Replan records.
    pub replan: u64,
    /// End records.
    pub end: u64,
    /// Unreachable records.
    pub unreachable: u64,
    /// Task records (a lifelong run's assignments).
    pub task: u64,
    /// Map-change records (cells the agents saw close or open).
    pub map_change: u64,
}

impl KindCounts {
    /// All records.
    pub fn total(&self) -> u64 {
        self.header
            + self.round
            + self.lifecycle
            + self.replan
            + self.end
            + self.unreachable
            + self.task
            + self.map_change
    }
}

/// What a replica's log holds besides its decided records.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RaftSummary {
    /// Raft entry records written (overwritten ones included).
    pub written: u64,
    /// The last entry's index.
    pub last_index: u64,
    /// The last hard state written.
    pub state: RaftStateRecord,
    /// The snapshot's index and term, for a compacted log.
    pub snapshot: Option<(u64, u64)>,
}

/// The verdict of [`verify`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VerifyStatus {
    /// Intact (see the [module docs](self)).
    Intact,
    /// Readable, but torn, corrupt or out of order.
    NotIntact,
    /// The directory or a segment could not be read at all, or holds no segments.
    Unreadable,
}

/// What [`verify`] found.
#[derive(Debug)]
pub struct VerifyReport {
    /// The log directory.
    pub dir: PathBuf,
    /// Segment files.
    pub segments: usize,
    /// Bytes of all complete records, segment magics included.
    pub bytes: u64,
    /// Complete records read (up to the first error), by kind.
    pub counts: KindCounts,
    /// Round of the first round record.
    pub first_round: Option<u64>,
    /// Round of the last round record.
    pub last_round: Option<u64>,
    /// The (first) end record, if the log has one.
    pub end: Option<EndRecord>,
    /// For a replica's log: its Raft entries and last hard state.
    pub raft: Option<RaftSummary>,
    /// Decided records a compacted replica's log no longer holds, its snapshot stands for
    /// them (0 for any other log).
    pub compacted: u64,
    /// The torn tail, if any.
    pub torn: Option<TornTail>,
    /// The error that stopped reading (corruption, header, version, gap, I/O), if any.
    pub error: Option<LogError>,
    /// Everything that makes the log not intact, one line each.
    pub problems: Vec<String>,
}

impl VerifyReport {
    /// Whether the log is intact.
    pub fn is_intact(&self) -> bool {
        self.problems.is_empty()
    }

    /// Intact, not intact, or unreadable.
    pub fn status(&self) -> VerifyStatus {
        match &self.error {
            Some(e) if e.is_unreadable() => VerifyStatus::Unreadable,
            _ if self.is_intact() => VerifyStatus::Intact,
            _ => VerifyStatus::NotIntact,
        }
    }

    /// Whether the log has an end record.
    pub fn has_end(&self) -> bool {
        self.end.is_some()
    }

    /// Whether the run's log was closed by an end record (an intact log without one belongs
    /// to a run that was cut short or is still going).
    pub fn is_closed(&self) -> bool {
        self.has_end()
    }

    /// A short multi-line report.
    pub fn render(&self) -> String {
        let mut s = String::new();
        let c = &self.counts;
        let _ = writeln!(s, "log        {}", self.dir.display());
        let _ = writeln!(s, "segments   {} ({} bytes)", self.segments, self.bytes);
        let _ = writeln!(
            s,
            "records    {}: {} header, {} round, {} lifecycle, {} replan, {} end",
            c.total(),
            c.header,
            c.round,
            c.lifecycle,
            c.replan,
            c.end
        );
        if c.unreachable > 0 {
            s.pop();
            let _ = writeln!(s, ", {} unreachable", c.unreachable);
        }
        if c.task > 0 {
            s.pop();
            let _ = writeln!(s, ", {} task", c.task);
        }
        if c.map_change > 0 {
            s.pop();
            let _ = writeln!(s, ", {} map-change", c.map_change);
        }
        if let Some((index, term)) = self.raft.and_then(|r| r.snapshot) {
            let _ = writeln!(
                s,
                "snapshot   index {index}, term {term}: {} decided records compacted",
                self.compacted
            );
        }
        if let Some(r) = &self.raft {
            let st = &r.state;
            let _ = writeln!(
                s,
                "raft       {} entries written, last index {}, commit {}, term {}, vote {}",
                r.written, r.last_index, st.commit, st.term, st.vote
            );
        }
        match (self.first_round, self.last_round) {
            (Some(a), Some(b)) => _ = writeln!(s, "rounds     {a}..{b}"),
            _ => _ = writeln!(s, "rounds     none"),
        }
        match &self.end {
            Some(e) => {
                let reason = e.reason.name();
                _ = writeln!(
                    s,
                    "end        round {} {reason}, {} at goal",
                    e.round, e.at_goal
                )
            }
            None if self.status() == VerifyStatus::Unreadable => _ = writeln!(s, "end        none"),
            None => {
                _ = writeln!(
                    s,
                    "end        none: not closed (the run was cut short or is still going)"
                )
            }
        }
        match &self.torn {
            Some(t) => _ = writeln!(s, "torn tail  {} bytes at {}", t.bytes, torn_place(t)),
            None => _ = writeln!(s, "torn tail  none"),
        }
        let status = match self.status() {
            VerifyStatus::Intact if !self.is_closed() => "intact, not closed",
            VerifyStatus::Intact => "intact",
            VerifyStatus::NotIntact => "NOT INTACT",
            VerifyStatus::Unreadable => "UNREADABLE",
        };
        let _ = writeln!(s, "status     {status}");
        for p in &self.problems {
            let _ = writeln!(s, "  problem: {p}");
        }
        s
    }
}

fn torn_place(t: &TornTail) -> String {
    format!(
        "{} byte {} ({})",
        segment_name(t.segment),
        t.offset,
        t.problem
    )
}

/// Reads the log in `dir` and reports what it holds and whether it is intact.
pub fn verify(dir: impl AsRef<Path>) -> VerifyReport {
    let dir = dir.as_ref();
    let mut report = VerifyReport {
        dir: dir.to_path_buf(),
        segments: 0,
        bytes: 0,
        counts: KindCounts::default(),
        first_round: None,
        last_round: None,
        end: None,
        raft: None,
        compacted: 0,
        torn: None,
        error: None,
        problems: Vec::new(),
    };
    let mut reader = match LogReader::open(dir) {
        Ok(r) => r,
        Err(e) => {
            report.problems.push(e.to_string());
            report.error = Some(e);
            return report;
        }
    };
    report.segments = reader.segments().len();
    let mut order = OrderCheck::default();
    let mut spans = SegmentCheck::default();
    let mut last_segment = None;
    // A replica's log is checked once resolved: its stored records, and where each entry
    // is (the last written at each index, as resolving takes it).
    let mut replica: Option<(Vec<Record>, HashMap<u64, RecordPos>)> = None;
    loop {
        match reader.next_record() {
            Ok(Some((pos, record))) => {
                if last_segment != Some(pos.segment) {
                    report.bytes += pos.offset;
                    last_segment = Some(pos.segment);
                }
                report.bytes += pos.len;
                spans.record(pos);
                if replica.is_none() && is_replicated(std::slice::from_ref(&record)) {
                    replica = Some((Vec::new(), HashMap::new()));
                }
                match &mut replica {
                    Some((records, at)) if !matches!(record, Record::Header(_)) => {
                        if let Record::Raft(e) = &record {
                            at.insert(e.index, pos);
                        }
                        records.push(record);
                    }
                    Some((records, _)) => {
                        order.check(&mut report, pos, &record);
                        records.push(record);
                    }
                    None => order.check(&mut report, pos, &record),
                }
            }
            Ok(None) => break,
            Err(e) => {
                report.problems.push(e.to_string());
                report.error = Some(e);
                break;
            }
        }
    }
    if let Some((records, at)) = replica {
        check_replica(dir, records, &at, &mut order, &mut report);
    }
    if let Some(t) = reader.torn_tail() {
        report
            .problems
            .push(format!("torn tail: {} bytes at {}", t.bytes, torn_place(t)));
        report.torn = Some(t.clone());
    }
    if report.error.is_none() {
        if report.counts.header == 0 {
            report.problems.push("no complete header record".into());
        }
        let segments = report.segments;
        spans.finish(&mut report, segments);
    }
    if order.unlisted > 0 {
        report
            .problems
            .push(format!("... and {} more order problems", order.unlisted));
    }
    report
}

/// Resolves a replica's log and applies the order rules to its decided records, each at the
/// position of the entry it came from.
fn check_replica(
    dir: &Path,
    records: Vec<Record>,
    at: &HashMap<u64, RecordPos>,
    order: &mut OrderCheck,
    report: &mut VerifyReport,
) {
    let written = records
        .iter()
        .filter(|r| matches!(r, Record::Raft(_)))
        .count() as u64;
    match resolve(dir, records) {
        Ok(r) => {
            report.raft = Some(RaftSummary {
                written,
                last_index: r.last_index,
                state: r.state,
                snapshot: r.snapshot.as_ref().map(|s| (s.index, s.term)),
            });
            // The decided records go on from where the snapshot's state left off.
            if let Some(c) = &r.compacted {
                report.compacted = c.records;
                report.last_round = Some(c.round).filter(|&n| n > 0);
                report.end = c.end;
                order.ended(c.end.is_some());
            }
            // The header was checked as it was read.
            for (record, &(_, index)) in r.records.iter().skip(1).zip(&r.entries) {
                if let Some(&pos) = at.get(&index) {
                    order.check(report, pos, record);
                }
            }
        }
        Err(e) => report.problems.push(e.to_string()),
    }
}
