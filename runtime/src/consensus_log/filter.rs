//! Which records `hnav log show` prints: [`RecordFilter`], by round range, agent and kind.
//!
//! A replica's Raft entry is judged by the record it carries (a round inside an entry is a
//! round), so the same filter works on a replicated log; an entry narrowed to one agent's
//! decisions is re-encoded around the narrowed record.

use std::ops::RangeInclusive;

use super::frame::{decode_record, encode_record};
use super::record::{RaftEntryRecord, Record};
use crate::msg::Role;

/// The kinds a filter can name, as [`Record::kind`] spells them.
pub const KINDS: [&str; 11] = [
    "header",
    "round",
    "lifecycle",
    "replan",
    "unreachable",
    "end",
    "raft-entry",
    "raft-state",
    "task",
    "snapshot",
    "map-change",
];

/// What to keep of a log. The empty filter keeps everything; each part given narrows it.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RecordFilter {
    /// Only records of these rounds (records without a round, the header and Raft hard
    /// states, are left out).
    pub rounds: Option<RangeInclusive<u64>>,
    /// Only what concerns this agent: its decisions (a round without one is left out), its
    /// lifecycle events, replans, unreachable reports and tasks.
    pub agent: Option<u32>,
    /// Only records of these kinds (names of [`KINDS`]); empty: every kind.
    pub kinds: Vec<String>,
}

impl RecordFilter {
    /// Whether the filter keeps everything.
    pub fn is_empty(&self) -> bool {
        self.rounds.is_none() && self.agent.is_none() && self.kinds.is_empty()
    }

    /// `record` as the filter keeps it: unchanged, narrowed to the agent's decisions, or
    /// `None` when it is left out.
    pub fn apply(&self, record: &Record) -> Option<Record> {
        if self.is_empty() {
            return Some(record.clone());
        }
        let Record::Raft(entry) = record else {
            return self.apply_plain(record);
        };
        let inner = (!entry.data.is_empty())
            .then(|| decode_record(&entry.data).ok())
            .flatten();
        let Some(inner) = inner else {
            // An empty entry (a new leader's) or one that cannot be decoded: only by kind.
            let keep =
                self.rounds.is_none() && self.agent.is_none() && self.kind_kept(record.kind());
            return keep.then(|| record.clone());
        };
        let kept = self.apply_plain(&inner)?;
        if kept == inner {
            return Some(record.clone());
        }
        let mut data = Vec::new();
        encode_record(&kept, &mut data).ok()?;
        Some(Record::Raft(RaftEntryRecord {
            term: entry.term,
            index: entry.index,
            data,
        }))
    }

    fn kind_kept(&self, kind: &str) -> bool {
        self.kinds.is_empty() || self.kinds.iter().any(|k| k == kind)
    }

    /// [`RecordFilter::apply`] for a record that is not a Raft entry.
    fn apply_plain(&self, record: &Record) -> Option<Record> {
        if !self.kind_kept(record.kind()) {
            return None;
        }
        if let Some(rounds) = &self.rounds {
            if !record.round().is_some_and(|r| rounds.contains(&r)) {
                return None;
            }
        }
        let Some(agent) = self.agent else {
            return Some(record.clone());
        };
        match record {
            Record::Round(r) => {
                let mut r = r.clone();
                r.decisions.retain(|d| d.agent == agent);
                (!r.decisions.is_empty()).then_some(Record::Round(r))
            }
            Record::Lifecycle(l) => {
                (l.role == Role::Agent as u8 && l.index == agent).then(|| record.clone())
            }
            Record::Replan(r) => (r.agent == agent).then(|| record.clone()),
            Record::Unreachable(u) => (u.agent == agent).then(|| record.clone()),
            Record::Task(t) => (t.agent == agent).then(|| record.clone()),
            Record::MapChange(m) => (m.agent == agent).then(|| record.clone()),
            _ => None,
        }
    }
}

