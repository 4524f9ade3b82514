//! Runs A*, Basic Theta* and Lazy Theta* on every query of the two MovingAI `random-32-32`
//! scenario files in `maps/` and prints timing, optimality and the Theta*/Lazy Theta*
//! comparison (totals and per-query distributions).
//!
//! ```text
//! cargo run --release -p hnav-coordinator --example movingai_planners [-- --repeat 20]
//! ```
//!
//! `--repeat N` runs the whole query set N times per planner and reports the best pass, which
//! steadies the timing on a busy machine.

use std::time::Instant;

use hnav_coordinator::planner::{AStar, BasicTheta, LazyTheta, Path, Planner, PlannerConfig};
use hnav_runtime::grid::{
    octile_shortest_path_len, read_map_file, read_scen_file, Cell, CornerCutting, Grid,
};

const SETS: [(&str, &str); 2] = [
    ("random-32-32-10.map", "random-32-32-10-random-1.scen"),
    ("random-32-32-20.map", "random-32-32-20-random-1.scen"),
];

struct Query {
    grid: usize,
    start: Cell,
    goal: Cell,
    optimal: f64,
}

/// Runs every query once; returns the paths, per-query stats and the wall time in µs.
fn pass(
    planner: &mut dyn Planner,
    grids: &[Grid],
    queries: &[Query],
) -> (Vec<(Path, u64, u64)>, f64) {
    let t0 = Instant::now();
    let mut out = Vec::with_capacity(queries.len());
    for q in queries {
        let path = planner
            .plan(&grids[q.grid], q.start, q.goal)
            .expect("valid query")
            .expect("scen queries are solvable");
        let s = planner.stats();
        out.push((path, s.expansions, s.los_checks));
    }
    (out, t0.elapsed().as_secs_f64() * 1e6)
}

fn percentiles(mut v: Vec<f64>) -> String {
    v.sort_by(f64::total_cmp);
    let at = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    format!(
        "min {:.4}  p10 {:.4}  median {:.4}  p90 {:.4}  max {:.4}",
        at(0.0),
        at(0.1),
        at(0.5),
        at(0.9),
        at(1.0)
    )
}

fn main() {
    let repeat: usize = std::env::args()
        .skip_while(|a| a != "--repeat")
        .nth(1)
        .and_then(|v| v.parse().ok())
        .unwrap_or(10);
    let maps = concat!(env!("CARGO_MANIFEST_DIR"), "/../maps/");
    let mut grids = Vec::new();
    let mut queries = Vec::new();
    for (gi, (map, scen)) in SETS.iter().enumerate() {
        grids.push(read_map_file(format!("{maps}{map}")).expect("map"));
        for e in read_scen_file(format!("{maps}{scen}"))
            .expect("scen")
            .entries
        {
            queries.push(Query {
                grid: gi,
                start: e.start,
                goal: e.goal,
                optimal: e.optimal_length,
            });
        }
    }
    println!(
        "{} queries, best of {repeat} passes per planner",
        queries.len()
    );
    let mut planners: Vec<Box<dyn Planner>> = vec![
        Box::new(AStar::new(PlannerConfig::default())),
        Box::new(BasicTheta::new(PlannerConfig::default())),
        Box::new(LazyTheta::new(PlannerConfig::default())),
    ];
    let mut results = Vec::new();
    for p in planners.iter_mut() {
        let mut best = f64::INFINITY;
        let mut paths = Vec::new();
        for _ in 0..repeat.max(1) {
            let (r, us) = pass(p.as_mut(), &grids, &queries);
            best = best.min(us);
            paths = r;
        }
        let exp: u64 = paths.iter().map(|r| r.1).sum();
        let los: u64 = paths.iter().map(|r| r.2).sum();
        let len: f64 = paths.iter().map(|r| r.0.length).sum();
        println!(
            "{:<11} total {:>9.0} µs ({:>6.2} µs/query)  length {:>10.3}  expansions {:>7}  LOS checks {:>7}",
            p.name(),
            best,
            best / queries.len() as f64,
            len,
            exp,
            los
        );
        results.push(paths);
    }
    // Reference: the runtime's simple oracle A* (fresh buffers per query, lazy-deletion heap).
    let mut best = f64::INFINITY;
    for _ in 0..repeat.max(1) {
        let t0 = Instant::now();
        for q in &queries {
            let len =
                octile_shortest_path_len(&grids[q.grid], q.start, q.goal, CornerCutting::Forbidden);
            assert!(len.is_some());
        }
        best = best.min(t0.elapsed().as_secs_f64() * 1e6);
    }
    println!(
        "{:<11} total {:>9.0} µs ({:>6.2} µs/query)  (hnav_runtime::grid::octile_shortest_path_len, for reference)",
        "oracle", best, best / queries.len() as f64
    );
    let worst_gap = queries
        .iter()
        .zip(&results[0])
        .map(|(q, r)| (r.0.length - q.optimal).abs())
        .fold(0.0, f64::max);
    println!("A*: largest |length - optimal| = {worst_gap:.2e}");
    let (astar, basic, lazy) = (&results[0], &results[1], &results[2]);
    let ratio = |a: &[(Path, u64, u64)], b: &[(Path, u64, u64)]| -> Vec<f64> {
        a.iter()
            .zip(b)
            .map(|(x, y)| x.0.length / y.0.length)
            .collect()
    };
    let theta_over_astar = ratio(basic, astar);
    let lazy_over_basic = ratio(lazy, basic);
    println!(
        "Theta*/A* length per query:      {}",
        percentiles(theta_over_astar.clone())
    );
    println!(
        "  longer than A*: {}",
        theta_over_astar
            .iter()
            .filter(|&&r| r > 1.0 + 1e-12)
            .count()
    );
    println!(
        "Lazy/Basic length per query:    {}",
        percentiles(lazy_over_basic.clone())
    );
    println!(
        "  Lazy shorter: {}, equal: {}, longer: {}",
        lazy_over_basic.iter().filter(|&&r| r < 1.0 - 1e-12).count(),
        lazy_over_basic
            .iter()
            .filter(|&&r| (r - 1.0).abs() <= 1e-12)
            .count(),
        lazy_over_basic.iter().filter(|&&r| r > 1.0 + 1e-12).count()
    );
    let los_ratio: Vec<f64> = lazy
        .iter()
        .zip(basic)
        .filter(|(_, b)| b.2 > 0)
        .map(|(l, b)| l.2 as f64 / b.2 as f64)
        .collect();
    println!(
        "Lazy/Basic LOS checks per query: {}",
        percentiles(los_ratio)
    );
    let exp_ratio: Vec<f64> = lazy
        .iter()
        .zip(basic)
        .map(|(l, b)| l.1 as f64 / b.1 as f64)
        .collect();
    println!(
        "Lazy/Basic expansions per query: {}",
        percentiles(exp_ratio)
    );
}
