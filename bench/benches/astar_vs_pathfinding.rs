//! Our A* against the `pathfinding` crate's A* on the same MovingAI queries.
//!
//! `cargo bench -p hnav-bench --bench astar_vs_pathfinding [-- PASSES]`
//!
//! Both answer every entry of the two shipped `.scen` files (octile moves, no corner cutting)
//! and must agree with the scenario's optimal length. `pathfinding` needs integer costs, so
//! its moves cost 10^9 and round(√2·10^9); its lengths are checked to 1e-6.
//! Passes alternate between the implementations so machine load hits both alike; the best
//! pass of each is reported (the least disturbed), and the median beside it.

use std::time::Instant;

use hnav_coordinator::planner::{AStar, Planner, PlannerConfig};
use hnav_runtime::grid::{read_map_file, read_scen_file, Cell, CornerCutting, Grid};

const SCALE: f64 = 1_000_000_000.0;

struct Case {
    grid: Grid,
    queries: Vec<(Cell, Cell, f64)>,
}

fn load() -> Vec<Case> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../maps");
    ["random-32-32-10", "random-32-32-20"]
        .iter()
        .map(|name| {
            let grid = read_map_file(format!("{dir}/{name}.map")).expect("shipped map");
            let scen = read_scen_file(format!("{dir}/{name}-random-1.scen")).expect("shipped scen");
            let queries = scen
                .entries
                .iter()
                .map(|e| (e.start, e.goal, e.optimal_length))
                .collect();
            Case { grid, queries }
        })
        .collect()
}

fn ours(cases: &[Case], planner: &mut AStar) -> f64 {
    let mut total = 0.0;
    for case in cases {
        for &(s, g, opt) in &case.queries {
            let path = planner
                .plan(&case.grid, s, g)
                .expect("valid query")
                .expect("path");
            assert!(
                (path.length - opt).abs() < 1e-6,
                "ours {} vs optimal {opt}",
                path.length
            );
            total += path.length;
        }
    }
    total
}

fn ours_fresh(cases: &[Case]) -> f64 {
    let mut total = 0.0;
    for case in cases {
        for &(s, g, _) in &case.queries {
            let mut planner = AStar::new(PlannerConfig::new(CornerCutting::Forbidden));
            total += planner.plan(&case.grid, s, g).unwrap().unwrap().length;
        }
    }
    total
}

fn theirs(cases: &[Case]) -> f64 {
    let straight = SCALE as u64;
    let diagonal = (SCALE * std::f64::consts::SQRT_2).round() as u64;
    let mut total = 0.0;
    for case in cases {
        let grid = &case.grid;
        for &(s, g, opt) in &case.queries {
            let h = |c: &Cell| {
                let dx = c.x.abs_diff(g.x) as u64;
                let dy = c.y.abs_diff(g.y) as u64;
                straight * dx.max(dy) + (diagonal - straight) * dx.min(dy)
            };
            let (_, cost) = pathfinding::prelude::astar(
                &s,
                |c| {
                    grid.neighbours(*c, CornerCutting::Forbidden)
                        .map(|(d, n)| (n, if d.is_diagonal() { diagonal } else { straight }))
                        .collect::<Vec<_>>()
                },
                h,
                |c| *c == g,
            )
            .expect("path");
            let len = cost as f64 / SCALE;
            assert!(
                (len - opt).abs() < 1e-6,
                "pathfinding {len} vs optimal {opt}"
            );
            total += len;
        }
    }
    total
}

fn timed(f: impl FnOnce() -> f64) -> f64 {
    let t0 = Instant::now();
    std::hint::black_box(f());
    t0.elapsed().as_secs_f64() * 1e3
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let passes: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(30);
    let cases = load();
    let n: usize = cases.iter().map(|c| c.queries.len()).sum();
    let mut planner = AStar::new(PlannerConfig::new(CornerCutting::Forbidden));
    let (mut a, mut b, mut c) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..passes {
        a.push(timed(|| ours(&cases, &mut planner)));
        b.push(timed(|| ours_fresh(&cases)));
        c.push(timed(|| theirs(&cases)));
    }
    let best = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let (ba, bb, bc) = (best(&a), best(&b), best(&c));
    let (ma, mb, mc) = (median(&mut a), median(&mut b), median(&mut c));
    println!("A* on {n} MovingAI queries (random-32-32-10/20 .scen), {passes} passes, ms per pass");
    println!(
        "{:<34} {:>9} {:>9} {:>11}",
        "implementation", "best", "median", "best ratio"
    );
    println!(
        "{:<34} {:>9.3} {:>9.3} {:>11.3}",
        "hnav A* (buffers reused)",
        ba,
        ma,
        ba / bc
    );
    println!(
        "{:<34} {:>9.3} {:>9.3} {:>11.3}",
        "hnav A* (new planner per query)",
        bb,
        mb,
        bb / bc
    );
    println!(
        "{:<34} {:>9.3} {:>9.3} {:>11.3}",
        "pathfinding 4 astar", bc, mc, 1.0
    );
}
