//! The checker ([`Checker`]): Raft's safety properties asserted on what the replicas
//! really did, as the scheduler sees it after every call into one of them (the messages it
//! sent, the entries it handed out as committed, its role, term and hard state, its log),
//! and the simulated coordinator's own promises (what it acknowledged, what it applied).
//!
//! | property | how it is checked |
//! |---|---|
//! | one leader per term | every replica's role and term after every call |
//! | log matching | the logs of the running replicas pairwise, whenever a new leader is seen and at the end: where two hold an entry of the same index and term, they hold the same entries up to it |
//! | leader completeness | a new leader's log holds every entry that leaders of earlier terms committed (as far as their commit indices reached), at its index and term; a leader of an earlier term elected late need not hold a later term's |
//! | same record at the same index | each committed entry handed out is compared with what any replica handed out at its index before |
//! | none applied twice | a replica hands out rising indices, and the coordinator applies no record twice |
//! | no acknowledged record lost | an acknowledged record is the committed entry at its index, and every replica has handed it out by the end |
//! | votes and terms durable | a replica that granted its vote in a term never grants it to another candidate in that term, and never restarts with a lower term than one it spoke in or with another vote in that term |
//!
//! Liveness (a commit within a bound after the heal, every replica caught up within another)
//! is the scheduler's to time; it reports a miss here.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;

use raft::eraftpb::{HardState, Message, MessageType};

use hnav_runtime::consensus_log::{decode_record, AppliedState};

use super::super::peer::{Committed, Role};
use super::clock::Time;

/// A property the checker found broken.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Property {
    /// Two leaders in one term.
    OneLeaderPerTerm,
    /// Two logs that agree on an entry but not on the entries before it.
    LogMatching,
    /// A leader without an entry that was committed before it.
    LeaderCompleteness,
    /// Two replicas that handed out different records at one index.
    SameRecordAtIndex,
    /// An entry handed out twice, or a record applied twice.
    AppliedTwice,
    /// An acknowledged record that is not committed at its index.
    AcknowledgedLost,
    /// A vote or a term forgotten.
    DurableVote,
    /// No commit within the bound after the heal, or a replica not caught up.
    Liveness,
}

impl Property {
    /// Its name in a report.
    pub fn name(self) -> &'static str {
        match self {
            Property::OneLeaderPerTerm => "one leader per term",
            Property::LogMatching => "log matching",
            Property::LeaderCompleteness => "leader completeness",
            Property::SameRecordAtIndex => "same record at the same index",
            Property::AppliedTwice => "none applied twice",
            Property::AcknowledgedLost => "no acknowledged record lost",
            Property::DurableVote => "votes and terms durable",
            Property::Liveness => "liveness",
        }
    }
}

/// A broken property, when and how.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Violation {
    /// When the checker saw it.
    pub at: Time,
    /// Which property.
    pub property: Property,
    /// What it saw.
    pub detail: String,
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} at {}: {}",
            self.property.name(),
            self.at,
            self.detail
        )
    }
}

/// One entry of a replica's log, as log matching compares it.
pub type LogEntry = (u64, Vec<u8>);

/// What the checker has seen, to check the properties listed at the top of its file.
#[derive(Debug, Default)]
pub struct Checker {
    leaders: BTreeMap<u64, u64>,
    /// Term -> the highest commit index its leader reached.
    leader_commits: BTreeMap<u64, u64>,
    /// Every committed entry any replica handed out: index -> (term, data).
    committed: BTreeMap<u64, (u64, Vec<u8>)>,
    /// Per replica (0-based): the last index it handed out in this incarnation.
    handed: Vec<u64>,
    /// Per replica: what its coordinator applied in this incarnation, in order.
    applied: Vec<Vec<Vec<u8>>>,
    applied_set: Vec<BTreeSet<Vec<u8>>>,
    /// (replica, term) -> the candidate it granted its vote to.
    votes: BTreeMap<(u64, u64), u64>,
    /// Per replica: the highest term it sent a message in (pre-votes aside).
    spoke: Vec<u64>,
    /// Acknowledged records: index -> data.
    acked: BTreeMap<u64, Vec<u8>>,
    first: Option<Violation>,
}

impl Checker {
    /// A checker of replicas `1..=n`.
    pub fn new(n: usize) -> Self {
        Checker {
            handed: vec![0; n],
            applied: vec![Vec::new(); n],
            applied_set: vec![BTreeSet::new(); n],
            spoke: vec![0; n],
            ..Checker::default()
        }
    }

    /// The first violation, if any.
    pub fn violation(&self) -> Option<&Violation> {
        self.first.as_ref()
    }

    /// Records a violation (the first one is kept).
    pub fn fail(&mut self, at: Time, property: Property, detail: String) {
        if self.first.is_none() {
            self.first = Some(Violation {
                at,
                property,
                detail,
            });
        }
    }

    /// Records acknowledged so far.
    pub fn acknowledged(&self) -> u64 {
        self.acked.len() as u64
    }

