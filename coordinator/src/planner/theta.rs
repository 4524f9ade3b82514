//! Basic Theta* (Nash, Daniel, Koenig & Felner, AAAI 2007; seed 002 §3.4 and §3.6).
//!
//! A* whose `UpdateVertex` tries "path 2" first: when expanding `s`, each successor `s'` may
//! take `parent(s)` as its parent if the segment `parent(s) -> s'` has line of sight. That
//! check is made **eagerly**, once per generated successor (the start, whose parent is
//! itself, needs none). Otherwise "path 1": `s' ` hangs off `s` like in A*.
//!
//! * Heuristic: the Euclidean distance (thesis eq. 2.2), admissible for any-angle paths.
//! * Moves: the 8 neighbours under the corner rule, never squeezing between two diagonally
//!   touching blocked cells (so every path-1 edge also has line of sight).
//! * Ties: as in A* (smallest `f`, then largest `g`).
//! * With a hazard model \[inferred, seed 002 §3.6\]: the line-of-sight walk also sums the
//!   hazard of the crossed cells, and because a segment's cost is then no longer its length,
//!   path 2 is taken only if it is not dearer than path 1 (without hazard this is always the
//!   case by the triangle inequality, and the canonical algorithm does not compare).
//! * The path lists the waypoints (start, turning points, goal).

use hnav_runtime::grid::{Cell, Grid};

use super::interface::{PlanStats, Planner, PlannerConfig};
use super::path::Path;
use super::search::{planner_options, Search};
use super::space::Space;
use crate::error::PlanError;
use crate::line_of_sight::euclid;

/// The Basic Theta* planner. Reuse one value for many queries: its buffers are kept.
#[derive(Clone, Debug, Default)]
pub struct BasicTheta {
    config: PlannerConfig,
    search: Search,
}

planner_options!(BasicTheta);

impl Planner for BasicTheta {
    fn name(&self) -> &'static str {
        "theta"
    }

    fn plan(&mut self, grid: &Grid, start: Cell, goal: Cell) -> Result<Option<Path>, PlanError> {
        let hazard = self.config.hazard.as_deref();
        let space = Space::new(grid, hazard, self.config.corner_cutting, true, start, goal)?;
        let search = &mut self.search;
        search.begin(space.len());
        let (s0, t) = (space.index(start), space.index(goal));
        search.open(s0, 0.0, euclid(start, goal), s0);
        while let Some(s) = search.pop() {
            search.stats.expansions += 1;
            if s == t {
                let (cells, length) = search.path_to(&space, t);
                return Ok(Some(Path { cells, length }));
            }
            let gs = search.g(s);
            let p = search.parent(s);
            let gp = search.g(p);
            let c = space.cell(s);
            space.for_each_move(s, c, |n, dx, dy| {
                if search.is_closed(n) {
                    return;
                }
                // ComputeCost: path 2 through parent(s) if visible, else path 1 through s.
                let path1 = || gs + space.move_cost(s, n, dx != 0 && dy != 0);
                let (g, parent) = if p == s {
                    (path1(), s)
                } else {
                    search.stats.los_checks += 1;
                    match space.segment_cost(p, n) {
                        Some(c) if !space.has_hazard() => (gp + c, p),
                        Some(c) => {
                            let (two, one) = (gp + c, path1());
                            if two <= one {
                                (two, p)
                            } else {
                                (one, s)
                            }
                        }
                        None => (path1(), s),
                    }
                };
                if g < search.g(n) {
                    let cn = Cell::new(c.x.wrapping_add_signed(dx), c.y.wrapping_add_signed(dy));
                    search.open(n, g, euclid(cn, goal), parent);
                }
            });
        }
        debug_assert!(search.open_is_empty());
        Ok(None)
    }

    fn stats(&self) -> PlanStats {
        self.search.stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::planner::astar::AStar;
    use crate::planner::path::check_path;
    use hnav_runtime::grid::CornerCutting;

    fn grid(rows: &[&str]) -> Grid {
        Grid::from_rows(rows).unwrap()
    }

    #[test]
    fn open_grid_gives_one_straight_segment() {
        let g = Grid::new(50, 50).unwrap();
        let mut th = BasicTheta::default();
        let p = th
            .plan(&g, Cell::new(0, 0), Cell::new(49, 49))
            .unwrap()
            .unwrap();
        assert_eq!(p.cells, vec![Cell::new(0, 0), Cell::new(49, 49)]);
        assert!((p.length - 49.0 * std::f64::consts::SQRT_2).abs() < 1e-9);
        let p = th
            .plan(&g, Cell::new(3, 40), Cell::new(45, 2))
            .unwrap()
            .unwrap();
        assert_eq!(p.cells.len(), 2);
        assert!((p.length - 42f64.hypot(38.0)).abs() < 1e-9);
        assert!(th.stats().los_checks > 0);
    }

    #[test]
    fn goes_around_a_wall_no_longer_than_astar() {
        let g = grid(&[
            "..........",
            "..........",
            "....@.....",
            "....@.....",
            "....@.....",
            "....@.....",
            "..........",
        ]);
        for rule in [CornerCutting::Forbidden, CornerCutting::Allowed] {
            let cfg = PlannerConfig::new(rule);
            let mut th = BasicTheta::new(cfg.clone());
            let mut a = AStar::new(cfg);
            let (s, t) = (Cell::new(1, 4), Cell::new(8, 3));
            let p = th.plan(&g, s, t).unwrap().unwrap();
            let q = a.plan(&g, s, t).unwrap().unwrap();
            assert!(p.length <= q.length + 1e-9);
            assert_eq!(check_path(&g, None, rule, &p.cells, s, t), Ok(()));
        }
    }

    #[test]
    fn no_path_when_walled_off() {
        let g = grid(&["..@..", ".@...", "@...."]);
        let mut th = BasicTheta::new(PlannerConfig::new(CornerCutting::Allowed));
        // Allowed would let A* squeeze diagonally; any-angle planners never squeeze.
        assert_eq!(th.plan(&g, Cell::new(0, 0), Cell::new(4, 2)), Ok(None));
    }
}
