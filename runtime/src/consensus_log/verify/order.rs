//! The record-order rules of [`verify`](super::verify): one header first, rounds counting up
//! from 1 without a gap, every other record at the round the coordinator writes it at, and
//! nothing after the end record.
//!
//! The coordinator (`coordinator::process::state`) writes a replan record for round `n + 1`
//! just before the round record `n + 1`, and a lifecycle or end record at the last round it
//! logged (`n`, 0 before the first round); an unreachable or task record is written like a replan. A restarted coordinator resumes from the last
//! round record, so a round decided twice (replans logged, then a crash before the round
//! record) repeats only its replan records. These rules are what lets a lost record show: a
//! round record removed from the middle of a segment leaves a gap, and records lost at the
//! end of one segment leave a gap before the next segment's first round.

use super::VerifyReport;
use crate::consensus_log::reader::RecordPos;
use crate::consensus_log::record::Record;
use crate::consensus_log::segment::segment_name;
use crate::msg::Verdict;

/// At most this many order problems are listed; the rest are counted.
const MAX_LISTED: usize = 20;

/// The running state of the order rules over the records read so far.
#[derive(Default)]
pub(super) struct OrderCheck {
    agents: Option<usize>,
    /// Cells of the run's grid (from the header).
    cells: Option<u64>,
    listed: usize,
    /// Problems found beyond [`MAX_LISTED`].
    pub unlisted: usize,
    end_seen: bool,
}

impl OrderCheck {
    fn problem(&mut self, report: &mut VerifyReport, pos: RecordPos, what: String) {
        if self.listed < MAX_LISTED {
            self.listed += 1;
            let at = format!("{} byte {}", segment_name(pos.segment), pos.offset);
            report.problems.push(format!("{at}: {what}"));
        } else {
            self.unlisted += 1;
        }
    }

    fn agent(&mut self, report: &mut VerifyReport, pos: RecordPos, agent: u32) {
        if let Some(n) = self.agents {
            if agent as usize >= n {
                self.problem(report, pos, format!("agent {agent} of a run of {n} agents"));
            }
        }
    }

    /// A map change's cells must be on the grid, each list ascending, no cell in both.
    fn map_cells(
        &mut self,
        report: &mut VerifyReport,
        pos: RecordPos,
        closed: &[u32],
        opened: &[u32],
    ) {
        let on_grid = |c: &u32| self.cells.is_none_or(|n| u64::from(*c) < n);
        let ascending = |v: &[u32]| v.windows(2).all(|w| w[0] < w[1]);
        let what = if !closed.iter().chain(opened).all(on_grid) {
            "a map change with a cell off the grid"
        } else if !ascending(closed) || !ascending(opened) {
            "a map change whose cells are not ascending"
        } else if closed.iter().any(|c| opened.binary_search(c).is_ok()) {
            "a map change that closes and opens the same cell"
        } else if closed.is_empty() && opened.is_empty() {
            "a map change without a cell"
        } else {
            return;
        };
        self.problem(report, pos, what.into());
    }

    /// A record other than a round must belong to `expected`, the round it is written at.
    fn at_round(
        &mut self,
        report: &mut VerifyReport,
        pos: RecordPos,
        record: &Record,
        expected: u64,
    ) {
        let Some(round) = record.round().filter(|&r| r != expected) else {
            return;
        };
        let last = report.last_round.unwrap_or(0);
        let what = format!(
            "{} record for round {round}, but the last round logged before it is {last} \
             (expected round {expected})",
            record.kind()
        );
        self.problem(report, pos, what);
    }

    /// Says whether the run ended before the records to come (a compacted log's snapshot).
    pub(super) fn ended(&mut self, ended: bool) {
        self.end_seen = ended;
    }

