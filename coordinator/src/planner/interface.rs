//! What every global planner is to its callers: the [`Planner`] trait, its options and its
//! work counters.

use std::sync::Arc;

use hnav_runtime::grid::{Cell, CornerCutting, Grid};
use serde::{Deserialize, Serialize};

use super::path::Path;
use crate::error::PlanError;
use crate::terrain::HazardMap;

/// A single-agent global planner over an occupancy grid.
///
/// Implementations keep whatever state makes repeated queries cheap; `plan` takes `&mut self`
/// for that reason. The trait knows nothing about how a planner works inside, so the agent's
/// neural map can implement it too.
pub trait Planner {
    /// A short stable name, e.g. `"astar"`; the `planner` field of a query's
    /// [`PlanResult`](hnav_runtime::plan::PlanResult).
    fn name(&self) -> &'static str;

    /// A path from `start` to `goal`, `Ok(None)` if the goal is unreachable, or an error if an
    /// endpoint is unusable (outside the grid, blocked or impassable).
    fn plan(&mut self, grid: &Grid, start: Cell, goal: Cell) -> Result<Option<Path>, PlanError>;

    /// Counters of the last call of [`Planner::plan`] (all zero before the first).
    fn stats(&self) -> PlanStats;
}

/// Work counters of one query.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default, Serialize, Deserialize)]
pub struct PlanStats {
    /// Nodes taken from the open list and expanded (the goal counts when it is taken).
    pub expansions: u64,
    /// Pushes onto the open list: a newly reached node or a better `g` for a known one.
    pub generated: u64,
    /// Line-of-sight checks (each one a cell walk of a segment). Always 0 for A*.
    pub los_checks: u64,
}

/// What the grid planners of this module are configured with.
#[derive(Clone, Debug, Default)]
pub struct PlannerConfig {
    /// Whether diagonals may pass a blocked corner. Default: forbidden (MovingAI's rule).
    pub corner_cutting: CornerCutting,
    /// Terrain hazard to add to the cost and impassable cells to avoid; `None` plans on
    /// length alone (the seed-002 Table 3.1 mode). Shared, because one hazard map usually
    /// serves every planner and query of a run.
    pub hazard: Option<Arc<HazardMap>>,
}

impl PlannerConfig {
    /// A config with the given corner rule and no hazard.
    pub fn new(corner_cutting: CornerCutting) -> Self {
        PlannerConfig {
            corner_cutting,
            hazard: None,
        }
    }

    /// The same config with a hazard model.
    pub fn with_hazard(mut self, hazard: Arc<HazardMap>) -> Self {
        self.hazard = Some(hazard);
        self
    }
}
