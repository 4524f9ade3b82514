//! [`Tally`]: what a run's decisions add up to, per agent — accepted moves and their octile
//! length, conflicts, rounds waited, global replans.
//!
//! The coordinator's arbiter folds every decision it publishes, the coordinator rebuilds the
//! same numbers from the log after a restart, and the run summary and the report read them
//! from the log when the run is over; all of them fold the decisions in log order through
//! [`Tally::fold`], so they agree (the lengths are sums of floats, and the same order gives
//! the same bits).
//!
//! # What counts as a conflict
//!
//! The same in every rule set, from what the log holds: a conflict is a request refused
//! ([`Verdict::Block`]) or held for another robot or the map ([`Verdict::Hold`] with a
//! [`ConflictKind`] other than `none`), counted once per request. An agent held asks again
//! every round (a round is one control period, 10 ms by default), so a robot that waits 300
//! rounds behind another for the same cell is one held request, not 300: a decision that
//! repeats the agent's previous logged decision (same verdict, kind and cell) is that
//! request still waiting.
//!
//! Every round an agent asks for a step and is held ([`Verdict::Hold`], whatever the kind)
//! is a round it **waited**, counted in rounds, as time: for a cell to be left, for another
//! robot's turn, or, under `lacam`, for the plan (its order through a cell is `reserved`, and
//! while the robots come to rest for a (re)plan a hold has kind `none`, no conflict). Under
//! `lacam` every hold is a wait for the plan; nothing is ever refused.

use super::record::{LoggedDecision, RoundRecord, RunHeader};
use crate::msg::{ConflictKind, Verdict};

/// One agent's share of a [`Tally`].
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AgentTally {
    /// Accepted moves.
    pub steps: u32,
    /// Length of the accepted moves in cells (straight 1, diagonal sqrt 2).
    pub length: f64,
    /// Requests refused or held for a conflict, each once (see the [module docs](self)).
    pub conflicts: u32,
    /// Rounds in which its request was held ([`Verdict::Hold`]): the time it waited.
    pub waited: u32,
    /// Global replans ([`Verdict::Replan`]).
    pub replans: u32,
}

/// What [`Tally::fold`] made of one decision.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Counted {
    /// An accepted move.
    Step,
    /// A new conflict: a request refused, or held for another robot or the map.
    Conflict,
    /// The same request as the agent's previous decision, still refused or held.
    StillHeld,
    /// Held with no conflict to name (kind `none`): waited, no conflict.
    Waited,
    /// A global replan.
    Replan,
    /// Nothing: an agent the tally does not know, or an unknown verdict.
    Nothing,
}

/// Per-agent [`AgentTally`]s of a run's decisions; see the [module docs](self).
///
/// It keeps each agent's cell (its start, then the cell of its last accepted move) to measure
/// the next move, and its last decision to tell a new request from one still waiting.
/// Folding allocates nothing.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Tally {
    agents: Vec<AgentTally>,
    cells: Vec<u32>,
    last: Vec<Option<(u8, u8, u32)>>,
    width: u32,
}

impl Tally {
    /// A tally of agents starting on the row-major cells `starts` of a grid `width` cells
    /// wide (a width of 0 counts as 1).
    pub fn new(starts: impl IntoIterator<Item = u32>, width: u32) -> Self {
        let cells: Vec<u32> = starts.into_iter().collect();
        Self {
            agents: vec![AgentTally::default(); cells.len()],
            last: vec![None; cells.len()],
            cells,
            width: width.max(1),
        }
    }

    /// A tally of the run a log's header describes.
    pub fn from_header(header: &RunHeader) -> Self {
        Self::new(header.agents.iter().map(|a| a.start), header.width)
    }

    /// Adds one decision and says what it counted. A decision for an agent the tally does
    /// not know, or with an unknown verdict, changes nothing (a damaged log must not stop a
    /// summary).
    pub fn fold(&mut self, d: &LoggedDecision) -> Counted {
        let i = d.agent as usize;
        let (Some(a), Some(cell), Some(last)) = (
            self.agents.get_mut(i),
            self.cells.get_mut(i),
            self.last.get_mut(i),
        ) else {
            return Counted::Nothing;
        };
        let Some(verdict) = Verdict::from_u8(d.verdict) else {
            return Counted::Nothing;
        };
        let repeat = last.replace((d.verdict, d.kind, d.cell)) == Some((d.verdict, d.kind, d.cell));
        let no_conflict = d.kind == ConflictKind::None as u8;
        if verdict == Verdict::Hold {
            a.waited = a.waited.saturating_add(1);
        }
        match verdict {
            Verdict::Accept => {
                a.steps = a.steps.saturating_add(1);
                a.length += step_length(*cell, d.cell, self.width);
                *cell = d.cell;
                Counted::Step
            }
            Verdict::Hold if no_conflict => Counted::Waited,
            Verdict::Block | Verdict::Hold if repeat => Counted::StillHeld,
            Verdict::Block | Verdict::Hold => {
                a.conflicts = a.conflicts.saturating_add(1);
                Counted::Conflict
            }
            Verdict::Replan => {
                a.replans = a.replans.saturating_add(1);
                Counted::Replan
            }
            // A new goal is no move and no conflict: the task records count the tasks.
            Verdict::Task => Counted::Nothing,
        }
    }

    /// Adds every decision of a logged round, in order.
    pub fn fold_round(&mut self, round: &RoundRecord) {
        for d in &round.decisions {
            self.fold(d);
        }
    }

