//! Comparing two consensus logs record by record: `hnav log replay` checks that a lockstep
//! run started again decides exactly as its log says.
//!
//! Records are compared decoded, not as bytes, so that the first difference can be said in
//! words: the round, the agent, and both decisions (verdict, cell, conflict kind). A round's
//! decisions are compared before its candidates' digest, because a decision names an agent
//! and the digest does not; a round whose candidates differ while every decision agrees is
//! reported as such.

use std::fmt;

use super::record::{EndReason, LoggedDecision, Record, RoundRecord};
use super::show::{describe, describe_decision};

/// How a replayed log compares with the logged one.
#[derive(Clone, Debug, PartialEq)]
pub enum Comparison {
    /// Every record the same.
    Identical {
        /// Round records compared.
        rounds: u64,
        /// The logged run was cut short (stopped, or no end record) after this round: only
        /// that far was compared, the replay may have gone on.
        cut_short_at: Option<u64>,
    },
    /// The first difference.
    Diverged(Divergence),
}

/// The first record where two logs differ.
#[derive(Clone, Debug, PartialEq)]
pub struct Divergence {
    /// The round the records belong to (`None`: the header).
    pub round: Option<u64>,
    /// The agent whose decision (or record) differs, when one does.
    pub agent: Option<u32>,
    /// What the log holds there, in words (`None`: the log ended).
    pub logged: Option<String>,
    /// What the replay decided there, in words (`None`: the replay's log ended).
    pub replayed: Option<String>,
    /// More on the difference (e.g. the candidates' digests).
    pub detail: Option<String>,
}

impl fmt::Display for Divergence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.round, self.agent) {
            (None, _) => write!(f, "the run header")?,
            (Some(r), None) => write!(f, "round {r}")?,
            (Some(r), Some(a)) => write!(f, "round {r}, agent {a}")?,
        }
        let said = |s: &Option<String>| s.clone().unwrap_or_else(|| "nothing more".into());
        write!(
            f,
            ": logged {}, replayed {}",
            said(&self.logged),
            said(&self.replayed)
        )?;
        if let Some(d) = &self.detail {
            write!(f, " ({d})")?;
        }
        Ok(())
    }
}

/// Compares `replayed` with `logged` (both a whole log's records in order, header first);
/// `width` is the grid width, for cells in words.
///
/// A logged run that was stopped, or has no end record (killed, or still going), is
/// compared only as far as it goes: a replay decides on after the point where it ended.
pub fn compare(logged: &[Record], replayed: &[Record], width: u32) -> Comparison {
    let cut_short_at = cut_short(logged);
    // A stopped run's end record says where it was stopped, not what it decided.
    let logged_until = match (cut_short_at, logged.last()) {
        (Some(_), Some(Record::End(_))) => logged.len() - 1,
        _ => logged.len(),
    };
    let mut rounds = 0;
    let mut last_round = 0;
    for i in 0..logged_until.max(replayed.len()) {
        let a = logged[..logged_until].get(i);
        let b = replayed.get(i);
        let (a, b) = match (a, b) {
            (Some(a), Some(b)) => (a, b),
            (None, Some(_)) if cut_short_at.is_some() => break,
            (a, b) => {
                return Comparison::Diverged(Divergence {
                    round: a.or(b).and_then(Record::round).or(Some(last_round)),
                    agent: None,
                    logged: a.map(|r| describe(r, width)),
                    replayed: b.map(|r| describe(r, width)),
                    detail: None,
                })
            }
        };
        if let (Record::Round(x), Record::Round(y)) = (a, b) {
            if x.round == y.round {
                if let Some(d) = compare_rounds(x, y, width) {
                    return Comparison::Diverged(d);
                }
                rounds += 1;
                last_round = x.round;
                continue;
            }
        }
        if a != b {
            return Comparison::Diverged(Divergence {
                round: a.round(),
                agent: record_agent(a),
                logged: Some(describe(a, width)),
                replayed: Some(describe(b, width)),
                detail: None,
            });
        }
    }
    Comparison::Identical {
        rounds,
        cut_short_at,
    }
}

/// The last round of a log that ends without deciding its end: no end record, or `stopped`.
fn cut_short(records: &[Record]) -> Option<u64> {
    let last_round = || {
        records
            .iter()
            .rev()
            .find_map(Record::round)
            .unwrap_or_default()
    };
    match records.last() {
        Some(Record::End(e)) if e.reason == EndReason::Stopped => Some(e.round),
        Some(Record::End(_)) => None,
        _ => Some(last_round()),
    }
}

/// The agent a record is about, if it is about one.
fn record_agent(r: &Record) -> Option<u32> {
    match r {
        Record::Replan(x) => Some(x.agent),
        Record::Unreachable(x) => Some(x.agent),
        Record::Lifecycle(x) if x.role == crate::msg::Role::Agent as u8 => Some(x.index),
        _ => None,
    }
}

