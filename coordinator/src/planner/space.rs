//! The grid as the planners see it: obstacles (blocked cells plus impassable terrain), legal
//! moves, and the cost of moves and segments.
//!
//! A [`Space`] is built per query from borrowed data, after checking the endpoints and the
//! hazard map's shape, so the search loops below can index slices without further checks.

use hnav_runtime::grid::geometry::{cell_index, index_cell};
use hnav_runtime::grid::{Cell, CornerCutting, Endpoint, Grid};

use crate::error::PlanError;
use crate::line_of_sight::{euclid, walk};
use crate::terrain::{hazard::walk_hazard, HazardMap};

/// A validated view of one query's grid.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Space<'a> {
    width: usize,
    height: usize,
    blocked: &'a [bool],
    hazard: Option<&'a HazardMap>,
    rule: CornerCutting,
    /// Refuse a diagonal move between two blocked corner cells even when corners may be cut
    /// (the any-angle planners: their moves must have line of sight).
    no_squeeze: bool,
}

impl<'a> Space<'a> {
    /// Checks the hazard shape and both endpoints and builds the view.
    pub(crate) fn new(
        grid: &'a Grid,
        hazard: Option<&'a HazardMap>,
        rule: CornerCutting,
        any_angle: bool,
        start: Cell,
        goal: Cell,
    ) -> Result<Self, PlanError> {
        if let Some(h) = hazard {
            if (h.width(), h.height()) != (grid.width(), grid.height()) {
                return Err(PlanError::ShapeMismatch {
                    found_width: h.width(),
                    found_height: h.height(),
                    width: grid.width(),
                    height: grid.height(),
                });
            }
        }
        for (endpoint, cell) in [(Endpoint::Start, start), (Endpoint::Goal, goal)] {
            if !grid.contains(cell) {
                return Err(PlanError::OutOfBounds {
                    endpoint,
                    cell,
                    width: grid.width(),
                    height: grid.height(),
                });
            }
        }
        for (endpoint, cell) in [(Endpoint::Start, start), (Endpoint::Goal, goal)] {
            if grid.is_blocked(cell) {
                return Err(PlanError::Blocked { endpoint, cell });
            }
            if hazard.is_some_and(|h| h.is_impassable(cell)) {
                return Err(PlanError::Impassable { endpoint, cell });
            }
        }
        Ok(Space {
            width: grid.width() as usize,
            height: grid.height() as usize,
            blocked: grid.blocked(),
            hazard,
            rule,
            no_squeeze: any_angle,
        })
    }

    /// Number of cells.
    pub(crate) fn len(&self) -> usize {
        self.blocked.len()
    }

    /// Row-major index of a cell inside the grid.
    #[inline]
    pub(crate) fn index(&self, c: Cell) -> usize {
        // The width came from the grid's u32.
        cell_index(self.width as u32, c)
    }

    /// The cell at an index `< len()`.
    #[inline]
    pub(crate) fn cell(&self, i: usize) -> Cell {
        // A grid's width is at least 1 and its rows fit u32, so the conversion cannot fail.
        index_cell(self.width as u32, i).unwrap_or_default()
    }

    /// Whether the cell at `i` is an obstacle: blocked, or impassable terrain.
    #[inline]
    pub(crate) fn is_obstacle(&self, i: usize) -> bool {
        self.blocked[i] || self.hazard.is_some_and(|h| h.impassable()[i])
    }

    /// Calls `f(j, dx, dy)` for every legal single move `i -> j = i + (dx, dy)` from the
    /// cell `c` at index `i`, in the runtime's direction order (N, NE, E, SE, S, SW, W, NW).
    /// Moves are symmetric: `j -> i` is legal too. Taking both `i` and `c`, and handing out
    /// offsets, spares a division per call and per successor.
    #[inline]
    pub(crate) fn for_each_move(&self, i: usize, c: Cell, mut f: impl FnMut(usize, i32, i32)) {
        let (moves, n) = self.moves(i, c.x as usize, c.y as usize);
        for &(j, dx, dy) in &moves[..n] {
            f(j, i32::from(dx), i32::from(dy));
        }
    }

