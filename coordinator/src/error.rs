//! The error type of the coordinator's planning and terrain code.
//!
//! Every problem a caller can cause with bad input (an endpoint outside the grid or on an
//! obstacle, a terrain layer of the wrong shape, an unknown planner name, nonsensical terrain
//! parameters) is a [`PlanError`]; the planners never panic on user input. "No path exists"
//! is not an error: planners answer `Ok(None)`.

use hnav_runtime::grid::{Cell, Endpoint};

/// Bad input to a planner, a hazard model or a query.
#[derive(Clone, PartialEq, Debug, thiserror::Error)]
pub enum PlanError {
    /// A start or goal cell lies outside the grid.
    #[error("{endpoint} {cell} is outside the {width}x{height} grid")]
    OutOfBounds {
        /// Which end.
        endpoint: Endpoint,
        /// The offending cell.
        cell: Cell,
        /// Grid width.
        width: u32,
        /// Grid height.
        height: u32,
    },
    /// A start or goal cell is blocked in the occupancy grid.
    #[error("{endpoint} {cell} is on a blocked cell")]
    Blocked {
        /// Which end.
        endpoint: Endpoint,
        /// The offending cell.
        cell: Cell,
    },
    /// A start or goal cell is free in the grid but impassable terrain (slope or relief over
    /// its limit) according to the planner's hazard model.
    #[error("{endpoint} {cell} is on impassable terrain")]
    Impassable {
        /// Which end.
        endpoint: Endpoint,
        /// The offending cell.
        cell: Cell,
    },
    /// A hazard map or height map does not have the grid's shape.
    #[error("terrain layer is {found_width}x{found_height} but the grid is {width}x{height}")]
    ShapeMismatch {
        /// Width of the layer.
        found_width: u32,
        /// Height of the layer.
        found_height: u32,
        /// Width of the grid.
        width: u32,
        /// Height of the grid.
        height: u32,
    },
    /// A terrain layer, height map or parameter set is unusable (wrong length, NaN, negative
    /// weight, a grid without an elevation layer...).
    #[error("bad terrain input: {problem}")]
    BadTerrain {
        /// What is wrong, in words.
        problem: String,
    },
    /// A planner name that `planner::PlannerKind` does not know.
    #[error("unknown planner {name:?} (expected astar, theta or lazy-theta)")]
    UnknownPlanner {
        /// The name as given.
        name: String,
    },
}
