//! Line of sight between cell centres, and the cell chords of a segment.
//!
//! Vertices are cell centres, `(x + 0.5, y + 0.5)` in cell units (seed 002, §2.1). A segment
//! from one centre to another is walked cell by cell in an exact supercover traversal: it
//! visits every cell whose interior the segment crosses, in order, and notices when the
//! segment passes exactly through a grid corner. All decisions use integers (a crossing of
//! the `k`-th vertical grid line happens at `t = (2k - 1) / (2|dx|)`, of the `m`-th horizontal
//! line at `t = (2m - 1) / (2|dy|)`, and the two are compared by cross-multiplying), so there
//! is no floating-point doubt about corner cases.
//!
//! # The corner rule
//!
//! A segment between two centres never runs along a grid line (centres sit at half-integers),
//! so the only special places are grid corners the segment goes straight through. There it
//! moves diagonally from one cell to the next and touches the two *side* cells at a single
//! point:
//!
//! * [`CornerCutting::Forbidden`] (MovingAI's rule): both side cells must be free. Equivalently
//!   the closed segment touches no blocked cell at all. For a single diagonal move this is
//!   exactly [`Grid::can_move`] with the same rule, so A*'s moves and Theta*'s segments obey
//!   one rule.
//! * [`CornerCutting::Allowed`]: at least one side cell must be free. A segment never squeezes
//!   between two blocked cells that touch diagonally, even though [`Grid::can_move`] allows
//!   that single move: a path of zero width through a point where two obstacles meet is not a
//!   route a robot can drive, and the any-angle planners use this rule for their moves too.
//!
//! Cells outside the grid cannot be reached: the segment stays inside the bounding box of its
//! two end cells, and the side cells of a corner crossing do too.

use hnav_runtime::grid::{Cell, CornerCutting, Grid};

/// Walks the segment from the centre of `a` to the centre of `b` (both inside a grid of the
/// given `width`; the caller checks that).
///
/// `blocked(index)` says whether a cell stops the segment. `visit(index, t_in, t_out)` is
/// called for every crossed cell, in order, with the segment parameters (`0..=1`) where the
/// segment enters and leaves it; it is only given meaningful `t` values when `CHORDS` is true
/// (otherwise both are 0, and the optimiser removes the divisions). Returns `false` as soon as
/// a crossed cell is blocked or a corner crossing breaks `rule`; `visit` has then been called
/// for a prefix of the cells only.
#[inline]
pub(crate) fn walk<const CHORDS: bool>(
    width: usize,
    a: Cell,
    b: Cell,
    rule: CornerCutting,
    blocked: impl Fn(usize) -> bool,
    mut visit: impl FnMut(usize, f64, f64),
) -> bool {
    let (mut x, mut y) = (i64::from(a.x), i64::from(a.y));
    let (dx, dy) = (i64::from(b.x) - x, i64::from(b.y) - y);
    let (sx, sy) = (dx.signum(), dy.signum());
    let (dx, dy) = (dx.abs(), dy.abs());
    // Both coordinates stay within the bounding box of a and b, so they are >= 0 and the
    // index fits in usize.
    let index = |x: i64, y: i64| y as usize * width + x as usize;
    if blocked(index(x, y)) {
        return false;
    }
    let (two_dx, two_dy) = (2.0 * dx as f64, 2.0 * dy as f64);
    let (mut ix, mut iy) = (1_i64, 1_i64);
    let mut t_in = 0.0;
    while ix <= dx || iy <= dy {
        // Which grid line comes first: the next vertical (x) or horizontal (y) one?
        let order = if ix > dx {
            std::cmp::Ordering::Greater
        } else if iy > dy {
            std::cmp::Ordering::Less
        } else {
            ((2 * ix - 1) * dy).cmp(&((2 * iy - 1) * dx))
        };
        let t_out = if !CHORDS {
            0.0
        } else if order == std::cmp::Ordering::Greater {
            (2 * iy - 1) as f64 / two_dy
        } else {
            (2 * ix - 1) as f64 / two_dx
        };
        visit(index(x, y), t_in, t_out);
        t_in = t_out;
        match order {
            std::cmp::Ordering::Less => {
                x += sx;
                ix += 1;
            }
            std::cmp::Ordering::Greater => {
                y += sy;
                iy += 1;
            }
            std::cmp::Ordering::Equal => {
                let side_x = blocked(index(x + sx, y));
                let side_y = blocked(index(x, y + sy));
                let refused = match rule {
                    CornerCutting::Forbidden => side_x || side_y,
                    CornerCutting::Allowed => side_x && side_y,
                };
                if refused {
                    return false;
                }
                x += sx;
                y += sy;
                ix += 1;
                iy += 1;
            }
        }
        if blocked(index(x, y)) {
            return false;
        }
    }
    visit(index(x, y), t_in, if CHORDS { 1.0 } else { 0.0 });
    true
}

