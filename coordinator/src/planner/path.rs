//! Planned paths and their validity.

use hnav_runtime::grid::{Cell, CornerCutting, Grid};
use serde::{Deserialize, Serialize};

use crate::line_of_sight::walk;
use crate::terrain::HazardMap;

/// A planned path: the cells from start to goal and the polyline length through their
/// centres, in cell units.
///
/// For A* (and the neural map) consecutive cells are 8-neighbours; for the any-angle planners
/// they are waypoints joined by straight segments with line of sight. A path from a cell to
/// itself is that one cell, of length 0.
#[derive(Clone, PartialEq, Debug, Serialize, Deserialize)]
pub struct Path {
    /// Start first, goal last.
    pub cells: Vec<Cell>,
    /// Sum of the Euclidean distances between consecutive cells.
    pub length: f64,
}

impl Path {
    /// Number of moves (A*) or segments (any-angle): `cells.len() - 1`, 0 for an empty path.
    pub fn steps(&self) -> usize {
        self.cells.len().saturating_sub(1)
    }
}

/// Why [`check_path`] rejects a path.
#[derive(Clone, Copy, PartialEq, Debug, thiserror::Error)]
pub enum PathDefect {
    /// The path has no cells.
    #[error("the path is empty")]
    Empty,
    /// The first cell is not the start or the last is not the goal.
    #[error("the path does not run from {start} to {goal}")]
    WrongEnds {
        /// The expected start.
        start: Cell,
        /// The expected goal.
        goal: Cell,
    },
    /// A waypoint is outside the grid, blocked, or impassable terrain.
    #[error("waypoint {0} is outside, blocked or impassable")]
    BadWaypoint(Cell),
    /// Two consecutive waypoints do not see each other.
    #[error("no line of sight from {0} to {1}")]
    NoLineOfSight(Cell, Cell),
}

/// Checks that `cells` runs from `start` to `goal`, that no waypoint is outside, blocked or
/// (with a hazard map) impassable, and that each pair of consecutive waypoints has line of
/// sight under `rule` over the same obstacles (see [`mod@crate::line_of_sight`]).
/// A*'s paths pass too: every legal move has line of sight, except a diagonal squeeze
/// between two blocked cells, which only A* with corners allowed can produce.
pub fn check_path(
    grid: &Grid,
    hazard: Option<&HazardMap>,
    rule: CornerCutting,
    cells: &[Cell],
    start: Cell,
    goal: Cell,
) -> Result<(), PathDefect> {
    let (Some(&first), Some(&last)) = (cells.first(), cells.last()) else {
        return Err(PathDefect::Empty);
    };
    if first != start || last != goal {
        return Err(PathDefect::WrongEnds { start, goal });
    }
    let hazard = hazard.filter(|h| (h.width(), h.height()) == (grid.width(), grid.height()));
    let obstacle = |i: usize| grid.blocked()[i] || hazard.is_some_and(|h| h.impassable()[i]);
    for &c in cells {
        if !grid.contains(c) || obstacle(grid.index(c)) {
            return Err(PathDefect::BadWaypoint(c));
        }
    }
    for w in cells.windows(2) {
        if !walk::<false>(
            grid.width() as usize,
            w[0],
            w[1],
            rule,
            obstacle,
            |_, _, _| {},
        ) {
            return Err(PathDefect::NoLineOfSight(w[0], w[1]));
        }
    }
    Ok(())
}

/// Heading changes of a polyline: how many times the direction changes, and the sum of the
/// absolute turn angles in degrees. Collinear waypoints do not count.
pub fn heading_changes(cells: &[Cell]) -> (usize, f64) {
    let mut count = 0;
    let mut total = 0.0;
    for w in cells.windows(3) {
        let d1 = (
            f64::from(w[1].x) - f64::from(w[0].x),
            f64::from(w[1].y) - f64::from(w[0].y),
        );
        let d2 = (
            f64::from(w[2].x) - f64::from(w[1].x),
            f64::from(w[2].y) - f64::from(w[1].y),
        );
        let cross = d1.0 * d2.1 - d1.1 * d2.0;
        let dot = d1.0 * d2.0 + d1.1 * d2.1;
        let angle = cross.atan2(dot).abs();
        if angle > 1e-9 {
            count += 1;
            total += angle.to_degrees();
        }
    }
    (count, total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::grid::read_map_rows;

    #[test]
    fn defects_are_named() {
        let g = read_map_rows([(1, "..."), (2, ".@."), (3, "...")], "<t>").unwrap();
        let (s, t) = (Cell::new(0, 0), Cell::new(2, 2));
        let rule = CornerCutting::Forbidden;
        assert_eq!(
            check_path(&g, None, rule, &[], s, t),
            Err(PathDefect::Empty)
        );
        assert_eq!(
            check_path(&g, None, rule, &[s, t], s, t),
            Err(PathDefect::NoLineOfSight(s, t))
        );
        assert_eq!(
            check_path(&g, None, rule, &[s, Cell::new(1, 1), t], s, t),
            Err(PathDefect::BadWaypoint(Cell::new(1, 1)))
        );
        assert_eq!(
            check_path(&g, None, rule, &[s, Cell::new(2, 0), t], s, t),
            Ok(())
        );
        assert!(matches!(
            check_path(&g, None, rule, &[t, s], s, t),
            Err(PathDefect::WrongEnds { .. })
        ));
    }

    #[test]
    fn turns() {
        let c = |x, y| Cell::new(x, y);
        assert_eq!(heading_changes(&[c(0, 0), c(1, 1), c(2, 2)]), (0, 0.0));
        let (n, deg) = heading_changes(&[c(0, 0), c(2, 0), c(2, 3), c(0, 3)]);
        assert_eq!(n, 2);
        assert!((deg - 180.0).abs() < 1e-9);
        assert_eq!(heading_changes(&[c(0, 0)]), (0, 0.0));
    }
}
