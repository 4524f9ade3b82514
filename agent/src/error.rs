//! The crate's error type: bad inputs, never internal failures.
//!
//! Every public function that takes a cell or an option validates it and returns an [`Error`]
//! instead of panicking. An unreachable goal is *not* an error: it is a normal outcome
//! ([`crate::neural_map::Outcome::Unreachable`], `found: false` in a plan).

use std::fmt;

use hnav_runtime::grid::Cell;

/// What a rejected cell was meant to be.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Role {
    /// The robot's start (or current) cell.
    Start,
    /// The goal cell of a plan.
    Goal,
    /// The target (activation point) of a neural map.
    Target,
    /// A cell handed in as a new obstacle.
    Obstacle,
}

impl fmt::Display for Role {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Role::Start => "start",
            Role::Goal => "goal",
            Role::Target => "target",
            Role::Obstacle => "obstacle",
        })
    }
}

/// Bad input to the neural map, the path constructor or the planner.
#[derive(Clone, PartialEq, Debug, thiserror::Error)]
pub enum Error {
    /// A cell lies outside the grid.
    #[error("{role} {cell} is outside the {width} x {height} grid")]
    OutOfBounds {
        /// What the cell was for.
        role: Role,
        /// The offending cell.
        cell: Cell,
        /// Grid width.
        width: u32,
        /// Grid height.
        height: u32,
    },
    /// A start, goal or target lies on an obstacle.
    #[error("{role} {cell} is on an obstacle")]
    Blocked {
        /// What the cell was for.
        role: Role,
        /// The offending cell.
        cell: Cell,
    },
    /// An option is out of its domain (a weight that is not positive, a NaN tolerance...).
    #[error("invalid option `{name}`: {problem}")]
    InvalidOption {
        /// The option's field name.
        name: &'static str,
        /// What is wrong with it.
        problem: String,
    },
    /// A dense weight matrix was requested for too many neurons.
    #[error("a dense weight matrix of {cells} neurons is too large (at most {max})")]
    TooLarge {
        /// Neurons requested.
        cells: usize,
        /// The limit.
        max: usize,
    },
}

impl Error {
    /// Shorthand for [`Error::InvalidOption`].
    pub(crate) fn option(name: &'static str, problem: impl Into<String>) -> Error {
        Error::InvalidOption {
            name,
            problem: problem.into(),
        }
    }
}

/// Checks that `cell` is inside a `width x height` grid.
pub(crate) fn check_inside(cell: Cell, role: Role, width: u32, height: u32) -> Result<(), Error> {
    if cell.x < width && cell.y < height {
        Ok(())
    } else {
        Err(Error::OutOfBounds {
            role,
            cell,
            width,
            height,
        })
    }
}
