//! How long the gradient-ascent paths are compared with the octile shortest path, on random
//! maps (0-30 % obstacles, 8..=64 cells a side), for each map variant.
//!
//! `cargo run --release -p hnav-agent --example path_quality [-- CASES]` (default 2000)
//!
//! Prints per variant: cases solved, share optimal, mean / p95 / max of `length / shortest`,
//! and the worst case. Unsolved solvable cases would be printed as failures.

use hnav_agent::neural_map::{Activation, Denominator, NeuralMapOptions, Weights};
use hnav_agent::path_constructor::PathOptions;
use hnav_agent::plan::{PlanStop, Planner};
use hnav_runtime::grid::{octile_shortest_path_len, Cell, CornerCutting, Grid};

/// A xorshift generator: reproducible cases without an RNG dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: u32) -> u32 {
        (self.next() % u64::from(n)) as u32
    }
}

fn case(rng: &mut Rng) -> (Grid, Cell, Cell) {
    let (w, h) = (8 + rng.below(57), 8 + rng.below(57));
    let pct = rng.below(31);
    let blocked: Vec<bool> = (0..w * h).map(|_| rng.below(100) < pct).collect();
    let mut g = Grid::from_blocked(w, h, &blocked).unwrap();
    let s = Cell::new(rng.below(w), rng.below(h));
    let t = Cell::new(rng.below(w), rng.below(h));
    g.set_blocked(s, false);
    g.set_blocked(t, false);
    (g, s, t)
}

fn main() {
    let cases: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(2000);
    println!("{cases} random maps per variant");
    for corner in [CornerCutting::Forbidden, CornerCutting::Allowed] {
        for activation in [Activation::Tanh, Activation::Linear] {
            for denominator in [
                Denominator::LinkedOnly,
                Denominator::InGrid,
                Denominator::OffGridAsZero,
                Denominator::AllEight,
            ] {
                for self_weight in [0.0, 1.0] {
                    for stop in [PlanStop::Partial, PlanStop::Full] {
                        let map = NeuralMapOptions {
                            activation,
                            denominator,
                            diagonals: corner.into(),
                            weights: Weights {
                                self_weight,
                                ..Weights::default()
                            },
                            ..NeuralMapOptions::default()
                        };
                        run(cases, corner, map, stop);
                    }
                }
            }
        }
    }
}

fn run(cases: usize, corner: CornerCutting, map: NeuralMapOptions, stop: PlanStop) {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut ratios: Vec<(f64, String)> = Vec::new();
    let mut failures = 0;
    let mut sweeps = 0u64;
    for _ in 0..cases {
        let (g, s, t) = case(&mut rng);
        let Some(shortest) = octile_shortest_path_len(&g, s, t, corner) else {
            continue;
        };
        let mut planner = Planner::with_options(&g, map, stop, PathOptions::default()).unwrap();
        let r = planner.query(s, t).unwrap();
        sweeps += r.iterations;
        if !r.found {
            failures += 1;
            continue;
        }
        if shortest > 0.0 {
            ratios.push((
                r.length / shortest,
                format!("{}x{} {s} -> {t}", g.width(), g.height()),
            ));
        }
    }
    ratios.sort_by(|a, b| a.0.total_cmp(&b.0));
    let n = ratios.len();
    let mean = ratios.iter().map(|r| r.0).sum::<f64>() / n as f64;
    let p95 = ratios[((n as f64 * 0.95).ceil() as usize).clamp(1, n) - 1].0;
    let optimal = ratios.iter().filter(|r| r.0 < 1.0 + 1e-9).count();
    let (max, worst) = &ratios[n - 1];
    println!(
        "{:<9} {:<6} {:<10} self {:.0} {:<7} n {n} optimal {:5.1} % mean {mean:.4} p95 {p95:.4} \
         max {max:.4} ({worst}) failures {failures} mean sweeps {:.1}",
        format!("{corner:?}"),
        format!("{:?}", map.activation),
        format!("{:?}", map.denominator),
        map.weights.self_weight,
        format!("{stop:?}"),
        100.0 * optimal as f64 / n as f64,
        sweeps as f64 / n as f64,
    );
}