/// Parses a round range as `hnav log show --round` takes it: `A..B` (both included), `A..`,
/// `..B`, or one round `A`.
pub fn parse_rounds(text: &str) -> Result<RangeInclusive<u64>, String> {
    let number = |s: &str, or: u64| -> Result<u64, String> {
        if s.is_empty() {
            return Ok(or);
        }
        s.trim().parse::<u64>().map_err(|_| {
            format!(
                "`{s}` is not a round number (a whole number from 0); write A..B, A.., ..B or A"
            )
        })
    };
    let (a, b) = match text.split_once("..") {
        Some((a, b)) => (number(a, 0)?, number(b, u64::MAX)?),
        None if text.is_empty() => return Err("empty; write A..B, A.., ..B or A".into()),
        None => {
            let r = number(text, 0)?;
            (r, r)
        }
    };
    if a > b {
        return Err(format!(
            "{a}..{b} is empty: the first round is after the last"
        ));
    }
    Ok(a..=b)
}

/// Parses one kind name (one of [`KINDS`]).
pub fn parse_kind(text: &str) -> Result<String, String> {
    if KINDS.contains(&text) {
        Ok(text.to_string())
    } else {
        Err(format!(
            "`{text}` is not a kind of record; kinds: {}",
            KINDS.join(", ")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::consensus_log::record::{LifecycleRecord, LoggedDecision, RoundRecord};

    fn decision(agent: u32) -> LoggedDecision {
        LoggedDecision {
            agent,
            verdict: 0,
            refused: 0,
            kind: 0,
            cell: 0,
            waypoint: 0,
        }
    }

    fn round(n: u64, agents: &[u32]) -> Record {
        Record::Round(RoundRecord {
            round: n,
            candidates: 0,
            candidates_digest: 0,
            decisions: agents.iter().map(|&a| decision(a)).collect(),
        })
    }

    #[test]
    fn rounds_are_a_to_b_inclusive_and_open_ends() {
        assert_eq!(parse_rounds("3..7"), Ok(3..=7));
        assert_eq!(parse_rounds("3.."), Ok(3..=u64::MAX));
        assert_eq!(parse_rounds("..7"), Ok(0..=7));
        assert_eq!(parse_rounds("5"), Ok(5..=5));
        assert!(parse_rounds("7..3").unwrap_err().contains("empty"));
        assert!(parse_rounds("x..3")
            .unwrap_err()
            .contains("`x` is not a round number"));
        assert!(parse_kind("rounds")
            .unwrap_err()
            .contains("kinds: header, round"));
    }

    #[test]
    fn an_agent_keeps_its_decisions_and_events_only() {
        let f = RecordFilter {
            agent: Some(2),
            ..RecordFilter::default()
        };
        assert_eq!(f.apply(&round(4, &[1, 2, 3])), Some(round(4, &[2])));
        assert_eq!(f.apply(&round(5, &[1, 3])), None);
        let life = |index| {
            Record::Lifecycle(LifecycleRecord {
                round: 9,
                role: Role::Agent as u8,
                index,
                event: 0,
                restarts: 0,
            })
        };
        assert!(f.apply(&life(2)).is_some());
        assert!(f.apply(&life(1)).is_none());
    }

    #[test]
    fn rounds_and_kinds_narrow_and_raft_entries_are_judged_by_their_record() {
        let f = RecordFilter {
            rounds: Some(4..=5),
            kinds: vec!["round".into()],
            agent: Some(1),
        };
        let mut data = Vec::new();
        encode_record(&round(5, &[0, 1]), &mut data).unwrap();
        let entry = Record::Raft(RaftEntryRecord {
            term: 2,
            index: 9,
            data,
        });
        let Some(Record::Raft(kept)) = f.apply(&entry) else {
            panic!("the entry of round 5 is kept");
        };
        assert_eq!((kept.term, kept.index), (2, 9));
        assert_eq!(decode_record(&kept.data).unwrap(), round(5, &[1]));
        assert_eq!(f.apply(&round(6, &[1])), None);
        let empty = Record::Raft(RaftEntryRecord {
            term: 3,
            index: 10,
            data: Vec::new(),
        });
        assert_eq!(f.apply(&empty), None);
        assert!(RecordFilter::default().apply(&empty).is_some());
    }
}