/// Whether the straight segment between the centres of `a` and `b` crosses only free cells
/// of `grid` and passes grid corners according to `rule` (see the [module docs](self)).
/// `false` if either cell is outside the grid or blocked. A cell sees itself if it is free.
///
/// ```
/// use hnav_coordinator::planner::line_of_sight;
/// use hnav_runtime::grid::{read_map, Cell, CornerCutting};
/// let g = read_map("type octile\nheight 2\nwidth 2\nmap\n.@\n@.\n", "m").unwrap();
/// // The diagonal would squeeze between two blocked cells touching at a corner.
/// assert!(!line_of_sight(&g, Cell::new(0, 0), Cell::new(1, 1), CornerCutting::Allowed));
/// ```
pub fn line_of_sight(grid: &Grid, a: Cell, b: Cell, rule: CornerCutting) -> bool {
    if !grid.contains(a) || !grid.contains(b) {
        return false;
    }
    let blocked = grid.blocked();
    walk::<false>(
        grid.width() as usize,
        a,
        b,
        rule,
        |i| blocked[i],
        |_, _, _| {},
    )
}

/// The cells whose interior the segment between the centres of `a` and `b` crosses, in
/// order from `a` to `b`, each with the length of the segment inside it (in cell units).
/// Cells the segment only touches at a corner are not listed. Obstacles are ignored; `None`
/// if either cell is outside the grid.
///
/// ```
/// use hnav_coordinator::planner::segment_chords;
/// use hnav_runtime::grid::{Cell, Grid};
/// let g = Grid::new(3, 1).unwrap();
/// let chords = segment_chords(&g, Cell::new(0, 0), Cell::new(2, 0)).unwrap();
/// let lens: Vec<f64> = chords.iter().map(|c| c.1).collect();
/// assert_eq!(lens, vec![0.5, 1.0, 0.5]);
/// ```
pub fn segment_chords(grid: &Grid, a: Cell, b: Cell) -> Option<Vec<(Cell, f64)>> {
    if !grid.contains(a) || !grid.contains(b) {
        return None;
    }
    let len = euclid(a, b);
    let mut out = Vec::new();
    walk::<true>(
        grid.width() as usize,
        a,
        b,
        CornerCutting::Allowed,
        |_| false,
        |i, t_in, t_out| {
            if let Some(c) = grid.cell_at(i) {
                out.push((c, (t_out - t_in) * len));
            }
        },
    );
    Some(out)
}

