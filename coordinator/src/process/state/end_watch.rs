//! When the run is over ([`EndWatch`]): every agent at its goal, or settled (at its goal,
//! confirmed unable to reach it, or lost), or in lockstep the round of the time limit. A
//! lifelong run (`[tasks]`) ends only by the time limit.

use hnav_runtime::consensus_log::EndReason;
use hnav_runtime::grid::{reachable_from, Cell, CornerCutting, Grid};
use hnav_runtime::msg::Progress;
use hnav_runtime::scenario::{ClockMode, Scenario};

use super::roster::Roster;
use crate::round::Arbiter;

/// What ends the run, and whether it has ended.
pub(super) struct EndWatch {
    /// Why the run ended, once the log holds its end.
    end: Option<EndReason>,
    /// In lockstep, the round after which the time limit ends the run.
    round_limit: Option<u64>,
    /// Per agent: `None` until it first reports its goal unreachable, then whether the walls
    /// confirm it. An agent stays in its connected part of the map, so one check is enough.
    unreachable: Vec<Option<bool>>,
    /// The map's walls, for confirming an agent's report of an unreachable goal.
    walls: Grid,
    corners: CornerCutting,
    goals: Vec<Cell>,
    /// A lifelong run (`[tasks]`): only time ends it.
    lifelong: bool,
}

impl EndWatch {
    /// A run of `scenario` that has not ended.
    pub(super) fn new(scenario: &Scenario) -> Self {
        EndWatch {
            end: None,
            round_limit: (scenario.sim.clock == ClockMode::Lockstep)
                .then(|| scenario.sim.rounds_in(scenario.coordinator.time_limit_s)),
            unreachable: vec![None; scenario.agents.len()],
            walls: scenario.map.grid.clone(),
            corners: scenario.map.corner_cutting,
            goals: scenario.agents.iter().map(|a| a.goal).collect(),
            lifelong: scenario.tasks.is_some(),
        }
    }

    /// Why the run ended, `None` while it goes on.
    pub(super) fn reason(&self) -> Option<EndReason> {
        self.end
    }

    /// The log holds the end of the run now.
    pub(super) fn ended(&mut self, reason: EndReason) {
        self.end = Some(reason);
    }

    /// The log holds agent `i`'s goal as unreachable (a replayed record).
    pub(super) fn logged_unreachable(&mut self, i: u32) {
        if let Some(r) = self.unreachable.get_mut(i as usize) {
            *r = Some(true);
        }
    }

    /// Agent `i`, standing on cell index `current`, reports its goal unreachable; returns
    /// whether that is to be logged now: the first report of the agent, and the walls
    /// confirm it. A report the walls do not confirm (the agent's map counts robots it was
    /// blocked by as obstacles, and robots move on) is not logged: the agent stands still as
    /// it asked and is asked again later.
    pub(super) fn confirm_unreachable(&mut self, i: usize, current: u32) -> bool {
        if self.unreachable[i].is_some() || self.walls.cell_at(current as usize).is_none() {
            return false;
        }
        let reach = reachable_from(&self.walls, self.goals[i], self.corners);
        let unreachable = !reach[current as usize];
        self.unreachable[i] = Some(unreachable);
        unreachable
    }

    /// Why the run is over after `round` (committed), if it is: checked in this order, so
    /// that all at the goal wins over a loss, and both over the time limit. The limit is
    /// counted in rounds of simulated time, so that a lockstep run ends at the same record
    /// whatever the wall clock says.
    pub(super) fn due(&self, round: u64, arbiter: &Arbiter, roster: &Roster) -> Option<EndReason> {
        if self.end.is_some() || round == 0 {
            return None;
        }
        if self.lifelong {
            // Goals keep coming: all at goal is a moment, not the end.
            return self
                .round_limit
                .is_some_and(|limit| round >= limit)
                .then_some(EndReason::TimeLimit);
        }
        let settled = || {
            (0..arbiter.agents()).all(|i| {
                arbiter.agent_at_goal(i) || self.unreachable[i] == Some(true) || roster.lost(i)
            })
        };
        if roster.at_goal(arbiter) as usize == arbiter.agents() {
            Some(EndReason::AllAtGoal)
        } else if settled() && roster.any_lost() {
            Some(EndReason::AllAtGoalOrLost)
        } else if settled() {
            Some(EndReason::AllAtGoalOrUnreachable)
        } else if self.round_limit.is_some_and(|limit| round >= limit) {
            Some(EndReason::TimeLimit)
        } else {
            None
        }
    }

    /// The progress topic's `done`: what it says of the end.
    pub(super) fn done(&self) -> u8 {
        match self.end {
            // Nothing is left to decide for the unreachable ones either.
            Some(
                EndReason::AllAtGoal
                | EndReason::AllAtGoalOrUnreachable
                | EndReason::AllAtGoalOrLost,
            ) => Progress::ALL_AT_GOAL,
            Some(EndReason::TimeLimit) => Progress::TIME_LIMIT,
            Some(EndReason::Stopped) | None => 0,
        }
    }
}
