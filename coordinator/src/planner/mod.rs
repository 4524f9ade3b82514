//! Global planners: A*, Basic Theta* and Lazy Theta* behind one [`Planner`] trait.
//!
//! | module | concept |
//! |---|---|
//! | [`Planner`], [`PlannerConfig`], [`PlanStats`] (here) | the trait every global planner implements, its options and counters |
//! | [`path`] | [`Path`] (cells + length) and [`check_path`], the validity test for any-angle paths |
//! | [`astar`] | [`AStar`]: octile A*, the coordinator's exact grid planner |
//! | [`theta`] | [`BasicTheta`]: Basic Theta* (Nash, Daniel, Koenig & Felner 2007), eager line of sight |
//! | [`lazy_theta`] | [`LazyTheta`]: Lazy Theta* (Nash, Koenig & Tovey 2010), one line-of-sight check per expansion |
//! | [`mod@line_of_sight`] | [`line_of_sight()`](fn@line_of_sight) and the exact cell walk behind it |
//! | [`query`] | [`PlannerKind`] and [`run_query`], answering with the runtime's [`PlanResult`](hnav_runtime::plan::PlanResult), the JSON line of `hnav-bench plan` |
//! | `open_list`, `search`, `space` (private) | the reusable open list, per-node buffers with generation stamps, and the grid as the planners see it |
//!
//! # Conventions shared by every planner
//!
//! * Vertices are cell centres; lengths are in cell units (metres when the cell size is 1 m).
//!   A* moves between 8-neighbours (1 straight, `sqrt 2` diagonal); the Theta* variants join
//!   any two cells with line of sight by a straight segment.
//! * [`CornerCutting`] decides whether a diagonal may pass a blocked corner (see
//!   [`mod@line_of_sight`] for the exact rule for long segments). The any-angle planners never
//!   squeeze between two diagonally touching blocked cells, even when corners may be cut.
//! * With a [`HazardMap`] in the config, cells of infinite hazard are obstacles and every
//!   segment `a -> b` costs its length plus `weight * (R(a)/2 + R(b)/2 + sum alpha * R)` over
//!   the cells it crosses in between (seed 002 eq. 3.1-3.2, see [`crate::terrain`]). Without
//!   one, cost is length.
//! * A bad start or goal (outside, blocked, impassable) is a [`PlanError`]; an unreachable
//!   goal is `Ok(None)`; `start == goal` is a one-cell path of length 0.
//! * A planner keeps its buffers between queries: a query allocates only its answer (and
//!   grows the buffers when the grid is larger than any before).

pub mod astar;
pub mod lazy_theta;
pub mod line_of_sight;
mod open_list;
pub mod path;
pub mod query;
mod search;
mod space;
pub mod theta;

use std::sync::Arc;

use hnav_runtime::grid::{Cell, CornerCutting, Grid};
use serde::{Deserialize, Serialize};

use crate::error::PlanError;
use crate::terrain::HazardMap;

pub use astar::AStar;
pub use lazy_theta::LazyTheta;
pub use line_of_sight::{euclid, line_of_sight, segment_chords};
pub use path::{check_path, heading_changes, Path, PathDefect};
pub use query::{run_query, run_query_with, PlannerKind};
pub use theta::BasicTheta;

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