    /// Leaders elected so far (terms that had one).
    pub fn elections(&self) -> u64 {
        self.leaders.len() as u64
    }

    /// The highest acknowledged index.
    pub fn last_acknowledged(&self) -> u64 {
        self.acked.keys().next_back().copied().unwrap_or(0)
    }

    /// The last index replica `id` handed out in this incarnation.
    pub fn handed(&self, id: u64) -> u64 {
        self.handed[id as usize - 1]
    }

    /// Replica `id` sent `m`.
    pub fn sent(&mut self, at: Time, id: u64, m: &Message) {
        let t = m.get_msg_type();
        if matches!(
            t,
            MessageType::MsgRequestPreVote | MessageType::MsgRequestPreVoteResponse
        ) {
            return;
        }
        let i = id as usize - 1;
        self.spoke[i] = self.spoke[i].max(m.term);
        if t == MessageType::MsgRequestVoteResponse && !m.reject {
            match self.votes.insert((id, m.term), m.to) {
                Some(before) if before != m.to => self.fail(
                    at,
                    Property::DurableVote,
                    format!(
                        "replica {id} granted its vote in term {} to {before} and then to {}",
                        m.term, m.to
                    ),
                ),
                _ => {}
            }
        }
    }

    /// Replica `id` started a new incarnation over its journal, with hard state `hs`.
    pub fn started(&mut self, at: Time, id: u64, hs: &HardState) {
        let i = id as usize - 1;
        self.handed[i] = 0;
        self.applied[i].clear();
        self.applied_set[i].clear();
        if hs.term < self.spoke[i] {
            let detail = format!(
                "replica {id} restarted in term {} after it spoke in term {}",
                hs.term, self.spoke[i]
            );
            self.fail(at, Property::DurableVote, detail);
        }
        if let Some(&c) = self.votes.get(&(id, hs.term)) {
            if hs.vote != c {
                let detail = format!(
                    "replica {id} restarted in term {} with vote {} after it voted for {c}",
                    hs.term, hs.vote
                );
                self.fail(at, Property::DurableVote, detail);
            }
        }
    }

    /// Replica `id` is in `role` in `term`; true if it is a leader not seen before.
    pub fn role(&mut self, at: Time, id: u64, role: Role, term: u64) -> bool {
        if role != Role::Leader {
            return false;
        }
        match self.leaders.insert(term, id) {
            None => true,
            Some(other) if other != id => {
                let detail = format!("replicas {other} and {id} both lead term {term}");
                self.fail(at, Property::OneLeaderPerTerm, detail);
                false
            }
            Some(_) => false,
        }
    }

    /// The leader of `term` knows entries up to `index` committed.
    pub fn leader_committed(&mut self, term: u64, index: u64) {
        let c = self.leader_commits.entry(term).or_default();
        *c = (*c).max(index);
    }

    /// Leader `id` of `term`, whose log says `log_term(index)` (`None` past its end), against
    /// every committed entry up to the highest index a leader of an earlier term committed:
    /// Raft's leader completeness speaks of leaders of later terms, and a leader of an earlier
    /// term may win its election after a later term has committed more.
    /// Indices up to `compacted` are in the leader's snapshot, which stands for committed
    /// entries only.
    pub fn complete(
        &mut self,
        at: Time,
        (id, term): (u64, u64),
        compacted: u64,
        log_term: impl Fn(u64) -> Option<u64>,
    ) {
        let Some(&upto) = self.leader_commits.range(..term).map(|(_, i)| i).max() else {
            return;
        };
        if upto <= compacted {
            return;
        }
        let missing = self
            .committed
            .range(compacted + 1..=upto)
            .find(|(&index, (t, _))| log_term(index) != Some(*t));
        if let Some((index, (t, _))) = missing {
            let held = log_term(*index).map_or("nothing".to_string(), |h| format!("term {h}"));
            let detail = format!(
                "leader {id} of term {term} holds {held} at index {index}, committed in term {t} \
                 before term {term}"
            );
            self.fail(at, Property::LeaderCompleteness, detail);
        }
    }

    /// Replica `id` handed out `entries` as committed.
    pub fn committed(&mut self, at: Time, id: u64, entries: &[Committed]) {
        let i = id as usize - 1;
        for e in entries {
            if e.index <= self.handed[i] {
                let detail = format!(
                    "replica {id} handed out index {} after index {}",
                    e.index, self.handed[i]
                );
                self.fail(at, Property::AppliedTwice, detail);
            }
            self.handed[i] = e.index;
            match self.committed.get(&e.index) {
                None => {
                    self.committed.insert(e.index, (e.term, e.data.clone()));
                }
                Some((t, d)) if (*t, d) != (e.term, &e.data) => {
                    let property = if self.acked.contains_key(&e.index) {
                        Property::AcknowledgedLost
                    } else {
                        Property::SameRecordAtIndex
                    };
                    let detail = format!(
                        "replica {id} committed term {} at index {}, another replica term {t}",
                        e.term, e.index
                    );
                    self.fail(at, property, detail);
                }
                Some(_) => {}
            }
        }
    }

