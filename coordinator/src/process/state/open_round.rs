//! The round being collected ([`OpenRound`]): the candidates in so far, when the first came,
//! and when the round closes without the rest.

use std::time::{Duration, Instant};

use hnav_runtime::consensus_log::{candidates_digest, LoggedDecision, RoundRecord};
use hnav_runtime::msg::{Candidate, Decision};
use hnav_runtime::scenario::{ClockMode, Scenario};

use super::roster::Roster;

/// The open round (`last + 1`) of the run.
pub(super) struct OpenRound {
    /// Per agent, its candidate for the open round, if one came.
    pending: Vec<Option<Candidate>>,
    /// The candidates that came, in agent order: the record's digest is over them. Kept so
    /// that closing a round allocates nothing once warm.
    present: Vec<Candidate>,
    /// When its first candidate came; `None` while it has none.
    opened: Option<Instant>,
    /// When its last candidate came.
    last: Option<Instant>,
    clock: ClockMode,
    /// `round_deadline_ms`: how long a realtime round waits after its first candidate.
    deadline: Duration,
}

impl OpenRound {
    /// An empty round of `scenario`'s swarm.
    pub(super) fn new(scenario: &Scenario) -> Self {
        let n = scenario.agents.len();
        OpenRound {
            pending: vec![None; n],
            present: Vec::with_capacity(n),
            opened: None,
            last: None,
            clock: scenario.sim.clock,
            deadline: Duration::from_millis(u64::from(scenario.coordinator.round_deadline_ms)),
        }
    }

    /// Takes in a candidate for this round (checked, of a known agent).
    pub(super) fn take(&mut self, c: Candidate) {
        let now = Instant::now();
        if self.pending.iter().all(Option::is_none) {
            self.opened = Some(now);
        }
        self.last = Some(now);
        self.pending[c.agent as usize] = Some(c);
    }

    /// When its first and its last candidate came (`None` while it has none).
    pub(super) fn came(&self) -> (Option<Instant>, Option<Instant>) {
        (self.opened, self.last)
    }

    /// Per agent, its candidate or `None`.
    pub(super) fn candidates(&self) -> &[Option<Candidate>] {
        &self.pending
    }

    /// Whether every agent the roster waits for has its candidate in (and one has).
    pub(super) fn complete(&self, roster: &Roster) -> bool {
        self.pending.iter().any(Option::is_some)
            && self
                .pending
                .iter()
                .enumerate()
                .all(|(i, c)| !roster.live(i) || c.is_some())
    }

    /// When the round closes without the missing candidates: in realtime `round_deadline_ms`
    /// after its first candidate; never in lockstep, or with no candidate in.
    pub(super) fn deadline(&self) -> Option<Instant> {
        match (self.clock, self.opened) {
            (ClockMode::Realtime, Some(opened)) => Some(opened + self.deadline),
            _ => None,
        }
    }

    /// The round's record as `round` with `decisions`, written into `reuse` (the last
    /// round's record), whose buffers are kept: no allocation once warm.
    pub(super) fn record(
        &mut self,
        round: u64,
        decisions: &[Decision],
        reuse: Option<RoundRecord>,
    ) -> RoundRecord {
        self.present.clear();
        self.present.extend(self.pending.iter().flatten());
        let mut rec = reuse.unwrap_or_else(|| RoundRecord::new(0, &[], &[]));
        rec.round = round;
        rec.candidates = self.present.len() as u32;
        rec.candidates_digest = candidates_digest(&self.present);
        rec.decisions.clear();
        rec.decisions
            .extend(decisions.iter().map(LoggedDecision::from));
        rec
    }

    /// Empties the round once it is decided: the next one opens with its first candidate.
    pub(super) fn clear(&mut self) {
        self.pending.iter_mut().for_each(|c| *c = None);
        self.opened = None;
        self.last = None;
    }
}
