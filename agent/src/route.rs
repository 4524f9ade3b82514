//! Route planners: the seeds' planners that answer a query with a whole route (seed 003's
//! particle swarm, seed 004's genetic algorithm) rather than a field to climb.
//!
//! An agent driven by one of them follows the route cell by cell under the same decision round
//! as a neural-map agent (the coordinator's masks, blocks and replans apply unchanged), so a
//! mixed swarm shares one coordinator, one set of conflict rules and one consensus log.
//! The trait is deliberately small: a planner sees only the grid as the agent knows it.

use hnav_runtime::grid::{Cell, Grid};

use crate::error::Error;

/// A planner that answers a start-goal query with a route.
pub trait RoutePlanner {
    /// A short stable name, e.g. `"pso"`; the scenario's `planner` value.
    fn name(&self) -> &'static str;

    /// A route from `start` to `goal` over `grid` (walls, plus the robots the agent has learned
    /// as obstacles): both ends included, consecutive cells 8-neighbours that respect the
    /// grid's corner rule. `Ok(None)` when the planner fails to connect them (for a swarm
    /// planner, a trace with gaps counts as a failure); an error for an unusable endpoint.
    fn route(&mut self, grid: &Grid, start: Cell, goal: Cell) -> Result<Option<Vec<Cell>>, Error>;
}
