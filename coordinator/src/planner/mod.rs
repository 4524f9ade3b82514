//! Global planners: A*, Basic Theta* and Lazy Theta* behind one [`Planner`] trait.
//!
//! | module | concept |
//! |---|---|
//! | `interface`: [`Planner`], [`PlannerConfig`], [`PlanStats`] | the trait every global planner implements, its options and counters |
//! | [`path`] | [`Path`] (cells + length) and [`check_path`], the validity test for any-angle paths |
//! | [`astar`] | [`AStar`]: octile A*, the coordinator's exact grid planner |
//! | [`theta`] | [`BasicTheta`]: Basic Theta* (Nash, Daniel, Koenig & Felner 2007), eager line of sight |
//! | [`lazy_theta`] | [`LazyTheta`]: Lazy Theta* (Nash, Koenig & Tovey 2010), one line-of-sight check per expansion |
//! | [`query`] | [`PlannerKind`] and [`run_query`], answering with the runtime's [`PlanResult`](hnav_runtime::plan::PlanResult), the JSON line of `hnav-bench plan` |
//! | `open_list`, `search`, `space` (private) | the reusable open list, per-node buffers with generation stamps, and the grid as the planners see it |
//!
//! # Conventions shared by every planner
//!
//! * Vertices are cell centres; lengths are in cell units (metres when the cell size is 1 m).
//!   A* moves between 8-neighbours (1 straight, `sqrt 2` diagonal); the Theta* variants join
//!   any two cells with line of sight by a straight segment.
//! * [`CornerCutting`] decides whether a diagonal may pass a blocked corner (see
//!   [`mod@crate::line_of_sight`] for the exact rule for long segments). The any-angle planners never
//!   squeeze between two diagonally touching blocked cells, even when corners may be cut.
//! * With a [`HazardMap`] in the config, cells of infinite hazard are obstacles and every
//!   segment `a -> b` costs its length plus `weight * (R(a)/2 + R(b)/2 + sum alpha * R)` over
//!   the cells it crosses in between (seed 002 eq. 3.1-3.2, see [`crate::terrain`]). Without
//!   one, cost is length.
//! * A bad start or goal (outside, blocked, impassable) is a [`PlanError`]; an unreachable
//!   goal is `Ok(None)`; `start == goal` is a one-cell path of length 0.
//! * A planner keeps its buffers between queries: a query allocates only its answer (and
//!   grows the buffers when the grid is larger than any before).
//!
//! [`CornerCutting`]: hnav_runtime::grid::CornerCutting
//! [`HazardMap`]: crate::terrain::HazardMap
//! [`PlanError`]: crate::error::PlanError

pub mod astar;
mod interface;
pub mod lazy_theta;
mod open_list;
pub mod path;
pub mod query;
mod search;
mod space;
pub mod theta;

pub use crate::line_of_sight::{euclid, line_of_sight, segment_chords};
pub use astar::AStar;
pub use interface::{PlanStats, Planner, PlannerConfig};
pub use lazy_theta::LazyTheta;
pub use path::{check_path, heading_changes, Path, PathDefect};
pub use query::{run_query, run_query_with, PlannerKind};
pub use theta::BasicTheta;
