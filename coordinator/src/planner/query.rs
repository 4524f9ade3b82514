//! Single planning queries, the library side of `hnav-bench plan --planner astar|theta|lazy-theta`.
//!
//! A query answers with the runtime's [`PlanResult`], as the agent's neural-map query does, so
//! the bench prints every planner the same way: `planner`, `found`, `steps`, `length`,
//! `iterations` (node expansions), `path` (a list of `[x, y]`) and `time_us`, plus
//! `los_checks` for a planner that made any. The open-list pushes are in
//! [`Planner::stats`].

use std::fmt;
use std::str::FromStr;
use std::time::Instant;

use hnav_runtime::grid::{Cell, CornerCutting, Grid};
use hnav_runtime::plan::PlanResult;

use super::astar::AStar;
use super::interface::{Planner, PlannerConfig};
use super::lazy_theta::LazyTheta;
use super::theta::BasicTheta;
use crate::error::PlanError;

/// The grid planners of this crate, by the names the bench and the scenario files use.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum PlannerKind {
    /// [`AStar`], `"astar"`.
    AStar,
    /// [`BasicTheta`], `"theta"`.
    Theta,
    /// [`LazyTheta`], `"lazy-theta"`.
    LazyTheta,
}

impl PlannerKind {
    /// All kinds, in the order of the seed-002 table (A*, Basic Theta*, Lazy Theta*).
    pub const ALL: [PlannerKind; 3] = [
        PlannerKind::AStar,
        PlannerKind::Theta,
        PlannerKind::LazyTheta,
    ];

    /// The canonical name: `"astar"`, `"theta"` or `"lazy-theta"`.
    pub fn name(self) -> &'static str {
        match self {
            PlannerKind::AStar => "astar",
            PlannerKind::Theta => "theta",
            PlannerKind::LazyTheta => "lazy-theta",
        }
    }

    /// A new planner of this kind.
    pub fn build(self, config: PlannerConfig) -> Box<dyn Planner + Send> {
        match self {
            PlannerKind::AStar => Box::new(AStar::new(config)),
            PlannerKind::Theta => Box::new(BasicTheta::new(config)),
            PlannerKind::LazyTheta => Box::new(LazyTheta::new(config)),
        }
    }
}

impl fmt::Display for PlannerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for PlannerKind {
    type Err = PlanError;

    /// Accepts the canonical names `astar`, `theta`, `lazy-theta`, case-insensitively, and
    /// the spellings `a*`, `basic-theta`, `theta*`, `lazy_theta`, `lazy-theta*`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "astar" | "a*" => Ok(PlannerKind::AStar),
            "theta" | "theta*" | "basic-theta" | "basic_theta" => Ok(PlannerKind::Theta),
            "lazy-theta" | "lazy_theta" | "lazy-theta*" | "lazytheta" => Ok(PlannerKind::LazyTheta),
            _ => Err(PlanError::UnknownPlanner { name: s.into() }),
        }
    }
}

/// Runs one query with a fresh planner of the given kind and no hazard model.
///
/// ```
/// use hnav_coordinator::planner::{run_query, PlannerKind};
/// use hnav_runtime::grid::{Cell, CornerCutting, Grid};
/// let g = Grid::new(8, 8).unwrap();
/// let kind: PlannerKind = "lazy-theta".parse().unwrap();
/// let r = run_query(kind, &g, Cell::new(0, 0), Cell::new(7, 3), CornerCutting::Forbidden).unwrap();
/// assert!(r.found);
/// assert_eq!(r.steps, 1);
/// let json = serde_json::to_string(&r).unwrap();
/// assert!(json.contains(r#""path":[[0,0],[7,3]]"#));
/// ```
pub fn run_query(
    kind: PlannerKind,
    grid: &Grid,
    start: Cell,
    goal: Cell,
    corner_cutting: CornerCutting,
) -> Result<PlanResult, PlanError> {
    let mut planner = kind.build(PlannerConfig::new(corner_cutting));
    run_query_with(planner.as_mut(), grid, start, goal)
}

/// Runs one query with a given planner (reusing its buffers and its configuration, hazard
/// model included) and times it. `iterations` are the node expansions; `los_checks` is `None`
/// for a planner that made none (A*).
pub fn run_query_with(
    planner: &mut dyn Planner,
    grid: &Grid,
    start: Cell,
    goal: Cell,
) -> Result<PlanResult, PlanError> {
    let t0 = Instant::now();
    let path = planner.plan(grid, start, goal)?;
    let time_us = t0.elapsed().as_secs_f64() * 1e6;
    let stats = planner.stats();
    let (found, steps, length, path) = match path {
        Some(p) => (true, p.steps(), p.length, p.cells),
        None => (false, 0, 0.0, Vec::new()),
    };
    Ok(PlanResult {
        planner: planner.name().into(),
        found,
        steps,
        length,
        iterations: stats.expansions,
        path,
        time_us,
        los_checks: (stats.los_checks > 0).then_some(stats.los_checks),
        optimal: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for k in PlannerKind::ALL {
            assert_eq!(k.name().parse::<PlannerKind>(), Ok(k));
            assert_eq!(k.to_string(), k.name());
            assert_eq!(k.build(PlannerConfig::default()).name(), k.name());
        }
        assert_eq!("A*".parse::<PlannerKind>(), Ok(PlannerKind::AStar));
        assert_eq!(
            "dijkstra".parse::<PlannerKind>(),
            Err(PlanError::UnknownPlanner {
                name: "dijkstra".into()
            })
        );
    }

    #[test]
    fn not_found_and_errors() {
        let mut g = Grid::new(3, 3).unwrap();
        for y in 0..3 {
            g.set_blocked(Cell::new(1, y), true);
        }
        let r = run_query(
            PlannerKind::Theta,
            &g,
            Cell::new(0, 0),
            Cell::new(2, 2),
            CornerCutting::Allowed,
        )
        .unwrap();
        assert!(!r.found);
        assert_eq!((r.steps, r.length, r.path.len()), (0, 0.0, 0));
        assert!(r.iterations > 0);
        let e = run_query(
            PlannerKind::AStar,
            &g,
            Cell::new(0, 0),
            Cell::new(1, 1),
            CornerCutting::Forbidden,
        )
        .unwrap_err();
        assert_eq!(e.to_string(), "goal [1, 1] is on a blocked cell");
    }
}
