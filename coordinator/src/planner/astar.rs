//! A* on the 8-connected grid (Hart, Nilsson & Raphael 1968; seed 002 §3.2).
//!
//! * Moves: the 8 neighbours, straight 1 and diagonal `sqrt 2`, under the configured
//!   [`CornerCutting`](hnav_runtime::grid::CornerCutting) rule exactly as
//!   [`Grid::can_move`](hnav_runtime::grid::Grid::can_move) defines it. With corners
//!   forbidden the lengths are MovingAI's optimal lengths.
//! * Heuristic: the octile distance. It is the exact cost on an empty grid, so it is
//!   admissible and consistent (also with a hazard model, which only adds non-negative cost):
//!   no node is expanded twice and the first time the goal leaves the open list its `g` is
//!   optimal. (The thesis's eq. 2.2 uses the Euclidean distance, which is weaker on an
//!   8-connected grid; the Theta* variants use it.)
//! * Tie-breaking: smallest `f`, then largest `g` (see the open list); neighbours are
//!   generated in the runtime's direction order N, NE, E, ... NW.
//! * The path lists every cell, start to goal.

use hnav_runtime::grid::{octile, Cell, Grid};

use super::interface::{PlanStats, Planner, PlannerConfig};
use super::path::Path;
use super::search::{planner_options, Search};
use super::space::Space;
use crate::error::PlanError;

/// The coordinator's A* planner. Reuse one value for many queries: its buffers are kept.
#[derive(Clone, Debug, Default)]
pub struct AStar {
    config: PlannerConfig,
    search: Search,
}

planner_options!(AStar);

impl Planner for AStar {
    fn name(&self) -> &'static str {
        "astar"
    }

    fn plan(&mut self, grid: &Grid, start: Cell, goal: Cell) -> Result<Option<Path>, PlanError> {
        let hazard = self.config.hazard.as_deref();
        let space = Space::new(grid, hazard, self.config.corner_cutting, false, start, goal)?;
        let search = &mut self.search;
        search.begin(space.len());
        let (s, t) = (space.index(start), space.index(goal));
        search.open(s, 0.0, octile(start, goal), s);
        while let Some(i) = search.pop() {
            search.stats.expansions += 1;
            if i == t {
                let (cells, length) = search.path_to(&space, t);
                return Ok(Some(Path { cells, length }));
            }
            let gi = search.g(i);
            let c = space.cell(i);
            space.for_each_move(i, c, |j, dx, dy| {
                if search.is_closed(j) {
                    return;
                }
                let g = gi + space.move_cost(i, j, dx != 0 && dy != 0);
                if g < search.g(j) {
                    // The neighbour's coordinates from the offset: no division per successor.
                    let n = Cell::new(c.x.wrapping_add_signed(dx), c.y.wrapping_add_signed(dy));
                    search.open(j, g, octile(n, goal), i);
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
    use hnav_runtime::grid::{octile_shortest_path_len, CornerCutting, Endpoint};

    fn grid(rows: &[&str]) -> Grid {
        Grid::from_rows(rows).unwrap()
    }

    #[test]
    fn open_grid_is_octile_and_path_is_connected() {
        let g = Grid::new(12, 7).unwrap();
        let mut a = AStar::default();
        let (s, t) = (Cell::new(1, 5), Cell::new(10, 0));
        let p = a.plan(&g, s, t).unwrap().unwrap();
        assert!((p.length - octile(s, t)).abs() < 1e-9);
        assert_eq!(p.cells.first(), Some(&s));
        assert_eq!(p.cells.last(), Some(&t));
        assert!(p
            .cells
            .windows(2)
            .all(|w| w[0].x.abs_diff(w[1].x) <= 1 && w[0].y.abs_diff(w[1].y) <= 1));
        assert_eq!(a.stats().los_checks, 0);
        assert!(a.stats().expansions >= p.cells.len() as u64);
    }

    #[test]
    fn corner_rules_match_the_oracle() {
        let g = grid(&["..@...", ".@..@.", "...@..", "@@.@.@", "......"]);
        for rule in [CornerCutting::Forbidden, CornerCutting::Allowed] {
            let mut a = AStar::new(PlannerConfig::new(rule));
            for s in g.passable_cells() {
                for t in g.passable_cells() {
                    let want = octile_shortest_path_len(&g, s, t, rule);
                    let got = a.plan(&g, s, t).unwrap().map(|p| p.length);
                    match (want, got) {
                        (Some(w), Some(l)) => assert!((w - l).abs() < 1e-9, "{s} {t} {rule:?}"),
                        (None, None) => {}
                        other => panic!("{s} {t} {rule:?}: {other:?}"),
                    }
                }
            }
        }
    }

    #[test]
    fn no_path_and_bad_endpoints() {
        let g = grid(&["..@..", "..@..", "..@.."]);
        let mut a = AStar::default();
        assert_eq!(a.plan(&g, Cell::new(0, 0), Cell::new(4, 2)), Ok(None));
        assert_eq!(
            a.plan(&g, Cell::new(2, 0), Cell::new(4, 2)),
            Err(PlanError::Blocked {
                endpoint: Endpoint::Start,
                cell: Cell::new(2, 0)
            })
        );
        assert!(matches!(
            a.plan(&g, Cell::new(0, 0), Cell::new(5, 0)),
            Err(PlanError::OutOfBounds {
                endpoint: Endpoint::Goal,
                ..
            })
        ));
        let p = a
            .plan(&g, Cell::new(1, 1), Cell::new(1, 1))
            .unwrap()
            .unwrap();
        assert_eq!((p.cells.len(), p.length), (1, 0.0));
    }

    #[test]
    fn diagonal_gap_depends_on_corner_rule() {
        let g = grid(&[".@", "@."]);
        let mut a = AStar::default();
        assert_eq!(a.plan(&g, Cell::new(0, 0), Cell::new(1, 1)), Ok(None));
        let mut a = AStar::new(PlannerConfig::new(CornerCutting::Allowed));
        let p = a
            .plan(&g, Cell::new(0, 0), Cell::new(1, 1))
            .unwrap()
            .unwrap();
        assert_eq!(p.cells.len(), 2);
    }
}
