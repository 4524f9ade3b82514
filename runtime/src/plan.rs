//! The answer to one start-goal planning query, whichever planner gave it: the agent's neural
//! map (`hnav_agent::plan`) or one of the coordinator's global planners
//! (`hnav_coordinator::planner::run_query`).
//!
//! One type, so that `hnav-bench plan` prints every planner's answer the same way: a
//! [`PlanResult`] serialises to exactly the bench's JSON line, `planner`, `found`, `steps`,
//! `length`, `iterations`, `path` (a list of `[x, y]`) and `time_us`, then `los_checks` and
//! `optimal` where they apply.
//!
//! ```
//! use hnav_runtime::grid::Cell;
//! use hnav_runtime::plan::PlanResult;
//! let r = PlanResult {
//!     planner: "astar".into(),
//!     found: true,
//!     steps: 1,
//!     length: 1.0,
//!     iterations: 2,
//!     path: vec![Cell::new(0, 0), Cell::new(1, 0)],
//!     time_us: 3.5,
//!     los_checks: None,
//!     optimal: None,
//! };
//! let json = serde_json::to_string(&r).unwrap();
//! assert_eq!(
//!     json,
//!     r#"{"planner":"astar","found":true,"steps":1,"length":1.0,"iterations":2,"path":[[0,0],[1,0]],"time_us":3.5}"#
//! );
//! ```

use serde::{Deserialize, Serialize};

use crate::grid::Cell;

/// The answer to one query.
#[derive(Clone, PartialEq, Debug, Serialize, Deserialize)]
pub struct PlanResult {
    /// The planner's name: `"hnav"` (the neural map), `"astar"`, `"theta"`, `"lazy-theta"`.
    pub planner: String,
    /// Whether the path reaches the goal.
    pub found: bool,
    /// Moves (grid planners) or segments (any-angle planners) of the path, 0 when not found.
    pub steps: usize,
    /// Path length in cell units (straight 1, diagonal `sqrt 2`; any-angle planners:
    /// Euclidean), 0 when not found.
    pub length: f64,
    /// The planner's iterations: neural-map sweeps, or node expansions.
    pub iterations: u64,
    /// Cells (waypoints for any-angle planners) from start to goal, empty when not found.
    pub path: Vec<Cell>,
    /// Wall time of the query in microseconds.
    pub time_us: f64,
    /// Line-of-sight checks, for planners that made any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub los_checks: Option<u64>,
    /// The reference length the query is judged against, when it has one (a MovingAI
    /// `.scen` entry's optimal length); planners leave it `None`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub optimal: Option<f64>,
}
