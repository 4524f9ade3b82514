//! Property tests on random small grids.
//!
//! * A* equals the runtime's oracle under both corner rules, and with a hazard model it
//!   equals a plain Dijkstra over the same move costs.
//! * Basic Theta* never costs more than A* (a theorem: its update is never worse than A*'s
//!   from the same node, and the Euclidean heuristic is consistent); Lazy Theta* finds a path
//!   whenever they do; every any-angle path is valid.
//! * Planners reused across grids of different sizes (generation-stamped buffers) answer
//!   exactly like fresh ones.

use std::sync::Arc;

use hnav_coordinator::planner::{
    check_path, AStar, BasicTheta, LazyTheta, Path, Planner, PlannerConfig,
};
use hnav_coordinator::terrain::HazardMap;
use hnav_runtime::grid::{octile_shortest_path_len, Cell, CornerCutting, Grid};
use proptest::prelude::*;

#[derive(Clone, Debug)]
struct Case {
    grid: Grid,
    start: Cell,
    goal: Cell,
    rule: CornerCutting,
    hazard: Vec<f32>,
}

fn case() -> impl Strategy<Value = Case> {
    (2u32..14, 2u32..14, 0.0f64..0.45, any::<bool>()).prop_flat_map(|(w, h, p, allowed)| {
        let n = (w * h) as usize;
        (
            prop::collection::vec(prop::bool::weighted(p), n),
            prop::collection::vec(
                prop_oneof![4 => 0.0f32..1.0, 1 => Just(0.0f32), 1 => Just(f32::INFINITY)],
                n,
            ),
            0..n,
            0..n,
        )
            .prop_map(move |(mut blocked, hazard, s, t)| {
                blocked[s] = false;
                blocked[t] = false;
                let grid = Grid::from_blocked(w, h, &blocked).unwrap();
                let cell = |i: usize| grid.cell_at(i).unwrap();
                let (start, goal) = (cell(s), cell(t));
                let rule = if allowed {
                    CornerCutting::Allowed
                } else {
                    CornerCutting::Forbidden
                };
                Case {
                    grid,
                    start,
                    goal,
                    rule,
                    hazard,
                }
            })
    })
}

/// Dijkstra over A*'s moves and costs (the hazard halves of both end cells per move).
fn dijkstra(c: &Case, hz: &HazardMap) -> Option<f64> {
    let g = &c.grid;
    let obstacle = |cell: Cell| g.is_blocked(cell) || hz.is_impassable(cell);
    if obstacle(c.start) || obstacle(c.goal) {
        return None;
    }
    let mut dist = vec![f64::INFINITY; g.len()];
    let mut done = vec![false; g.len()];
    dist[g.index(c.start)] = 0.0;
    loop {
        let (i, d) = (0..g.len())
            .filter(|&i| !done[i] && dist[i].is_finite())
            .map(|i| (i, dist[i]))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        if i == g.index(c.goal) {
            return Some(d);
        }
        done[i] = true;
        let cell = g.cell_at(i).unwrap();
        for (dir, n) in g.neighbours(cell, c.rule) {
            if hz.is_impassable(n) {
                continue;
            }
            // can_move only knows blocked cells: the hazard's impassable corners count too.
            if dir.is_diagonal() {
                let sides = [Cell::new(n.x, cell.y), Cell::new(cell.x, n.y)];
                let blocked = sides.iter().filter(|&&s| obstacle(s)).count();
                if c.rule == CornerCutting::Forbidden && blocked > 0 {
                    continue;
                }
            }
            let r = |x: Cell| f64::from(hz.hazard(x).unwrap());
            let nd = d + dir.cost() + hz.weight() * 0.5 * (r(cell) + r(n));
            let j = g.index(n);
            if nd < dist[j] {
                dist[j] = nd;
            }
        }
    }
}

