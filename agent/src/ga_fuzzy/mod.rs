//! Seed 004's hybrid planner: a genetic algorithm over time-indexed grids for the coarse
//! route and a fuzzy controller for the fine motion (notes `001_004_ch1.md`, Part B).
//!
//! The seed is a truncated article whose equations were images; what survives is the
//! structure (coarse GA + fine fuzzy controller, switched at the coarse route's nodal
//! points), the environment model (`N` Boolean `Sx x Sy` layers), the chromosome (`N` nodes,
//! start first, goal last), the fitness's shape (`sum alpha_k S_k`, `alpha_k in [0, 1]`, `S1`
//! length with `d = 1` orthogonal, `S2` time through the chromosome length `N_p`) and the
//! fuzzy controller's interface (free areas `A` in eight directions and heading deviation `b`
//! in, speed `V` and direction `phi` out, 72 rules = 9 x 8). Everything else is marked
//! `\[inferred\]` where it is decided, and listed in `docs/experiments/ga-fuzzy.md`.
//!
//! | module | concept |
//! |---|---|
//! | [`time_grid`] | [`TimeGrid`]: the `N` layers `Sx x Sy`, walls plus moving obstacles per tick |
//! | [`fitness`] | the step length `d`, `S1`, `S2`, `F`: [`score`] |
//! | [`chromosome`] | the operators: goal-biased walks, crossover at a shared node, mutation, loop cutting |
//! | [`search`] | the GA loop and [`GaPlanner`], the [`RoutePlanner`](crate::route::RoutePlanner) `"ga-fuzzy"` |
//! | [`fuzzy`] | the fuzzy controller: term sets, membership functions, the 72-rule base, inference |
//! | [`fine`] | the coarse/fine switch at nodal points, driven by the fuzzy controller |
//!
//! The wheel-level fuzzy drive is [`crate::controller::FuzzyController`], interchangeable
//! with the proportional one through [`crate::controller::WheelDrive`].
//!
//! ```
//! use hnav_agent::ga_fuzzy::{GaOptions, GaPlanner};
//! use hnav_agent::route::RoutePlanner;
//! use hnav_runtime::grid::{Cell, Grid};
//!
//! let grid = Grid::new(10, 10).unwrap();
//! let mut ga = GaPlanner::new(GaOptions::default()).unwrap();
//! let route = ga.route(&grid, Cell::new(0, 0), Cell::new(9, 4)).unwrap().unwrap();
//! assert_eq!((route[0], *route.last().unwrap()), (Cell::new(0, 0), Cell::new(9, 4)));
//! ```

pub mod chromosome;
pub mod fine;
pub mod fitness;
pub mod fuzzy;
pub mod search;
pub mod time_grid;

pub use fitness::{score, Score, Weights};
pub use fuzzy::{FuzzyOutput, FuzzyRules};
pub use search::{GaOptions, GaPlanner, GaRoute};
pub use time_grid::TimeGrid;

#[cfg(test)]
mod tests {
    use super::chromosome::is_legal;
    use super::*;
    use crate::route::RoutePlanner;
    use hnav_runtime::grid::{octile_shortest_path_len, Cell, CornerCutting, Grid};

    fn maze() -> Grid {
        Grid::from_rows(&[
            "..........",
            ".@@@@@@@@.",
            ".@......@.",
            ".@.@@@@.@.",
            ".@.@..@.@.",
            ".@.@..@...",
            ".@.@@.@@@.",
            ".@........",
            ".@@@@@@@@.",
            "..........",
        ])
        .unwrap()
    }

    #[test]
    fn routes_are_legal_near_optimal_and_deterministic() {
        let g = maze();
        let mut ga = GaPlanner::new(GaOptions::default()).unwrap();
        for (s, t) in [
            (Cell::new(0, 0), Cell::new(4, 4)),
            (Cell::new(9, 9), Cell::new(2, 2)),
            (Cell::new(0, 9), Cell::new(9, 0)),
        ] {
            let r = ga.route(&g, s, t).unwrap().unwrap();
            let tg = TimeGrid::fixed(g.clone(), CornerCutting::Forbidden, 100).unwrap();
            assert!(
                is_legal(&tg, &r) && r[0] == s && *r.last().unwrap() == t,
                "{r:?}"
            );
            let best = octile_shortest_path_len(&g, s, t, CornerCutting::Forbidden).unwrap();
            let len = fitness::route_length(&r).unwrap();
            assert!(
                len >= best - 1e-9 && len <= 1.5 * best,
                "{s}->{t}: {len} vs {best}"
            );
            // Same query, same route, whatever ran in between.
            let mut other = GaPlanner::new(GaOptions::default()).unwrap();
            assert_eq!(other.route(&g, s, t).unwrap().unwrap(), r);
        }
    }

    #[test]
    fn unreachable_goals_and_bad_endpoints() {
        let g = Grid::from_rows(&["..@..", "..@..", "..@.."]).unwrap();
        let mut ga = GaPlanner::new(GaOptions::default()).unwrap();
        assert_eq!(
            ga.route(&g, Cell::new(0, 0), Cell::new(4, 2)).unwrap(),
            None
        );
        assert!(ga.route(&g, Cell::new(2, 0), Cell::new(4, 2)).is_err());
        assert!(ga.route(&g, Cell::new(0, 0), Cell::new(9, 2)).is_err());
        let bad = GaOptions {
            mutation: 1.5,
            ..GaOptions::default()
        };
        assert!(GaPlanner::new(bad)
            .unwrap_err()
            .to_string()
            .contains("mutation"));
    }

    #[test]
    fn the_time_layers_make_the_robot_wait_or_dodge_a_crossing_robot() {
        // A robot crosses the corridor at ticks 3..5; going straight collides at tick 4.
        let g = Grid::from_rows(&["@@@@.@@@", "........", "@@@@.@@@"]).unwrap();
        let mut tg = TimeGrid::fixed(g, CornerCutting::Forbidden, 30).unwrap();
        let other: Vec<Cell> = [(4, 0), (4, 0), (4, 0), (4, 1), (4, 1), (4, 1), (4, 2)]
            .iter()
            .map(|&(x, y)| Cell::new(x, y))
            .collect();
        tg.add_moving(&other).unwrap();
        let straight: Vec<Cell> = (0..8).map(|x| Cell::new(x, 1)).collect();
        assert!(tg.conflicts(&straight) > 0);
        let mut ga = GaPlanner::new(GaOptions::default()).unwrap();
        let r = ga
            .plan(&tg, Cell::new(0, 1), Cell::new(7, 1))
            .unwrap()
            .unwrap();
        assert_eq!(r.score.conflicts, 0, "{:?}", r.cells);
        assert!(is_legal(&tg, &r.cells));
    }
}
