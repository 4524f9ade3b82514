//! The seeds' guide: a whole route from a [`RoutePlanner`] (seed 003's swarm, seed 004's
//! GA), followed cell by cell (`planner = "pso"` or `"ga-fuzzy"`).
//!
//! The route is planned over the grid as the agent knows it (walls and the robots it has
//! learned as obstacles) from the robot's cell to the target, and again whenever the robot
//! leaves it (a PIBT push), a learned obstacle cuts it, or the target changes (a waypoint
//! of the coordinator's replan, then the goal). A refused step is asked for again: the
//! coordinator decides who waits, and replans a robot refused too long, as for every agent.
//! A query that fails (the swarm trapped, a trace with gaps, the GA out of generations) is
//! reported as a local extremum, which is what makes the coordinator replan it in hybrid mode;
//! the next round queries again (a swarm's random stream has moved on by then).

use hnav_runtime::grid::{Cell, CornerCutting, Direction, Grid};

use super::Proposal;
use crate::route::RoutePlanner;

/// The planner, its current route and where the robot is on it.
pub(super) struct Follow {
    planner: Box<dyn RoutePlanner + Send>,
    corner_cutting: CornerCutting,
    route: Vec<Cell>,
    /// Index of the robot's cell in `route` (meaningful when `route` is not empty).
    at: usize,
}

impl Follow {
    /// A route of `planner` over `grid` from `from` to `target` (none yet if the first query
    /// fails: the first proposal asks again).
    pub(super) fn new(
        planner: Box<dyn RoutePlanner + Send>,
        corner_cutting: CornerCutting,
        grid: &Grid,
        from: Cell,
        target: Cell,
    ) -> Follow {
        let mut f = Follow {
            planner,
            corner_cutting,
            route: Vec::new(),
            at: 0,
        };
        f.plan(grid, from, target);
        f
    }

    /// The planner's name (`"pso"`, `"ga-fuzzy"`).
    pub(super) fn name(&self) -> &'static str {
        self.planner.name()
    }

    /// The remaining route, the robot's cell first (empty while no query has succeeded).
    pub(super) fn remaining(&self) -> &[Cell] {
        self.route.get(self.at..).unwrap_or(&[])
    }

    /// Queries the planner; returns whether a route was found. An endpoint the planner
    /// refuses (a target that became an obstacle) counts as a failed query, not as the end
    /// of the agent: the coordinator will replan it elsewhere.
    pub(super) fn plan(&mut self, grid: &Grid, from: Cell, target: Cell) -> bool {
        self.route.clear();
        self.at = 0;
        let found = match self.planner.route(grid, from, target) {
            Ok(Some(r)) if r.first() == Some(&from) && r.last() == Some(&target) => Some(r),
            Ok(_) => None,
            Err(e) => {
                tracing::warn!(planner = self.planner.name(), "route query refused: {e}");
                None
            }
        };
        match found {
            Some(r) => {
                self.route = r;
                true
            }
            None => false,
        }
    }

    /// The next route cell from `current`, planning first if the robot is off the route or
    /// the route is cut; the flag says whether a new route was planned (a snapshot is due).
    pub(super) fn propose(&mut self, grid: &Grid, current: Cell, target: Cell) -> (Proposal, bool) {
        if let Some(c) = self.next_step(grid, current) {
            return (Proposal::Step(c), false);
        }
        if !self.plan(grid, current, target) {
            return (Proposal::Extremum, true);
        }
        let p = self
            .next_step(grid, current)
            .map_or(Proposal::Extremum, Proposal::Step);
        (p, true)
    }

    /// The route cell after `current`, if the robot is on the route and that cell is still
    /// free and one legal move away.
    fn next_step(&mut self, grid: &Grid, current: Cell) -> Option<Cell> {
        if self.route.get(self.at) != Some(&current) {
            self.at = self.route.iter().position(|&c| c == current)?;
        }
        let next = *self.route.get(self.at + 1)?;
        let dir = Direction::between(current, next)?;
        grid.can_move(current, dir, self.corner_cutting)
            .then_some(next)
    }

    /// Whether the remaining route runs through `cell`.
    pub(super) fn crosses(&self, cell: Cell) -> bool {
        self.remaining().contains(&cell)
    }

    /// Writes the remaining route into `out`: cell `k` steps before the target gets
    /// `1 / (1 + k)`, every other cell keeps the 0 it has.
    pub(super) fn write(&self, grid: &Grid, out: &mut [f32]) {
        let rest = self.remaining();
        for (k, &c) in rest.iter().rev().enumerate() {
            if let Some(v) = out.get_mut(grid.index(c)) {
                *v = 1.0 / (1.0 + k as f32);
            }
        }
    }
}