/// Objective of a path under a hazard map: length plus weighted hazard, without the start's
/// and goal's halves that every route shares.
fn objective(p: &Path, hz: &HazardMap) -> f64 {
    let ends = 0.5 * f64::from(hz.hazard(p.cells[0]).unwrap())
        + 0.5 * f64::from(hz.hazard(*p.cells.last().unwrap()).unwrap());
    p.length + hz.weight() * (hz.route_hazard(&p.cells).unwrap() - ends)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, rng_seed: proptest::test_runner::RngSeed::Fixed(hnav_runtime::hash::test_seed(0xc0de)), ..ProptestConfig::default() })]

    #[test]
    fn planners_agree_with_references(c in case()) {
        let cfg = PlannerConfig::new(c.rule);
        let mut astar = AStar::new(cfg.clone());
        let mut basic = BasicTheta::new(cfg.clone());
        let mut lazy = LazyTheta::new(cfg);
        let a = astar.plan(&c.grid, c.start, c.goal).unwrap();
        let want = octile_shortest_path_len(&c.grid, c.start, c.goal, c.rule);
        prop_assert_eq!(a.is_some(), want.is_some());
        if let (Some(p), Some(w)) = (&a, want) {
            prop_assert!((p.length - w).abs() < 1e-9);
        }
        let b = basic.plan(&c.grid, c.start, c.goal).unwrap();
        let l = lazy.plan(&c.grid, c.start, c.goal).unwrap();
        prop_assert_eq!(b.is_some(), l.is_some());
        if c.rule == CornerCutting::Forbidden {
            // Same moves as A*, so the same cells are reachable.
            prop_assert_eq!(b.is_some(), a.is_some());
            if let (Some(b), Some(a)) = (&b, &a) {
                prop_assert!(b.length <= a.length + 1e-9, "{} > {}", b.length, a.length);
            }
        }
        for p in [&b, &l].into_iter().flatten() {
            prop_assert_eq!(check_path(&c.grid, None, c.rule, &p.cells, c.start, c.goal), Ok(()));
        }

        // The same planners, reused on a different grid, answer like fresh ones.
        let other = Grid::new(c.grid.width() + 3, c.grid.height() + 1).unwrap();
        let (s2, g2) = (Cell::new(0, 0), Cell::new(c.grid.width() + 2, c.grid.height()));
        prop_assert_eq!(
            lazy.plan(&other, s2, g2).unwrap(),
            LazyTheta::new(PlannerConfig::new(c.rule)).plan(&other, s2, g2).unwrap()
        );
        prop_assert_eq!(lazy.plan(&c.grid, c.start, c.goal).unwrap(), l);
        prop_assert_eq!(astar.plan(&c.grid, c.start, c.goal).unwrap(), a);
    }

    #[test]
    fn hazard_planners_are_optimal_or_valid(c in case()) {
        let (w, h) = (c.grid.width(), c.grid.height());
        let hz = Arc::new(HazardMap::new(w, h, c.hazard.clone(), 2.0).unwrap());
        let cfg = PlannerConfig::new(c.rule).with_hazard(hz.clone());
        let endpoints_ok = !hz.is_impassable(c.start) && !hz.is_impassable(c.goal);
        let mut astar = AStar::new(cfg.clone());
        let a = astar.plan(&c.grid, c.start, c.goal);
        if !endpoints_ok {
            prop_assert!(a.is_err());
            return Ok(());
        }
        let a = a.unwrap();
        let want = dijkstra(&c, &hz);
        prop_assert_eq!(a.is_some(), want.is_some());
        if let (Some(p), Some(w)) = (&a, want) {
            prop_assert!((objective(p, &hz) - w).abs() < 1e-6, "{} vs {}", objective(p, &hz), w);
        }
        let b = BasicTheta::new(cfg.clone()).plan(&c.grid, c.start, c.goal).unwrap();
        let l = LazyTheta::new(cfg).plan(&c.grid, c.start, c.goal).unwrap();
        prop_assert_eq!(b.is_some(), l.is_some());
        if c.rule == CornerCutting::Forbidden {
            prop_assert_eq!(b.is_some(), a.is_some());
            if let (Some(b), Some(a)) = (&b, &a) {
                prop_assert!(objective(b, &hz) <= objective(a, &hz) + 1e-6);
            }
        }
        for p in [&b, &l].into_iter().flatten() {
            prop_assert_eq!(
                check_path(&c.grid, Some(&hz), c.rule, &p.cells, c.start, c.goal),
                Ok(())
            );
        }
    }
}