    /// Applies the rules to the next record and counts it.
    pub(super) fn check(&mut self, report: &mut VerifyReport, pos: RecordPos, record: &Record) {
        if self.end_seen && !matches!(record, Record::End(_)) {
            let what = format!("{} record after the end record", record.kind());
            self.problem(report, pos, what);
        }
        let last = report.last_round.unwrap_or(0);
        match record {
            Record::Header(h) => {
                report.counts.header += 1;
                if report.counts.header > 1 {
                    self.problem(report, pos, "a second header record".into());
                } else {
                    self.agents = Some(h.agents.len());
                    self.cells = Some(u64::from(h.width) * u64::from(h.height));
                }
            }
            Record::Round(r) => {
                report.counts.round += 1;
                if let Some(prev) = report.last_round.filter(|&p| r.round <= p) {
                    let what = format!("round {} after round {prev}", r.round);
                    self.problem(report, pos, what);
                } else if r.round > last + 1 {
                    let missing = if r.round == last + 2 {
                        format!("round {} is missing", last + 1)
                    } else {
                        format!("rounds {} to {} are missing", last + 1, r.round - 1)
                    };
                    let what = format!("{missing} (round {} follows round {last})", r.round);
                    self.problem(report, pos, what);
                }
                report.first_round.get_or_insert(r.round);
                report.last_round = Some(r.round);
                for d in &r.decisions {
                    self.agent(report, pos, d.agent);
                    if Verdict::from_u8(d.verdict).is_none() {
                        let what = format!("agent {}: unknown verdict {}", d.agent, d.verdict);
                        self.problem(report, pos, what);
                    }
                }
            }
            Record::Lifecycle(_) => {
                report.counts.lifecycle += 1;
                self.at_round(report, pos, record, last);
            }
            Record::Replan(r) => {
                report.counts.replan += 1;
                self.agent(report, pos, r.agent);
                self.at_round(report, pos, record, last + 1);
            }
            Record::Unreachable(u) => {
                report.counts.unreachable += 1;
                self.agent(report, pos, u.agent);
                self.at_round(report, pos, record, last + 1);
            }
            Record::Task(t) => {
                report.counts.task += 1;
                self.agent(report, pos, t.agent);
                self.at_round(report, pos, record, last + 1);
            }
            Record::MapChange(m) => {
                report.counts.map_change += 1;
                self.agent(report, pos, m.agent);
                self.map_cells(report, pos, &m.closed, &m.opened);
                self.at_round(report, pos, record, last + 1);
            }
            Record::End(e) => {
                report.counts.end += 1;
                if report.end.is_some() {
                    self.problem(report, pos, "a second end record".into());
                } else {
                    report.end = Some(*e);
                    self.at_round(report, pos, record, last);
                }
                self.end_seen = true;
            }
            // Raft's records are resolved before these rules see a replica's log; in any
            // other log they are out of place.
            Record::Raft(_) | Record::RaftState(_) | Record::Snapshot(_) => {
                let what = format!("a {} record in a single coordinator's log", record.kind());
                self.problem(report, pos, what);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::consensus_log::record::{MapChangeRecord, Record, RunHeader};
    use crate::consensus_log::LogWriter;
    use crate::consensus_log::{verify, FORMAT_VERSION};
    use crate::scenario::FsyncPolicy;

    /// The problems `verify` finds in a 4 x 4 run's log holding `change` before round 1.
    fn problems(change: MapChangeRecord) -> Vec<String> {
        let dir = tempfile::tempdir().unwrap();
        let (mut log, _) = LogWriter::open(dir.path(), FsyncPolicy::EveryRecord).unwrap();
        log.append(&Record::Header(RunHeader::tiny(FORMAT_VERSION)))
            .unwrap();
        log.append(&Record::MapChange(change)).unwrap();
        drop(log);
        verify(dir.path()).problems
    }

    #[test]
    fn a_map_change_must_name_cells_of_the_grid_once_each_in_order() {
        let change = |closed: Vec<u32>, opened: Vec<u32>| MapChangeRecord {
            round: 1,
            agent: 0,
            closed,
            opened,
        };
        // The tiny run has no agents: every map change names an agent it does not have.
        let agent = "agent 0 of a run of 0 agents";
        let with = |p: Vec<String>, what: &str| p.iter().any(|l| l.ends_with(what));
        let good = problems(change(vec![1, 5], vec![7]));
        assert!(good.len() == 1 && with(good.clone(), agent), "{good:?}");
        for (bad, what) in [
            (
                change(vec![16], vec![]),
                "a map change with a cell off the grid",
            ),
            (
                change(vec![5, 1], vec![]),
                "a map change whose cells are not ascending",
            ),
            (
                change(vec![5], vec![5]),
                "a map change that closes and opens the same cell",
            ),
            (change(vec![], vec![]), "a map change without a cell"),
        ] {
            let p = problems(bad);
            assert!(with(p.clone(), what), "{what}: {p:?}");
        }
    }
}
