//! The three planners of the comparison on one query, each a whole call with a fresh
//! planner: seed 004's GA (coarse route plus the fuzzy fine switch), the coordinator's A*
//! and HNAV as Table 3-8 ran it (linear activation, partial activation).
//!
//! The GA plans over the query's time layers; A* and HNAV see only the walls (they have no
//! notion of time), and their paths are then scored on the same layers, node `t` held at
//! tick `t`, so the three count collisions with the moving obstacles alike.

use std::time::Instant;

use anyhow::{Context, Result};
use hnav_agent::ga_fuzzy::fitness::route_length;
use hnav_agent::ga_fuzzy::{GaOptions, GaPlanner, TimeGrid};
use hnav_runtime::grid::Cell;
use serde::Serialize;

use crate::experiment::hnav_vs_astar::measure::{Variant, HNAV_LINEAR_PARTIAL, VARIANTS};

/// A planner of the comparison.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Planner {
    /// Seed 004's hybrid: [`GaPlanner`] with its fine switch.
    Ga,
    /// The coordinator's octile A*.
    AStar,
    /// The neural map, linear activation, partial activation.
    Hnav,
}

/// The planners, in the tables' order.
pub const PLANNERS: [Planner; 3] = [Planner::Ga, Planner::AStar, Planner::Hnav];

impl Planner {
    /// The name the tables and the JSON use.
    pub fn name(self) -> &'static str {
        match self {
            Planner::Ga => "ga-fuzzy",
            Planner::AStar => "astar",
            Planner::Hnav => "hnav",
        }
    }
}

/// What a planner answered on one query. Everything but `time_us` is the same on every run
/// for a seed.
#[derive(Clone, Copy, PartialEq, Debug, Serialize)]
pub struct Answer {
    /// Whether it returned a route from the start to the goal.
    pub found: bool,
    /// Route length (straight 1, diagonal `sqrt 2`, a wait 0); 0 if not found.
    pub length: f64,
    /// Ticks to the goal: nodes of the route minus one (waits included); 0 if not found.
    pub ticks: usize,
    /// Collisions with the moving obstacles (node on an occupied cell, or a swap).
    pub conflicts: usize,
    /// Wall time of the call, µs.
    #[serde(skip)]
    pub time_us: f64,
}

impl Answer {
    fn of(route: Option<&[Cell]>, tg: &TimeGrid, time_us: f64) -> Result<Answer> {
        let Some(route) = route.filter(|r| !r.is_empty()) else {
            return Ok(Answer {
                found: false,
                length: 0.0,
                ticks: 0,
                conflicts: 0,
                time_us,
            });
        };
        let length = route_length(route).context("a route with a jump between two cells")?;
        Ok(Answer {
            found: true,
            length,
            ticks: route.len() - 1,
            conflicts: tg.conflicts(route),
            time_us,
        })
    }
}

/// Answers `start -> goal` on `tg` with `planner`. The GA's options are `ga` with the
/// query's layers as its depth; A* and HNAV plan on `tg`'s walls.
pub fn answer(
    planner: Planner,
    ga: GaOptions,
    tg: &TimeGrid,
    start: Cell,
    goal: Cell,
) -> Result<Answer> {
    let t0 = Instant::now();
    let route = match planner {
        Planner::Ga => {
            let mut p = GaPlanner::new(ga)?;
            p.plan(tg, start, goal)?.map(|r| r.cells)
        }
        Planner::AStar => found_path(Variant::AStar, tg, start, goal)?,
        Planner::Hnav => found_path(VARIANTS[HNAV_LINEAR_PARTIAL], tg, start, goal)?,
    };
    let time_us = t0.elapsed().as_secs_f64() * 1e6;
    Answer::of(route.as_deref(), tg, time_us)
        .with_context(|| format!("{} from {start} to {goal}", planner.name()))
}

fn found_path(v: Variant, tg: &TimeGrid, start: Cell, goal: Cell) -> Result<Option<Vec<Cell>>> {
    let r = v.query(tg.grid(), start, goal)?;
    Ok(r.found.then_some(r.path))
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::grid::{CornerCutting, Grid};

    #[test]
    fn every_planner_crosses_an_open_room_and_only_the_ga_dodges() {
        // A robot parks in the middle of the straight line at tick 3 and stays there.
        let g = Grid::new(7, 3).unwrap();
        let mut tg = TimeGrid::fixed(g, CornerCutting::Forbidden, 40).unwrap();
        let c = |x, y| Cell::new(x, y);
        tg.add_moving(&[c(3, 0), c(3, 0), c(3, 0), c(3, 1)])
            .unwrap();
        for p in PLANNERS {
            let a = answer(p, GaOptions::default(), &tg, c(0, 1), c(6, 1)).unwrap();
            assert!(
                a.found && a.length >= 6.0 - 1e-9 && a.ticks >= 6,
                "{p:?} {a:?}"
            );
            if p == Planner::Ga {
                assert_eq!(a.conflicts, 0, "{a:?}");
            }
        }
        let astar = answer(Planner::AStar, GaOptions::default(), &tg, c(0, 1), c(6, 1)).unwrap();
        assert_eq!((astar.length, astar.conflicts), (6.0, 1));
    }
}