/// The first difference between two records of the same round.
fn compare_rounds(x: &RoundRecord, y: &RoundRecord, width: u32) -> Option<Divergence> {
    let candidates_differ =
        x.candidates != y.candidates || x.candidates_digest != y.candidates_digest;
    let candidates = format!(
        "logged {} candidates, digest {:#018x}; replayed {}, digest {:#018x}",
        x.candidates, x.candidates_digest, y.candidates, y.candidates_digest
    );
    let by_agent = |v: &[LoggedDecision], agent: u32| v.iter().find(|d| d.agent == agent).copied();
    let mut agents: Vec<u32> = x
        .decisions
        .iter()
        .chain(&y.decisions)
        .map(|d| d.agent)
        .collect();
    agents.sort_unstable();
    agents.dedup();
    for agent in agents {
        let (a, b) = (by_agent(&x.decisions, agent), by_agent(&y.decisions, agent));
        if a != b {
            let words = |d: Option<LoggedDecision>| {
                Some(d.map_or_else(|| "no decision".into(), |d| describe_decision(&d, width)))
            };
            return Some(Divergence {
                round: Some(x.round),
                agent: Some(agent),
                logged: words(a),
                replayed: words(b),
                detail: candidates_differ
                    .then(|| format!("the round's candidates differ too: {candidates}")),
            });
        }
    }
    candidates_differ.then(|| Divergence {
        round: Some(x.round),
        agent: None,
        logged: Some(format!(
            "{} candidates, digest {:#018x}",
            x.candidates, x.candidates_digest
        )),
        replayed: Some(format!(
            "{} candidates, digest {:#018x}",
            y.candidates, y.candidates_digest
        )),
        detail: Some("the agents proposed differently; every decision agrees".into()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::consensus_log::record::{EndRecord, RunHeader};
    use crate::msg::{ConflictKind, Verdict, NO_CELL};

    fn decision(agent: u32, verdict: Verdict, cell: u32, kind: ConflictKind) -> LoggedDecision {
        LoggedDecision {
            agent,
            verdict: verdict as u8,
            refused: 0,
            kind: kind as u8,
            cell,
            waypoint: NO_CELL,
        }
    }

    fn log(rounds: u64, end: Option<EndReason>) -> Vec<Record> {
        let mut v = vec![Record::Header(RunHeader {
            version: 1,
            scenario_hash: 7,
            seed: 1,
            clock: "lockstep".into(),
            width: 4,
            height: 4,
            agents: Vec::new(),
        })];
        for r in 1..=rounds {
            v.push(Record::Round(RoundRecord {
                round: r,
                candidates: 2,
                candidates_digest: r * 11,
                decisions: vec![
                    decision(0, Verdict::Accept, r as u32, ConflictKind::None),
                    decision(1, Verdict::Hold, NO_CELL, ConflictKind::None),
                ],
            }));
        }
        if let Some(reason) = end {
            v.push(Record::End(EndRecord {
                round: rounds,
                at_goal: 2,
                reason,
            }));
        }
        v
    }

    fn round_mut(v: &mut [Record], round: u64) -> &mut RoundRecord {
        v.iter_mut()
            .find_map(|r| match r {
                Record::Round(x) if x.round == round => Some(x),
                _ => None,
            })
            .unwrap()
    }

    #[test]
    fn the_same_log_is_identical() {
        let a = log(5, Some(EndReason::AllAtGoal));
        assert_eq!(
            compare(&a, &a.clone(), 4),
            Comparison::Identical {
                rounds: 5,
                cut_short_at: None
            }
        );
    }

    #[test]
    fn the_first_changed_decision_is_named_with_its_round_and_agent() {
        let a = log(5, Some(EndReason::AllAtGoal));
        let mut b = a.clone();
        round_mut(&mut b, 3).decisions[1] =
            decision(1, Verdict::Block, NO_CELL, ConflictKind::Crossing);
        round_mut(&mut b, 4).decisions[0].cell = 9;
        let Comparison::Diverged(d) = compare(&a, &b, 4) else {
            panic!("no divergence found");
        };
        assert_eq!((d.round, d.agent), (Some(3), Some(1)));
        assert_eq!(
            d.to_string(),
            "round 3, agent 1: logged hold a1, replayed block a1 crossing"
        );
    }

    #[test]
    fn different_candidates_with_equal_decisions_are_a_divergence() {
        let a = log(3, Some(EndReason::AllAtGoal));
        let mut b = a.clone();
        round_mut(&mut b, 2).candidates_digest = 5;
        let Comparison::Diverged(d) = compare(&a, &b, 4) else {
            panic!("no divergence found");
        };
        assert_eq!((d.round, d.agent), (Some(2), None));
        assert!(d.to_string().contains("digest 0x0000000000000005"), "{d}");
    }

    #[test]
    fn a_replay_that_ends_elsewhere_diverges_unless_the_run_was_cut_short() {
        let a = log(4, Some(EndReason::AllAtGoal));
        let b = log(6, Some(EndReason::AllAtGoal));
        let Comparison::Diverged(d) = compare(&a, &b, 4) else {
            panic!("no divergence found");
        };
        assert_eq!(d.round, Some(4));
        assert!(d.to_string().contains("logged end round 4"), "{d}");
        let Comparison::Diverged(d) = compare(&b, &a, 4) else {
            panic!("no divergence found");
        };
        assert!(d.to_string().contains("replayed end round 4"), "{d}");
        for cut in [log(4, Some(EndReason::Stopped)), log(4, None)] {
            assert_eq!(
                compare(&cut, &b, 4),
                Comparison::Identical {
                    rounds: 4,
                    cut_short_at: Some(4)
                }
            );
        }
    }
}
