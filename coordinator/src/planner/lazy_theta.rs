//! Lazy Theta* (Nash, Koenig & Tovey, AAAI 2010; seed 002 §3.5 and the canonical form in §3.6).
//!
//! Basic Theta* checks line of sight for every generated successor. Lazy Theta* *assumes*
//! path 2 when it generates a successor (`parent(s') = parent(s)`, no check) and verifies the
//! assumption only when the node is taken from the open list (`SetVertex`): if the segment
//! `parent(s) -> s` is blocked, `s` falls back to path 1 through its best already-expanded
//! neighbour. So there is at most one line-of-sight check per **expansion** instead of one per
//! **successor**, and most successors are never expanded.
//!
//! * Heuristic, moves and ties: as in [`BasicTheta`](super::BasicTheta).
//! * The start needs no check (its parent is itself).
//! * With a hazard model \[inferred, seed 002 §3.6\]: the optimistic cost given to a successor
//!   is the segment's length plus its two end cells' hazard halves, a lower bound of the true
//!   cost found without walking the segment. `SetVertex` walks it once (line of sight and
//!   hazard sum together) and then takes the cheaper of the verified path 2 and the best
//!   path 1, so laziness survives the hazard term. Because the bound ignores the hazard of
//!   the cells in between, it can be far too low (a straight line over a hill looks free);
//!   so when the repair raises `g`, the node goes back on the open list with its true key
//!   instead of being expanded, and is expanded when it comes out again (without a second
//!   check unless it was improved meanwhile). Without this the planner would happily return
//!   the first route over the hill. Line-of-sight checks can then slightly exceed the
//!   expansions. Without hazard the bound is exact, nothing is queued again, and this is the
//!   canonical algorithm.
//! * The path lists the waypoints (start, turning points, goal).

use hnav_runtime::grid::{Cell, Grid};

use super::interface::{PlanStats, Planner, PlannerConfig};
use super::path::Path;
use super::search::{planner_options, Search};
use super::space::Space;
use crate::error::PlanError;
use crate::line_of_sight::euclid;

/// The Lazy Theta* planner. Reuse one value for many queries: its buffers are kept.
#[derive(Clone, Debug, Default)]
pub struct LazyTheta {
    config: PlannerConfig,
    search: Search,
}

planner_options!(LazyTheta);

/// `SetVertex(s)`: verifies the assumed segment `parent(s) -> s` and repairs `g(s)` and the
/// parent if needed.
fn set_vertex(search: &mut Search, space: &Space<'_>, s: usize) {
    let p = search.parent(s);
    search.mark_verified(s);
    if p == s {
        return;
    }
    search.stats.los_checks += 1;
    let verified = space.segment_cost(p, s).map(|c| (search.g(p) + c, p));
    if let (Some(best), false) = (verified, space.has_hazard()) {
        // Without hazard a visible path 2 is never dearer than any path 1.
        search.set(s, best.0, best.1);
        return;
    }
    // Path 1: the best expanded neighbour (there is always one: the node that generated s).
    let mut best = verified.unwrap_or((f64::INFINITY, s));
    let c = space.cell(s);
    space.for_each_move(s, c, |n, dx, dy| {
        if search.is_closed(n) {
            let g = search.g(n) + space.move_cost(n, s, dx != 0 && dy != 0);
            if g < best.0 {
                best = (g, n);
            }
        }
    });
    if best.1 != s {
        search.set(s, best.0, best.1);
    }
    // `set` clears the flag; the values are the checked ones.
    search.mark_verified(s);
}

impl Planner for LazyTheta {
    fn name(&self) -> &'static str {
        "lazy-theta"
    }

    fn plan(&mut self, grid: &Grid, start: Cell, goal: Cell) -> Result<Option<Path>, PlanError> {
        let hazard = self.config.hazard.as_deref();
        let space = Space::new(grid, hazard, self.config.corner_cutting, true, start, goal)?;
        let search = &mut self.search;
        search.begin(space.len());
        let (s0, t) = (space.index(start), space.index(goal));
        search.open(s0, 0.0, euclid(start, goal), s0);
        while let Some(s) = search.pop() {
            if !space.has_hazard() {
                set_vertex(search, &space, s);
            } else if !search.is_verified(s) {
                let optimistic = search.g(s);
                set_vertex(search, &space, s);
                if search.g(s) > optimistic {
                    search.requeue(s, euclid(space.cell(s), goal));
                    continue;
                }
            }
            search.stats.expansions += 1;
            if s == t {
                let (cells, length) = search.path_to(&space, t);
                return Ok(Some(Path { cells, length }));
            }
            let p = search.parent(s);
            let gp = search.g(p);
            let c = space.cell(s);
            space.for_each_move(s, c, |n, dx, dy| {
                if search.is_closed(n) {
                    return;
                }
                // ComputeCost: always assume path 2 through parent(s).
                let g = gp + space.segment_cost_bound(p, n);
                if g < search.g(n) {
                    let cn = Cell::new(c.x.wrapping_add_signed(dx), c.y.wrapping_add_signed(dy));
                    search.open(n, g, euclid(cn, goal), p);
                }
            });
        }
        Ok(None)
    }

    fn stats(&self) -> PlanStats {
        self.search.stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::planner::path::check_path;
    use crate::planner::theta::BasicTheta;
    use hnav_runtime::grid::CornerCutting;

    fn grid(rows: &[&str]) -> Grid {
        Grid::from_rows(rows).unwrap()
    }

    #[test]
    fn open_grid_gives_one_straight_segment() {
        let g = Grid::new(50, 50).unwrap();
        let mut lt = LazyTheta::default();
        let p = lt
            .plan(&g, Cell::new(0, 0), Cell::new(49, 49))
            .unwrap()
            .unwrap();
        assert_eq!(p.cells, vec![Cell::new(0, 0), Cell::new(49, 49)]);
        assert!((p.length - 69.296_464_556_281_66).abs() < 1e-9);
        // One check per expansion after the start's.
        assert_eq!(lt.stats().los_checks, lt.stats().expansions - 1);
    }

    #[test]
    fn repairs_a_blocked_assumption() {
        let g = grid(&[
            "..........",
            "...@@@....",
            "...@@@....",
            "..........",
            "..........",
        ]);
        let (s, t) = (Cell::new(0, 2), Cell::new(9, 1));
        for rule in [CornerCutting::Forbidden, CornerCutting::Allowed] {
            let cfg = PlannerConfig::new(rule);
            let mut lt = LazyTheta::new(cfg.clone());
            let mut bt = BasicTheta::new(cfg);
            let p = lt.plan(&g, s, t).unwrap().unwrap();
            let q = bt.plan(&g, s, t).unwrap().unwrap();
            assert_eq!(check_path(&g, None, rule, &p.cells, s, t), Ok(()));
            assert!((p.length - q.length).abs() < 0.05 * q.length);
            assert!(lt.stats().los_checks < bt.stats().los_checks);
        }
    }

    #[test]
    fn no_path() {
        let g = grid(&["..@..", "..@..", "..@.."]);
        let mut lt = LazyTheta::default();
        assert_eq!(lt.plan(&g, Cell::new(0, 0), Cell::new(4, 2)), Ok(None));
    }
}
