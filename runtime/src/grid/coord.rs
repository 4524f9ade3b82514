//! Grid coordinates.
//!
//! HNAV uses the MovingAI convention everywhere: `x` is the column, `y` the row, the origin is
//! the top-left corner and `y` grows downwards (so "north" is `y - 1`). The dissertation numbers
//! cells `1..=W*H` row by row from the top-left; [`crate::grid::Grid::cell_id`] and
//! [`crate::grid::Grid::cell_from_id`] convert between the two.

use std::cmp::Ordering;
use std::fmt;

/// One grid cell, `x` = column and `y` = row, origin top-left.
///
/// Cells order row-major (by `y`, then `x`), the same order as grid indices and the
/// dissertation's cell ids, so sorting cells sorts them the way the map is printed.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct Cell {
    /// Column, 0-based from the left.
    pub x: u32,
    /// Row, 0-based from the top.
    pub y: u32,
}

impl Cell {
    /// The cell at column `x`, row `y`.
    pub const fn new(x: u32, y: u32) -> Self {
        Cell { x, y }
    }

    /// The cell `(x + dx, y + dy)`, or `None` if a coordinate would leave `0..=u32::MAX`.
    ///
    /// This knows nothing about a grid's size; use [`crate::grid::Grid::step`] for that.
    pub fn offset(self, dx: i32, dy: i32) -> Option<Cell> {
        let x = self.x.checked_add_signed(dx)?;
        let y = self.y.checked_add_signed(dy)?;
        Some(Cell { x, y })
    }

    /// Octile distance to `other`; see [`octile`].
    pub fn octile(self, other: Cell) -> f64 {
        octile(self, other)
    }
}

impl Ord for Cell {
    fn cmp(&self, other: &Self) -> Ordering {
        (self.y, self.x).cmp(&(other.y, other.x))
    }
}

impl PartialOrd for Cell {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl fmt::Display for Cell {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "[{}, {}]", self.x, self.y)
    }
}

impl From<(u32, u32)> for Cell {
    fn from((x, y): (u32, u32)) -> Self {
        Cell { x, y }
    }
}

/// Octile distance between two cells: `max(dx,dy) - min(dx,dy) + sqrt(2) * min(dx,dy)`.
///
/// This is the length of the shortest 8-connected path on an empty grid (straight moves cost 1,
/// diagonal moves `sqrt 2`), hence an admissible and consistent A* heuristic for octile moves.
pub fn octile(a: Cell, b: Cell) -> f64 {
    let dx = f64::from(a.x.abs_diff(b.x));
    let dy = f64::from(a.y.abs_diff(b.y));
    let (lo, hi) = if dx < dy { (dx, dy) } else { (dy, dx) };
    (hi - lo) + std::f64::consts::SQRT_2 * lo
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn octile_examples() {
        assert_eq!(octile(Cell::new(0, 0), Cell::new(0, 0)), 0.0);
        assert_eq!(octile(Cell::new(0, 0), Cell::new(5, 0)), 5.0);
        assert!((octile(Cell::new(0, 0), Cell::new(2, 2)) - 2.0 * 2f64.sqrt()).abs() < 1e-12);
        // 10 straight + 2 diagonal moves.
        let d = octile(Cell::new(17, 21), Cell::new(5, 19));
        assert!((d - 12.828_427_12).abs() < 1e-8, "{d}");
        assert_eq!(
            octile(Cell::new(3, 9), Cell::new(7, 1)),
            octile(Cell::new(7, 1), Cell::new(3, 9))
        );
    }

    #[test]
    fn cells_order_row_major() {
        let mut v = vec![Cell::new(1, 1), Cell::new(5, 0), Cell::new(0, 1)];
        v.sort();
        assert_eq!(v, vec![Cell::new(5, 0), Cell::new(0, 1), Cell::new(1, 1)]);
    }

    #[test]
    fn offset_is_checked() {
        assert_eq!(Cell::new(0, 0).offset(-1, 0), None);
        assert_eq!(Cell::new(0, 3).offset(1, -1), Some(Cell::new(1, 2)));
        assert_eq!(Cell::new(u32::MAX, 0).offset(1, 0), None);
        assert_eq!(Cell::new(2, 3).to_string(), "[2, 3]");
    }
}

/// A cell travels in JSON and other serde formats as `[x, y]`, the shape MovingAI tools and
/// the bench's `path` field use.
impl serde::Serialize for Cell {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        [self.x, self.y].serialize(s)
    }
}

impl<'de> serde::Deserialize<'de> for Cell {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Cell, D::Error> {
        let [x, y] = <[u32; 2]>::deserialize(d)?;
        Ok(Cell { x, y })
    }
}

#[cfg(test)]
mod serde_tests {
    use super::Cell;

    #[test]
    fn cells_serialise_as_pairs() {
        let cells = vec![Cell { x: 1, y: 2 }, Cell { x: 30, y: 4 }];
        let text = serde_json::to_string(&cells).unwrap();
        assert_eq!(text, "[[1,2],[30,4]]");
        let back: Vec<Cell> = serde_json::from_str(&text).unwrap();
        assert_eq!(back, cells);
        assert!(serde_json::from_str::<Cell>("[1]").is_err());
    }
}