    /// Per agent, the cell it stands on: its start, then that of its last accepted move.
    pub fn cells(&self) -> &[u32] {
        &self.cells
    }

    /// Per agent, index = agent number.
    pub fn agents(&self) -> &[AgentTally] {
        &self.agents
    }

    /// Conflicts of all agents.
    pub fn conflicts(&self) -> u32 {
        self.agents
            .iter()
            .fold(0, |n, a| n.saturating_add(a.conflicts))
    }

    /// Rounds waited (held), of all agents.
    pub fn waited(&self) -> u32 {
        self.agents
            .iter()
            .fold(0, |n, a| n.saturating_add(a.waited))
    }

    /// Replans of all agents.
    pub fn replans(&self) -> u32 {
        self.agents
            .iter()
            .fold(0, |n, a| n.saturating_add(a.replans))
    }
}

/// Octile length of one move between row-major cell indices (0 when not a single move).
fn step_length(from: u32, to: u32, width: u32) -> f64 {
    let (fx, fy) = (i64::from(from % width), i64::from(from / width));
    let (tx, ty) = (i64::from(to % width), i64::from(to / width));
    match ((tx - fx).abs(), (ty - fy).abs()) {
        (1, 1) => std::f64::consts::SQRT_2,
        (1, 0) | (0, 1) => 1.0,
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msg::NO_CELL;

    fn decision(agent: u32, verdict: Verdict, cell: u32) -> LoggedDecision {
        held(agent, verdict, ConflictKind::None, cell)
    }

    fn held(agent: u32, verdict: Verdict, kind: ConflictKind, cell: u32) -> LoggedDecision {
        LoggedDecision {
            agent,
            verdict: verdict as u8,
            refused: 0,
            kind: kind as u8,
            cell,
            waypoint: NO_CELL,
        }
    }

    #[test]
    fn step_lengths_are_octile() {
        assert_eq!(step_length(0, 1, 10), 1.0);
        assert_eq!(step_length(0, 10, 10), 1.0);
        assert_eq!(step_length(0, 11, 10), std::f64::consts::SQRT_2);
        assert_eq!(step_length(0, 22, 10), 0.0);
        assert_eq!(step_length(9, 10, 10), 0.0, "no wrap across rows");
    }

    #[test]
    fn verdicts_are_counted_and_moves_measured_from_the_last_accepted_cell() {
        let mut t = Tally::new([0, 9], 10);
        let counted: Vec<Counted> = [
            decision(0, Verdict::Accept, 11),
            held(0, Verdict::Hold, ConflictKind::HeadOn, 12),
            decision(0, Verdict::Accept, 12),
            held(1, Verdict::Block, ConflictKind::Crossing, 8),
            decision(1, Verdict::Replan, NO_CELL),
            decision(1, Verdict::Accept, 19),
        ]
        .iter()
        .map(|d| t.fold(d))
        .collect();
        use Counted::*;
        assert_eq!(counted, [Step, Conflict, Step, Conflict, Replan, Step]);
        let [a, b] = t.agents() else {
            panic!("two agents: {t:?}")
        };
        assert_eq!((a.steps, a.conflicts, a.waited, a.replans), (2, 1, 1, 0));
        assert_eq!(a.length, std::f64::consts::SQRT_2 + 1.0);
        assert_eq!((b.steps, b.conflicts, b.waited, b.replans), (1, 1, 0, 1));
        assert_eq!(b.length, 1.0);
        assert_eq!((t.conflicts(), t.waited(), t.replans()), (2, 1, 1));
    }

    #[test]
    fn a_request_held_round_after_round_is_one_conflict_and_every_held_round_a_wait() {
        let mut t = Tally::new([0], 10);
        let reserved = held(0, Verdict::Hold, ConflictKind::Reserved, 1);
        let counted: Vec<Counted> = [
            reserved,
            reserved,
            reserved,
            // Another cell asked: a new request.
            held(0, Verdict::Hold, ConflictKind::Reserved, 10),
            // The first cell again, refused this time: a new decision on it.
            held(0, Verdict::Block, ConflictKind::Reserved, 1),
            held(0, Verdict::Block, ConflictKind::Reserved, 1),
            // Held with no conflict to name (lacam, settling for a plan): waits only.
            held(0, Verdict::Hold, ConflictKind::None, 1),
            held(0, Verdict::Hold, ConflictKind::None, 1),
            reserved,
        ]
        .iter()
        .map(|d| t.fold(d))
        .collect();
        use Counted::*;
        assert_eq!(
            counted,
            [
                Conflict, StillHeld, StillHeld, Conflict, Conflict, StillHeld, Waited, Waited,
                Conflict
            ]
        );
        // Held in rounds 1-4, 7-9; refused in 5-6.
        assert_eq!((t.conflicts(), t.waited()), (4, 7));
    }

    #[test]
    fn unknown_agents_and_verdicts_change_nothing() {
        let mut t = Tally::new([5], 0);
        let before = t.clone();
        t.fold(&decision(1, Verdict::Accept, 6));
        t.fold(&LoggedDecision {
            verdict: 200,
            ..decision(0, Verdict::Accept, 6)
        });
        assert_eq!(t, before);
        // Width 0 is read as 1: a column, where cell 6 lies one below cell 5.
        t.fold(&decision(0, Verdict::Accept, 6));
        assert_eq!(t.agents()[0].length, 1.0);
    }
}
