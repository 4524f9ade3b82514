//! What a range sensor sees from a cell (an emulated LiDAR, seed 000 §3.1.1): the cells
//! within a radius whose centres it sees in a straight line.
//!
//! Line of sight runs from the sensor's cell to the cell's, over the cells a Bresenham line
//! crosses: any blocked cell strictly between hides it (the first blocked cell on a line is
//! seen, what is behind it is not). The sim fills each robot's view with it, and the
//! operator's tools draw the same sensed area from a recording (the truth's poses, the
//! scenario's events and the recorded movers), so both say the same of what a robot saw.
//! What counts as blocked is the caller's: the sim's truth, or a picture of it rebuilt.

use crate::msg::{View, VIEW_EDGE};

/// Fills `view`'s window and cells with what a sensor at cell (`cx`, `cy`) of a `width` x
/// `height` grid sees within `range` cells (at most 15, what a [`View`] holds), given
/// `blocked(x, y)`; leaves its time, period, agent and moving cells to the caller. The sim
/// fills each robot's view with it, and a playback rebuilds the same views from a recording.
pub fn fill_view(
    view: &mut View,
    (width, height): (u32, u32),
    (cx, cy): (i64, i64),
    range: u32,
    blocked: impl Fn(i64, i64) -> bool,
) {
    let range = range.min((VIEW_EDGE as u32 - 1) / 2);
    let r = i64::from(range);
    let (x0, y0) = ((cx - r).max(0), (cy - r).max(0));
    view.reset(x0 as u32, y0 as u32, 2 * range + 1);
    for_each_in_sight((width, height), (cx, cy), range, &blocked, |x, y| {
        view.mark(x as u32, y as u32, blocked(x, y));
    });
}

/// Calls `seen(x, y)` for every cell within `range` cells (Euclidean, between cell
/// centres) of `(cx, cy)` on a `width` x `height` grid that is in sight from it, given
/// `blocked(x, y)`: the sensor's own cell first, then row by row.
pub fn for_each_in_sight(
    (width, height): (u32, u32),
    (cx, cy): (i64, i64),
    range: u32,
    blocked: impl Fn(i64, i64) -> bool,
    mut seen: impl FnMut(i64, i64),
) {
    let (w, h) = (i64::from(width), i64::from(height));
    if !(0..w).contains(&cx) || !(0..h).contains(&cy) {
        return;
    }
    let r = i64::from(range);
    for y in (cy - r).max(0)..=(cy + r).min(h - 1) {
        for x in (cx - r).max(0)..=(cx + r).min(w - 1) {
            let (dx, dy) = (x - cx, y - cy);
            if dx * dx + dy * dy <= r * r && in_sight((cx, cy), (x, y), &blocked) {
                seen(x, y);
            }
        }
    }
}

/// Whether no blocked cell lies strictly between `from` and `to` on the Bresenham line.
pub fn in_sight(from: (i64, i64), to: (i64, i64), blocked: impl Fn(i64, i64) -> bool) -> bool {
    let (mut x, mut y) = from;
    let (dx, dy) = ((to.0 - x).abs(), -(to.1 - y).abs());
    let (sx, sy) = ((to.0 - x).signum(), (to.1 - y).signum());
    let mut err = dx + dy;
    loop {
        if (x, y) == to {
            return true;
        }
        if (x, y) != from && blocked(x, y) {
            return false;
        }
        let e2 = 2 * err;
        if e2 >= dy {
            err += dy;
            x += sx;
        }
        if e2 <= dx {
            err += dx;
            y += sy;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wall_is_seen_and_hides_what_is_behind_it() {
        // A 7 x 1 corridor, the sensor at x = 1, a wall at x = 3.
        let mut seen = Vec::new();
        for_each_in_sight((7, 1), (1, 0), 5, |x, _| x == 3, |x, _| seen.push(x));
        assert_eq!(seen, vec![0, 1, 2, 3]);
    }

    #[test]
    fn the_range_is_a_disc_and_clipped_to_the_grid() {
        let mut n = 0;
        for_each_in_sight((10, 10), (0, 0), 2, |_, _| false, |_, _| n += 1);
        // (0,0) (1,0) (2,0) (0,1) (1,1) (0,2): 2 * 2 + 1 * 1 = 5 > 4 leaves out (2,1), (1,2).
        assert_eq!(n, 6);
        let mut none = 0;
        for_each_in_sight((10, 10), (-1, 3), 2, |_, _| false, |_, _| none += 1);
        assert_eq!(none, 0);
    }
}