/// Euclidean distance between two cell centres, in cell units.
#[inline]
pub fn euclid(a: Cell, b: Cell) -> f64 {
    let dx = f64::from(a.x.abs_diff(b.x));
    let dy = f64::from(a.y.abs_diff(b.y));
    // Not `hypot`: its overflow care is slow and useless for coordinates below 2^26.
    (dx * dx + dy * dy).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(rows: &[&str]) -> Grid {
        Grid::from_rows(rows).unwrap()
    }

    fn los(g: &Grid, a: (u32, u32), b: (u32, u32), rule: CornerCutting) -> bool {
        let (a, b) = (Cell::new(a.0, a.1), Cell::new(b.0, b.1));
        let fwd = line_of_sight(g, a, b, rule);
        assert_eq!(fwd, line_of_sight(g, b, a, rule), "LOS must be symmetric");
        fwd
    }

    #[test]
    fn diagonal_squeeze_is_refused_under_both_rules() {
        let g = grid(&[".@", "@."]);
        assert!(!los(&g, (0, 0), (1, 1), CornerCutting::Allowed));
        assert!(!los(&g, (0, 0), (1, 1), CornerCutting::Forbidden));
        // A longer segment through the same pinch point.
        let g = grid(&["....", ".@..", "..@.", "...."]);
        assert!(!los(&g, (3, 0), (0, 3), CornerCutting::Allowed));
        let g = grid(&["....", "..@.", ".@..", "...."]);
        // Here the pinch is on the anti-diagonal: the main diagonal crosses (1,1) and (2,2)
        // which are free, and its corners touch (2,1) and (1,2), both blocked.
        assert!(!los(&g, (0, 0), (3, 3), CornerCutting::Allowed));
        assert!(!los(&g, (0, 0), (3, 3), CornerCutting::Forbidden));
    }

    #[test]
    fn one_blocked_corner_depends_on_rule() {
        let g = grid(&[".@", ".."]);
        assert!(los(&g, (0, 0), (1, 1), CornerCutting::Allowed));
        assert!(!los(&g, (0, 0), (1, 1), CornerCutting::Forbidden));
        // Agrees with can_move for single diagonal moves under Forbidden.
        use hnav_runtime::grid::Direction;
        assert!(!g.can_move(Cell::new(0, 0), Direction::SE, CornerCutting::Forbidden));
    }

    #[test]
    fn blocked_cell_in_the_middle() {
        let g = grid(&[".....", "..@..", "....."]);
        assert!(!los(&g, (0, 1), (4, 1), CornerCutting::Allowed));
        assert!(los(&g, (0, 0), (4, 0), CornerCutting::Forbidden));
        // Slope 1/2 from (0,0) to (4,2): crosses (2,1) exactly at its centre.
        assert!(!los(&g, (0, 0), (4, 2), CornerCutting::Allowed));
        // Slope 1/4 from (0,0) to (4,1) crosses y = 1 at x = 2.5, inside column 2.
        assert!(!los(&g, (0, 0), (4, 1), CornerCutting::Allowed));
        // Slope 1/3 from (0,0) to (3,1) passes the grid corner (2, 1): cells (0,0) (1,0) then
        // (2,1) (3,1), side cells (2,0) free and (1,1) blocked.
        let g = grid(&["....", ".@..", "...."]);
        assert!(los(&g, (0, 0), (3, 1), CornerCutting::Allowed));
        assert!(!los(&g, (0, 0), (3, 1), CornerCutting::Forbidden));
    }

    #[test]
    fn endpoints_and_outside() {
        let g = grid(&["@.."]);
        assert!(!los(&g, (0, 0), (2, 0), CornerCutting::Allowed));
        assert!(los(&g, (1, 0), (2, 0), CornerCutting::Allowed));
        assert!(los(&g, (1, 0), (1, 0), CornerCutting::Allowed));
        assert!(!line_of_sight(
            &g,
            Cell::new(1, 0),
            Cell::new(7, 0),
            CornerCutting::Allowed
        ));
    }

    #[test]
    fn chords_sum_to_length_and_skip_touched_corners() {
        let g = Grid::new(8, 8).unwrap();
        for (a, b) in [
            ((0, 0), (7, 3)),
            ((6, 1), (0, 7)),
            ((2, 2), (2, 6)),
            ((0, 0), (3, 3)),
        ] {
            let (a, b) = (Cell::new(a.0, a.1), Cell::new(b.0, b.1));
            let ch = segment_chords(&g, a, b).unwrap();
            let sum: f64 = ch.iter().map(|c| c.1).sum();
            assert!((sum - euclid(a, b)).abs() < 1e-12, "{a} {b}");
            assert_eq!(ch.first().map(|c| c.0), Some(a));
            assert_eq!(ch.last().map(|c| c.0), Some(b));
            assert!(ch.iter().all(|c| c.1 > 0.0));
            for w in ch.windows(2) {
                let (p, q) = (w[0].0, w[1].0);
                assert!(p.x.abs_diff(q.x) <= 1 && p.y.abs_diff(q.y) <= 1);
            }
        }
        // The 45-degree diagonal passes corners only: 4 cells, chords sqrt2/2, sqrt2, sqrt2,
        // sqrt2/2.
        let ch = segment_chords(&g, Cell::new(0, 0), Cell::new(3, 3)).unwrap();
        assert_eq!(ch.len(), 4);
        let h = std::f64::consts::SQRT_2;
        for (c, want) in ch.iter().zip([h / 2.0, h, h, h / 2.0]) {
            assert!((c.1 - want).abs() < 1e-12);
        }
    }
}