    /// The legal moves from `i` as `(j, dx, dy)`, collected first so that the caller's loop
    /// body exists once (calling it from eight places made the compiler outline it).
    #[inline]
    fn moves(&self, i: usize, x: usize, y: usize) -> ([(usize, i8, i8); 8], usize) {
        let w = self.width;
        let has_n = y > 0;
        let has_s = y + 1 < self.height;
        let has_w = x > 0;
        let has_e = x + 1 < w;
        let free_n = has_n && !self.is_obstacle(i - w);
        let free_s = has_s && !self.is_obstacle(i + w);
        let free_w = has_w && !self.is_obstacle(i - 1);
        let free_e = has_e && !self.is_obstacle(i + 1);
        // Whether a diagonal passing the two orthogonal cells `a` and `b` may be taken.
        let corner_ok = |a: bool, b: bool| match self.rule {
            CornerCutting::Forbidden => a && b,
            CornerCutting::Allowed => !self.no_squeeze || a || b,
        };
        let mut out = [(0, 0, 0); 8];
        let mut n = 0;
        let mut push = |ok: bool, j: usize, dx: i8, dy: i8| {
            out[n] = (j, dx, dy);
            n += usize::from(ok);
        };
        // Each diagonal's target index is only formed when it exists (no underflow).
        push(free_n, i.wrapping_sub(w), 0, -1);
        let ne = has_n && has_e && !self.is_obstacle(i - w + 1) && corner_ok(free_n, free_e);
        push(ne, (i + 1).wrapping_sub(w), 1, -1);
        push(free_e, i + 1, 1, 0);
        let se = has_s && has_e && !self.is_obstacle(i + w + 1) && corner_ok(free_s, free_e);
        push(se, i + w + 1, 1, 1);
        push(free_s, i + w, 0, 1);
        let sw = has_s && has_w && !self.is_obstacle(i + w - 1) && corner_ok(free_s, free_w);
        push(sw, (i + w).wrapping_sub(1), -1, 1);
        push(free_w, i.wrapping_sub(1), -1, 0);
        let nw = has_n && has_w && !self.is_obstacle(i - w - 1) && corner_ok(free_n, free_w);
        push(nw, i.wrapping_sub(w + 1), -1, -1);
        (out, n)
    }

    /// Cost of a legal single move: its length plus, with a hazard model, half the hazard of
    /// each end cell (a move between neighbours crosses no other cell's interior).
    #[inline]
    pub(crate) fn move_cost(&self, i: usize, j: usize, diagonal: bool) -> f64 {
        let len = if diagonal {
            std::f64::consts::SQRT_2
        } else {
            1.0
        };
        match self.hazard {
            None => len,
            Some(h) => {
                let r = h.values();
                len + h.weight() * 0.5 * (f64::from(r[i]) + f64::from(r[j]))
            }
        }
    }

    /// Whether a hazard model is active (segment costs then need a cell walk).
    #[inline]
    pub(crate) fn has_hazard(&self) -> bool {
        self.hazard.is_some()
    }

    /// Line of sight between two cell centres under this query's obstacles and corner rule.
    #[inline]
    pub(crate) fn line_of_sight(&self, a: usize, b: usize) -> bool {
        walk::<false>(
            self.width,
            self.cell(a),
            self.cell(b),
            self.rule,
            |i| self.is_obstacle(i),
            |_, _, _| {},
        )
    }

    /// Line of sight and exact cost of the segment `a -> b` in one walk; `None` without line
    /// of sight.
    #[inline]
    pub(crate) fn segment_cost(&self, a: usize, b: usize) -> Option<f64> {
        let (ca, cb) = (self.cell(a), self.cell(b));
        match self.hazard {
            None => self.line_of_sight(a, b).then(|| euclid(ca, cb)),
            Some(h) => {
                let hazard = walk_hazard(self.width, h.values(), ca, cb, self.rule, |i| {
                    self.is_obstacle(i)
                })?;
                Some(euclid(ca, cb) + h.weight() * hazard)
            }
        }
    }

    /// A lower bound of [`Self::segment_cost`] that needs no walk: the length plus the two
    /// end cells' hazard halves (the cells in between add `>= 0`). Exact without hazard.
    #[inline]
    pub(crate) fn segment_cost_bound(&self, a: usize, b: usize) -> f64 {
        let len = euclid(self.cell(a), self.cell(b));
        match self.hazard {
            None => len,
            Some(h) => {
                let r = h.values();
                len + h.weight() * 0.5 * (f64::from(r[a]) + f64::from(r[b]))
            }
        }
    }
}
