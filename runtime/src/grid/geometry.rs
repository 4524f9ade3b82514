//! Cell geometry every process shares: row-major indices, cell centres in metres, octile step
//! lengths and heading wrapping.
//!
//! These live once because processes must agree on them to the bit: the agent decides it has
//! arrived at the centre of `next` from the same numbers the sim uses to place the robot
//! there, and the lockstep consensus logs are compared byte for byte, so even the rounding
//! of each formula is part of the contract. Changing one changes the logs.
//!
//! ```
//! use hnav_runtime::grid::geometry::{cell_centre_m, cell_index, index_cell, octile_step_len};
//! use hnav_runtime::grid::Cell;
//! assert_eq!(cell_index(10, Cell::new(3, 2)), 23);
//! assert_eq!(index_cell(10, 23), Some(Cell::new(3, 2)));
//! assert_eq!(cell_centre_m(0.16, Cell::new(0, 1)), (0.08, 1.5 * 0.16));
//! assert_eq!(octile_step_len(Cell::new(1, 1), Cell::new(2, 2)), std::f64::consts::SQRT_2);
//! ```

use std::f64::consts::{PI, SQRT_2, TAU};

use super::coord::Cell;
use crate::msg::Pose;

/// Row-major index of `cell` on a grid `width` cells wide: `y * width + x`, MovingAI's order
/// and the one cells travel in on the wire (as `u32`).
///
/// Meaningful for cells inside the grid only; an outside cell maps to an unrelated number
/// (never a panic: every grid has fewer than 2^26 cells, so in-grid products cannot overflow).
#[inline]
pub fn cell_index(width: u32, cell: Cell) -> usize {
    cell.y as usize * width as usize + cell.x as usize
}

/// The cell at row-major `index` of a grid `width` cells wide, the inverse of [`cell_index`].
///
/// `None` for a width of 0 or a row beyond `u32`; whether the row exists is the grid's
/// business ([`crate::grid::Grid::cell_at`] checks it).
#[inline]
pub fn index_cell(width: u32, index: usize) -> Option<Cell> {
    let w = width as usize;
    if w == 0 {
        return None;
    }
    // index % w < w <= u32::MAX, so the column always fits.
    Some(Cell::new(
        (index % w) as u32,
        u32::try_from(index / w).ok()?,
    ))
}

/// The centre of `cell` in metres, cells `cell_size_m` wide, origin at the grid's top-left
/// corner: `((x + 0.5) * size, (y + 0.5) * size)`.
#[inline]
pub fn cell_centre_m(cell_size_m: f64, cell: Cell) -> (f64, f64) {
    signed_cell_centre_m(cell_size_m, i64::from(cell.x), i64::from(cell.y))
}

/// [`cell_centre_m`] for signed cell coordinates: collision checks look at the cells around a
/// robot, which may lie outside the grid (column or row `-1`). The same arithmetic, so an
/// in-grid cell gets the same bits either way.
#[inline]
pub fn signed_cell_centre_m(cell_size_m: f64, x: i64, y: i64) -> (f64, f64) {
    (
        (x as f64 + 0.5) * cell_size_m,
        (y as f64 + 0.5) * cell_size_m,
    )
}

/// A pose at the centre of `cell` (see [`cell_centre_m`]) with heading `theta_rad`: where a
/// robot starts, and what the agent's dead reckoning assumes it started from.
#[inline]
pub fn cell_centre_pose(cell_size_m: f64, cell: Cell, theta_rad: f64) -> Pose {
    let (x_m, y_m) = cell_centre_m(cell_size_m, cell);
    Pose {
        x_m,
        y_m,
        theta_rad,
    }
}

/// Length of one octile move from `a` to `b`: 1 straight, `sqrt 2` diagonal, and 0 when the
/// cells are not 8-neighbours (equal, or further apart), so that tallying accepted moves never
/// counts a jump as travel.
#[inline]
pub fn octile_step_len(a: Cell, b: Cell) -> f64 {
    match (a.x.abs_diff(b.x), a.y.abs_diff(b.y)) {
        (1, 1) => SQRT_2,
        (1, 0) | (0, 1) => 1.0,
        _ => 0.0,
    }
}

/// Wraps an angle into `(-π, π]`. An angle already in range comes back unchanged, bit for
/// bit, so wrapping every step adds no rounding (the sim's truth and the agent's dead
/// reckoning wrap this way).
#[inline]
pub fn wrap_angle(a: f64) -> f64 {
    if a > -PI && a <= PI {
        return a;
    }
    let w = a.rem_euclid(TAU);
    if w > PI {
        w - TAU
    } else {
        w
    }
}

/// Wraps an angle into `(-π, π]` by shifting it by `π`, reducing modulo `2π` and shifting
/// back: the wheel controller's heading error.
///
/// Unlike [`wrap_angle`] this rounds even angles that are already in range (`(a + π) - π` is
/// not `a` in floating point). The controller's wheel commands, and with them every lockstep
/// consensus log, depend on exactly these bits, so the two formulas stay apart until a change
/// of behaviour is wanted.
#[inline]
pub fn wrap_angle_shifted(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(TAU) - PI;
    if w <= -PI {
        w + TAU
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indices_round_trip_on_a_non_square_grid() {
        for index in 0..21 {
            let c = index_cell(7, index).unwrap();
            assert!(c.x < 7 && c.y < 3);
            assert_eq!(cell_index(7, c), index);
        }
        assert_eq!(index_cell(7, 9), Some(Cell::new(2, 1)));
        assert_eq!(index_cell(0, 9), None, "a zero width is not a grid");
        assert_eq!(index_cell(1, usize::MAX), None, "the row does not fit u32");
    }

    #[test]
    fn centres_are_half_a_cell_in() {
        assert_eq!(cell_centre_m(2.0, Cell::new(0, 3)), (1.0, 7.0));
        assert_eq!(signed_cell_centre_m(0.12, -1, 2), (-0.06, 2.5 * 0.12));
        let c = Cell::new(17, 5);
        let (x, y) = cell_centre_m(0.16, c);
        assert_eq!(signed_cell_centre_m(0.16, 17, 5), (x, y));
        let p = cell_centre_pose(0.16, c, 1.25);
        assert_eq!((p.x_m, p.y_m, p.theta_rad), (x, y, 1.25));
    }

    #[test]
    fn step_lengths_are_octile() {
        let c = Cell::new(4, 4);
        assert_eq!(octile_step_len(c, Cell::new(5, 4)), 1.0);
        assert_eq!(octile_step_len(c, Cell::new(4, 3)), 1.0);
        assert_eq!(octile_step_len(c, Cell::new(3, 5)), SQRT_2);
        assert_eq!(octile_step_len(c, c), 0.0);
        assert_eq!(octile_step_len(c, Cell::new(6, 4)), 0.0);
    }

    #[test]
    fn wrapping_lands_in_the_half_open_interval() {
        assert_eq!(wrap_angle(0.5), 0.5);
        assert_eq!(wrap_angle(PI), PI);
        assert!((wrap_angle(3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap_angle(-3.5 * PI) - 0.5 * PI).abs() < 1e-12);
        assert!((wrap_angle_shifted(-PI) - PI).abs() < 1e-12);
        assert!((wrap_angle_shifted(2.5 * PI) - 0.5 * PI).abs() < 1e-12);
        for i in -200..200 {
            let a = f64::from(i) * 0.173;
            for w in [wrap_angle(a), wrap_angle_shifted(a)] {
                assert!(w > -PI && w <= PI, "{a} -> {w}");
                assert!(((a - w) / TAU - ((a - w) / TAU).round()).abs() < 1e-9);
            }
        }
    }
}
