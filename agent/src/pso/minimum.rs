//! Swarm local-minimum detection and the virtual obstacles placed around the minimum
//! (Pseudocode 2, notes §3.2-§3.5).
//!
//! Detection \[P\]: a minimum is declared when the swarm's best x^G has not changed for more
//! than n_lm iterations (`d_lm > n_lm`; `d_lm` is 1 on the iteration x^G changes). Before an
//! obstacle is placed, the 24-cell window around x^G (5 x 5 minus centre, Fig. 4) is analysed
//! to tell a corner or dead end from a straight wall (§3.5; the rule is the notes' suggestion,
//! \[A\], swappable through [`CornerRule`]).

use hnav_runtime::grid::Grid;

use super::field::{chebyshev, Field};
use super::options::{CornerRule, Footprint};

/// The counter d_lm of Pseudocode 2.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct Detector {
    /// Consecutive iterations with x^G unchanged (1 on the iteration it changed).
    pub count: u32,
}

impl Detector {
    /// Step 1 of Pseudocode 2 for this iteration; true when `d_lm > n_lm` (step 2 is due).
    pub fn observe(&mut self, best_changed: bool, n_lm: u32) -> bool {
        self.count = if best_changed { 1 } else { self.count + 1 };
        self.count > n_lm
    }

    /// The explicit reset after an exit (notes §3.3 \[A\]).
    pub fn reset(&mut self) {
        self.count = 1;
    }
}

/// What the local-minimum handling did in one run: counters only, one increment per event.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct MinimumCounts {
    /// Detections: the iterations on which `d_lm` first exceeds n_lm (one per stall of x^G;
    /// after an exit resets `d_lm`, the next needs n_lm more unchanged iterations).
    pub detections: u32,
    /// Iterations on which the exit algorithm ran: every iteration with `d_lm > n_lm`, since
    /// a minimum the [`CornerRule`] refuses is examined again until x^G moves.
    pub checks: u32,
    /// Exits that placed at least one virtual obstacle (at most one per detection).
    pub accepted: u32,
}

/// The four axis directions of the window: N (-y), S (+y), W (-x), E (+x).
const AXES: [[i64; 2]; 4] = [[0, -1], [0, 1], [-1, 0], [1, 0]];

/// Which axis directions of the window around `m` hold a blocked cell (wall or virtual) at
/// distance 1 or 2, as far as the swarm senses them (`particles`' positions, `radius`).
///
/// Only the axis cells count, not whole window sides, because a straight wall next to `m`
/// also touches the ends of the two perpendicular sides: counting sides would read every
/// wall as a corner, the very Fig. 3 case the analysis exists to spare.
pub fn blocked_axes(
    grid: &Grid,
    field: &Field,
    m: [i64; 2],
    particles: &[[i64; 2]],
    radius: i64,
) -> [bool; 4] {
    let sensed = |p: [i64; 2]| particles.iter().any(|&q| chebyshev(p, q) <= radius);
    let mut out = [false; 4];
    for (side, d) in AXES.iter().enumerate() {
        out[side] = (1..=2).any(|k| {
            let p = [m[0] + k * d[0], m[1] + k * d[1]];
            sensed(p) && !field.free(grid, p)
        });
    }
    out
}

/// Whether `rule` accepts a minimum whose window has `axes` blocked: [`CornerRule::Sides`]
/// wants two perpendicular axes or three (a corner or a dead end).
pub fn accepts(rule: CornerRule, axes: [bool; 4]) -> bool {
    match rule {
        CornerRule::Always => true,
        CornerRule::Sides => {
            let vertical = axes[0] || axes[1];
            let horizontal = axes[2] || axes[3];
            let count = axes.iter().filter(|&&b| b).count();
            (vertical && horizontal) || count >= 3
        }
    }
}

