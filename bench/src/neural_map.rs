//! Neural-map speed: builds to full activation on open grids, and plan queries.
//!
//! `cargo run --release -p hnav-bench -- neural-map [--quick]`
//!
//! Prints, per grid size and activation: sweeps, neuron updates, time per map and neuron
//! updates per second (one core), for the target in the centre and in a corner; then single
//! plan queries (map + path) corner to corner. Each figure is the best of several runs.
//! `HNAV_SIMD=avx2` or `HNAV_SIMD=baseline` caps the kernel's instruction set.

use std::time::Instant;

use hnav_agent::neural_map::{Activation, NeuralDynamics, NeuralMap, NeuralMapOptions, StopRule};
use hnav_agent::plan::{PlanOptions, Planner};
use hnav_runtime::grid::{Cell, Grid};

/// Grid sides measured: the dissertation's 20x20 up to 1024x1024.
const SIDES: [u32; 4] = [20, 128, 512, 1024];

/// The sides of a run: `quick` (the smoke check the performance suite's test runs, where the
/// code may be unoptimised) leaves out 1024x1024, whose three runs a point would take most
/// of its time.
fn sides(quick: bool) -> &'static [u32] {
    if quick {
        &SIDES[..3]
    } else {
        &SIDES
    }
}

/// Runs the benchmark and prints its tables; `quick` spends 0.05 s instead of 0.3 s a point
/// and stops at 512x512.
pub fn run(quick: bool) {
    hnav_runtime::outln!(
        "{:>10} {:>7} {:>7} {:>7} {:>14} {:>12} {:>12}",
        "grid",
        "act",
        "target",
        "sweeps",
        "updates",
        "time/map",
        "updates/s"
    );
    for &n in sides(quick) {
        let grid = Grid::new(n, n).unwrap();
        for activation in [Activation::Tanh, Activation::Linear] {
            let opts = NeuralMapOptions {
                activation,
                ..NeuralMapOptions::default()
            };
            let mut map = NeuralMap::new(&grid, opts).unwrap();
            for (label, target) in [
                ("centre", Cell::new(n / 2, n / 2)),
                ("corner", Cell::new(0, 0)),
            ] {
                let budget = if quick { 0.05 } else { 0.3 };
                let (best, r) = best_of(budget, || {
                    map.build(target, StopRule::FullActivation).unwrap()
                });
                hnav_runtime::outln!(
                    "{:>10} {:>7} {:>7} {:>7} {:>14} {:>12} {:>12.3e}",
                    format!("{n}x{n}"),
                    format!("{activation:?}").to_lowercase(),
                    label,
                    r.sweeps,
                    r.cells_updated,
                    fmt_time(best),
                    r.cells_updated as f64 / best
                );
            }
        }
    }
    plans(sides(quick), if quick { 0.05 } else { 0.3 });
    hnav_runtime::outln!();
    hnav_runtime::outln!("tanh / linear time per map above is the dissertation's comparison (it reports up to 2.5x).");
}

/// Best-of-several wall time of `f`, with at least 3 runs and `budget` seconds in total.
fn best_of<T>(budget: f64, mut f: impl FnMut() -> T) -> (f64, T) {
    let (mut best, mut runs, mut total) = (f64::INFINITY, 0, 0.0);
    loop {
        let t0 = Instant::now();
        let out = f();
        let dt = t0.elapsed().as_secs_f64();
        best = best.min(dt);
        total += dt;
        runs += 1;
        if runs >= 3 && total >= budget {
            return (best, out);
        }
    }
}

fn plans(sides: &[u32], budget: f64) {
    hnav_runtime::outln!();
    hnav_runtime::outln!(
        "{:>10} {:>7} {:>7} {:>7} {:>12}",
        "grid",
        "act",
        "sweeps",
        "steps",
        "time/query"
    );
    for &n in sides {
        let grid = Grid::new(n, n).unwrap();
        for activation in [Activation::Tanh, Activation::Linear] {
            let options = PlanOptions {
                activation,
                ..PlanOptions::default()
            };
            let mut planner = Planner::new(&grid, &options).unwrap();
            let (s, g) = (Cell::new(0, 0), Cell::new(n - 1, n - 1));
            let (best, r) = best_of(budget, || planner.query(s, g).unwrap());
            hnav_runtime::outln!(
                "{:>10} {:>7} {:>7} {:>7} {:>12}",
                format!("{n}x{n}"),
                format!("{activation:?}").to_lowercase(),
                r.iterations,
                r.steps,
                fmt_time(best)
            );
        }
    }
}

fn fmt_time(s: f64) -> String {
    if s < 1e-3 {
        format!("{:.2} us", s * 1e6)
    } else if s < 1.0 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{s:.2} s")
    }
}
