//! [`Tally`]: what a run's decisions add up to, per agent — accepted moves and their octile
//! length, refused or held requests, global replans.
//!
//! The coordinator's arbiter folds every decision it publishes, the coordinator rebuilds the
//! same numbers from the log after a restart, and the run summary reads them from the log
//! when the run is over; all three fold the decisions in log order through [`Tally::fold`],
//! so they agree (the lengths are sums of floats, and the same order gives the same bits).

use super::record::{LoggedDecision, RoundRecord, RunHeader};
use crate::msg::Verdict;

/// One agent's share of a [`Tally`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AgentTally {
    /// Accepted moves.
    pub steps: u32,
    /// Length of the accepted moves in cells (straight 1, diagonal sqrt 2).
    pub length: f64,
    /// Refused or held requests ([`Verdict::Block`], [`Verdict::Hold`]).
    pub conflicts: u32,
    /// Global replans ([`Verdict::Replan`]).
    pub replans: u32,
}

/// Per-agent [`AgentTally`]s of a run's decisions; see the [module docs](self).
///
/// It keeps each agent's cell (its start, then the cell of its last accepted move) to measure
/// the next move. Folding allocates nothing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tally {
    agents: Vec<AgentTally>,
    cells: Vec<u32>,
    width: u32,
}

impl Tally {
    /// A tally of agents starting on the row-major cells `starts` of a grid `width` cells
    /// wide (a width of 0 counts as 1).
    pub fn new(starts: impl IntoIterator<Item = u32>, width: u32) -> Self {
        let cells: Vec<u32> = starts.into_iter().collect();
        Self {
            agents: vec![AgentTally::default(); cells.len()],
            cells,
            width: width.max(1),
        }
    }

    /// A tally of the run a log's header describes.
    pub fn from_header(header: &RunHeader) -> Self {
        Self::new(header.agents.iter().map(|a| a.start), header.width)
    }

    /// Adds one decision. A decision for an agent the tally does not know, or with an
    /// unknown verdict, changes nothing (a damaged log must not stop a summary).
    pub fn fold(&mut self, d: &LoggedDecision) {
        let i = d.agent as usize;
        let (Some(a), Some(cell)) = (self.agents.get_mut(i), self.cells.get_mut(i)) else {
            return;
        };
        match Verdict::from_u8(d.verdict) {
            Some(Verdict::Accept) => {
                a.steps = a.steps.saturating_add(1);
                a.length += step_length(*cell, d.cell, self.width);
                *cell = d.cell;
            }
            Some(Verdict::Block | Verdict::Hold) => a.conflicts = a.conflicts.saturating_add(1),
            Some(Verdict::Replan) => a.replans = a.replans.saturating_add(1),
            None => {}
        }
    }

    /// Adds every decision of a logged round, in order.
    pub fn fold_round(&mut self, round: &RoundRecord) {
        for d in &round.decisions {
            self.fold(d);
        }
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
        LoggedDecision {
            agent,
            verdict: verdict as u8,
            refused: 0,
            kind: 0,
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
        for d in [
            decision(0, Verdict::Accept, 11),
            decision(0, Verdict::Hold, NO_CELL),
            decision(0, Verdict::Accept, 12),
            decision(1, Verdict::Block, 8),
            decision(1, Verdict::Replan, NO_CELL),
            decision(1, Verdict::Accept, 19),
        ] {
            t.fold(&d);
        }
        let [a, b] = t.agents() else {
            panic!("two agents: {t:?}")
        };
        assert_eq!((a.steps, a.conflicts, a.replans), (2, 1, 0));
        assert_eq!(a.length, std::f64::consts::SQRT_2 + 1.0);
        assert_eq!((b.steps, b.conflicts, b.replans), (1, 1, 1));
        assert_eq!(b.length, 1.0);
        assert_eq!((t.conflicts(), t.replans()), (2, 1));
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