    /// Replica `id` started from a snapshot standing for the entries up to `index`, its state
    /// `state`: that must be what the committed records up to `index` add up to (folded
    /// from `fresh`, the state of nothing); from there on the replica is as one that handed
    /// them out and applied them.
    pub fn installed(
        &mut self,
        at: Time,
        id: u64,
        (index, state): &(u64, AppliedState),
        mut fresh: AppliedState,
    ) {
        let i = id as usize - 1;
        let prefix: Vec<Vec<u8>> = self
            .committed
            .range(..=*index)
            .map(|(_, (_, d))| d.clone())
            .collect();
        for d in &prefix {
            if let Ok(r) = decode_record(d) {
                fresh.fold(&r);
            }
        }
        if fresh != *state {
            let detail = format!(
                "replica {id}'s snapshot at index {index} holds {} records through round {}, \
                 the committed entries up to it {} through round {}",
                state.records, state.round, fresh.records, fresh.round
            );
            self.fail(at, Property::SameRecordAtIndex, detail);
        }
        self.handed[i] = self.handed[i].max(*index);
        self.applied_set[i] = prefix.iter().cloned().collect();
        self.applied[i] = prefix;
    }

    /// Replica `id`'s coordinator applied `record`.
    pub fn applied(&mut self, at: Time, id: u64, record: &[u8]) {
        let i = id as usize - 1;
        if !self.applied_set[i].insert(record.to_vec()) {
            let detail = format!("replica {id}'s coordinator applied a record twice");
            self.fail(at, Property::AppliedTwice, detail);
        }
        self.applied[i].push(record.to_vec());
    }

    /// The leader acknowledged `record` at `index`: its decision is final.
    pub fn acked(&mut self, at: Time, index: u64, record: &[u8]) {
        if self.committed.get(&index).is_some_and(|(_, d)| d != record) {
            let detail =
                format!("the record acknowledged at index {index} is not the one committed there");
            self.fail(at, Property::AcknowledgedLost, detail);
        }
        self.acked.insert(index, record.to_vec());
    }

    /// The logs of the running replicas, compared pairwise: each is the index its snapshot
    /// stands for and the entries after it; the indices both hold are compared (a snapshot
    /// stands for committed entries only, checked as they are handed out).
    pub fn logs(&mut self, at: Time, logs: &[(u64, (u64, Vec<LogEntry>))]) {
        for (a, (ia, (oa, la))) in logs.iter().enumerate() {
            for (ib, (ob, lb)) in logs[a + 1..].iter() {
                let first = oa.max(ob) + 1;
                let end = (oa + la.len() as u64).min(ob + lb.len() as u64);
                let ea = |index: u64| &la[(index - oa - 1) as usize];
                let eb = |index: u64| &lb[(index - ob - 1) as usize];
                let Some(top) = (first..=end).rev().find(|&k| ea(k).0 == eb(k).0) else {
                    continue;
                };
                if let Some(k) = (first..top).find(|&k| ea(k) != eb(k)) {
                    let detail = format!(
                        "replicas {ia} and {ib} agree on index {top} (term {}) but not on index {k}",
                        ea(top).0,
                    );
                    self.fail(at, Property::LogMatching, detail);
                    return;
                }
            }
        }
    }

    /// The end of a run, every replica caught up: each acknowledged record is committed at
    /// its index, and what each coordinator applied is the committed sequence (a leader's
    /// last decision, `pending`, may still be in flight).
    pub fn finish(&mut self, at: Time, pending: &[(u64, Option<Vec<u8>>)]) {
        let lost = self
            .acked
            .iter()
            .find(|(i, d)| self.committed.get(i).is_none_or(|(_, c)| c != *d))
            .map(|(&i, _)| i);
        if let Some(index) = lost {
            let detail = format!(
                "the record acknowledged at index {index} is not the one committed there, or none is"
            );
            self.fail(at, Property::AcknowledgedLost, detail);
        }
        let sequence: Vec<&Vec<u8>> = self.committed.values().map(|(_, d)| d).collect();
        let mut wrong = None;
        for (id, last) in pending {
            let mut applied: &[Vec<u8>] = &self.applied[*id as usize - 1];
            if let (Some(p), [rest @ .., l]) = (last, applied) {
                if l == p {
                    applied = rest;
                }
            }
            let differs = applied.len() > sequence.len()
                || applied.iter().zip(&sequence).any(|(a, s)| a != *s);
            if differs && wrong.is_none() {
                wrong = Some(format!(
                    "replica {id}'s coordinator applied {} records that are not the committed sequence",
                    applied.len()
                ));
            }
        }
        if let Some(detail) = wrong {
            self.fail(at, Property::SameRecordAtIndex, detail);
        }
    }
}