/// Places the virtual obstacles of `footprint` around `m` and returns how many are new. The
/// goal cell is never covered: an obstacle there would make the run unwinnable.
pub fn place(
    grid: &Grid,
    field: &mut Field,
    footprint: Footprint,
    m: [i64; 2],
    axes: [bool; 4],
    goal: [i64; 2],
) -> usize {
    let mut new = 0;
    let mut put = |field: &mut Field, p: [i64; 2]| {
        if p != goal && field.cell(p).is_some() && field.place(p) {
            new += 1;
        }
    };
    put(field, m);
    if footprint == Footprint::TowardCorner {
        let dy: &[i64] = match (axes[0], axes[1]) {
            (true, false) => &[0, -1],
            (false, true) => &[0, 1],
            _ => &[0],
        };
        let dx: &[i64] = match (axes[2], axes[3]) {
            (true, false) => &[0, -1],
            (false, true) => &[0, 1],
            _ => &[0],
        };
        for &y in dy {
            for &x in dx {
                let p = [m[0] + x, m[1] + y];
                if field.free(grid, p) {
                    put(field, p);
                }
            }
        }
    }
    new
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(rows: &[&str]) -> Grid {
        Grid::from_rows(rows).unwrap()
    }

    #[test]
    fn d_lm_counts_unchanged_iterations_and_fires_above_the_threshold() {
        let mut d = Detector::default();
        assert!(!d.observe(true, 3));
        assert_eq!(d.count, 1);
        for _ in 0..2 {
            assert!(!d.observe(false, 3));
        }
        assert_eq!(d.count, 3);
        assert!(d.observe(false, 3), "d_lm = 4 > n_lm = 3");
        assert!(!d.observe(true, 3));
        assert_eq!(d.count, 1);
    }

    #[test]
    fn a_straight_wall_is_not_a_corner_but_a_corner_and_a_dead_end_are() {
        let wall = grid(&[".....", "@@@@@", ".....", ".....", "....."]);
        let corner = grid(&["...@.", "...@.", "...@.", "@@@@.", "....."]);
        let dead_end = grid(&[".....", ".@.@.", ".@.@.", ".@@@.", "....."]);
        let mut f = Field::default();
        let at = |g: &Grid, f: &mut Field, m: [i64; 2]| {
            f.reset(g);
            blocked_axes(g, f, m, &[m], 2)
        };
        let a = at(&wall, &mut f, [2, 2]);
        assert_eq!(a, [true, false, false, false]);
        assert!(!accepts(CornerRule::Sides, a) && accepts(CornerRule::Always, a));
        let a = at(&corner, &mut f, [2, 2]);
        assert_eq!(a, [false, true, false, true]);
        assert!(accepts(CornerRule::Sides, a));
        let a = at(&dead_end, &mut f, [2, 2]);
        assert_eq!(a, [false, true, true, true]);
        assert!(accepts(CornerRule::Sides, a));
    }

    #[test]
    fn unsensed_cells_count_as_free() {
        let wall = grid(&[".....", "@@@@@", ".....", ".....", "....."]);
        let mut f = Field::default();
        f.reset(&wall);
        // The only particle is 3 cells below the wall, outside a radius of 1 from it.
        let a = blocked_axes(&wall, &f, [2, 2], &[[2, 4]], 1);
        assert_eq!(a, [false; 4]);
    }

    #[test]
    fn the_footprint_fills_toward_the_corner_and_never_the_goal() {
        let corner = grid(&[".....", ".....", ".....", ".....", "....."]);
        let mut f = Field::default();
        f.reset(&corner);
        let axes = [true, false, false, true]; // N and E blocked
        assert_eq!(
            place(
                &corner,
                &mut f,
                Footprint::TowardCorner,
                [2, 2],
                axes,
                [9, 9]
            ),
            4
        );
        let cells: Vec<_> = f.virtual_cells().map(|c| (c.x, c.y)).collect();
        assert_eq!(cells, vec![(2, 1), (3, 1), (2, 2), (3, 2)]);
        f.reset(&corner);
        assert_eq!(
            place(&corner, &mut f, Footprint::Single, [2, 2], axes, [2, 2]),
            0
        );
        assert_eq!(f.placed(), 0);
    }
}
