//! Times neural-map builds to full activation on open grids (run with `--release`).
//!
//! `cargo run --release -p hnav-agent --example sweep_speed [-- --quick]`
//!
//! Prints, per grid size and activation: sweeps, neuron updates, time per map and neuron
//! updates per second (one core), for the target in the centre and in a corner.

use std::time::Instant;

use hnav_agent::neural_map::{
    Activation, NeuralDynamics, NeuralMap, NeuralMapOptions, StopRule,
};
use hnav_runtime::grid::{Cell, Grid};

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    println!(
        "{:>10} {:>7} {:>7} {:>7} {:>14} {:>12} {:>12}",
        "grid", "act", "target", "sweeps", "updates", "time/map", "updates/s"
    );
    for n in [20u32, 128, 512, 1024] {
        let grid = Grid::new(n, n).unwrap();
        for activation in [Activation::Tanh, Activation::Linear] {
            let opts = NeuralMapOptions {
                activation,
                ..NeuralMapOptions::default()
            };
            let mut map = NeuralMap::new(&grid, opts).unwrap();
            for (label, target) in [("centre", Cell::new(n / 2, n / 2)), ("corner", Cell::new(0, 0))] {
                // Repeat until ~0.3 s (at least 3 runs), keep the best run.
                let budget = if quick { 0.05 } else { 0.3 };
                let (mut best, mut runs, mut total) = (f64::INFINITY, 0, 0.0);
                let mut report = None;
                while runs < 3 || total < budget {
                    let t0 = Instant::now();
                    let r = map.build(target, StopRule::FullActivation).unwrap();
                    let dt = t0.elapsed().as_secs_f64();
                    best = best.min(dt);
                    total += dt;
                    runs += 1;
                    report = Some(r);
                }
                let r = report.unwrap();
                println!(
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
