//! One query measured with every planner of the comparison: the figures that do not depend
//! on the machine (found, steps, length, sweeps or expansions) once, and the wall time of
//! many repetitions as a median with its spread.
//!
//! Both planners are timed the same way, as the dissertation presumably did in Python: one
//! whole call with a fresh planner ([`plan_query`] allocates the neural map, builds it and
//! climbs it; [`run_query`] builds an [`AStar`](hnav_coordinator::planner::AStar) and
//! searches). The repetitions interleave the planners, each round starting with the next
//! one, so that a burst of load on the shared machine hits all of them alike.

use std::time::Instant;

use anyhow::{Context, Result};
use hnav_agent::neural_map::Activation;
use hnav_agent::plan::{plan_query, PlanOptions, PlanStop};
use hnav_coordinator::planner::{run_query, PlannerKind};
use hnav_runtime::grid::{Cell, CornerCutting, Grid};
use hnav_runtime::plan::PlanResult;
use serde::Serialize;

/// A planner of the comparison.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Variant {
    /// The coordinator's octile A*.
    AStar,
    /// The agent's neural map and path constructor with an activation and a stop rule,
    /// spelled as `hnav-bench plan --activation` and `--stop` spell them.
    Hnav(Activation, PlanStop),
}

/// The planners, in the tables' order: A*, then the dissertation's modified network (linear,
/// partial) first and the original (tanh, full) last.
pub const VARIANTS: [Variant; 5] = [
    Variant::AStar,
    Variant::Hnav(Activation::Linear, PlanStop::Partial),
    Variant::Hnav(Activation::Linear, PlanStop::Full),
    Variant::Hnav(Activation::Tanh, PlanStop::Partial),
    Variant::Hnav(Activation::Tanh, PlanStop::Full),
];

/// Index in [`VARIANTS`] of A*.
pub const ASTAR: usize = 0;
/// Index of HNAV as Table 3-8 ran it (linear activation, partial activation).
pub const HNAV_LINEAR_PARTIAL: usize = 1;
/// Index of linear activation, full activation.
pub const HNAV_LINEAR_FULL: usize = 2;
/// Index of tanh activation, partial activation.
pub const HNAV_TANH_PARTIAL: usize = 3;
/// Index of tanh activation, full activation.
pub const HNAV_TANH_FULL: usize = 4;

impl Variant {
    /// `astar` or `hnav <activation> <stop>`, in the command line's words.
    pub fn name(self) -> String {
        match self {
            Variant::AStar => "astar".to_string(),
            Variant::Hnav(a, s) => {
                let a = match a {
                    Activation::Linear => "linear",
                    Activation::Tanh => "tanh",
                };
                let s = match s {
                    PlanStop::Partial => "partial",
                    PlanStop::Full => "full",
                };
                format!("hnav {a} {s}")
            }
        }
    }

    /// One whole query with a fresh planner. Corners are never cut: the dissertation's
    /// strict diagonal rule (§3.3.2) and MovingAI's are the same rule.
    pub fn query(self, grid: &Grid, start: Cell, goal: Cell) -> Result<PlanResult> {
        let corners = CornerCutting::Forbidden;
        Ok(match self {
            Variant::AStar => run_query(PlannerKind::AStar, grid, start, goal, corners)?,
            Variant::Hnav(activation, stop) => {
                let options = PlanOptions {
                    activation,
                    stop,
                    corner_cutting: corners,
                };
                plan_query(grid, start, goal, &options)?
            }
        })
    }
}

/// What a planner answered: the same on every machine and every run.
#[derive(Clone, PartialEq, Debug, Serialize)]
pub struct Figures {
    /// The planner, as [`Variant::name`] spells it.
    pub planner: String,
    /// Whether it reached the goal.
    pub found: bool,
    /// Moves of the path.
    pub steps: usize,
    /// Length of the path, straight 1 and diagonal `sqrt 2`.
    pub length: f64,
    /// Neural-map sweeps (HNAV) or node expansions (A*).
    pub iterations: u64,
}

/// Wall times of the repetitions of one query, in microseconds.
#[derive(Clone, PartialEq, Debug, Serialize)]
pub struct Timing {
    /// The planner, as [`Variant::name`] spells it.
    pub planner: String,
    /// Repetitions timed.
    pub repetitions: usize,
    /// Median.
    pub median_us: f64,
    /// First quartile.
    pub p25_us: f64,
    /// Third quartile.
    pub p75_us: f64,
    /// Fastest repetition.
    pub min_us: f64,
}

/// Every planner on one query.
#[derive(Clone, Debug)]
pub struct Measured {
    /// Per planner of [`VARIANTS`].
    pub figures: Vec<Figures>,
    /// Per planner of [`VARIANTS`].
    pub timings: Vec<Timing>,
}

/// Answers the query once with every planner for the figures, then `repetitions` times more
/// for the times. A repetition whose path differs from the first answer is an error: the
/// planners are deterministic, and a table built on a flaky answer would be wrong.
pub fn measure(grid: &Grid, start: Cell, goal: Cell, repetitions: usize) -> Result<Measured> {
    let n = VARIANTS.len();
    let mut figures = Vec::with_capacity(n);
    let mut paths = Vec::with_capacity(n);
    for v in VARIANTS {
        let r = v
            .query(grid, start, goal)
            .with_context(|| format!("{} from {start} to {goal}", v.name()))?;
        figures.push(Figures {
            planner: v.name(),
            found: r.found,
            steps: r.steps,
            length: r.length,
            iterations: r.iterations,
        });
        paths.push(r.path);
    }
    let mut samples = vec![Vec::with_capacity(repetitions); n];
    for round in 0..repetitions {
        for k in 0..n {
            let i = (round + k) % n;
            let t0 = Instant::now();
            let r = VARIANTS[i].query(grid, start, goal)?;
            samples[i].push(t0.elapsed().as_secs_f64() * 1e6);
            if r.path != paths[i] {
                anyhow::bail!(
                    "{} from {start} to {goal} answered two different paths",
                    VARIANTS[i].name()
                );
            }
        }
    }
    let timings = samples
        .iter_mut()
        .zip(VARIANTS)
        .map(|(s, v)| timing(v.name(), s))
        .collect();
    Ok(Measured { figures, timings })
}

fn timing(planner: String, samples: &mut [f64]) -> Timing {
    samples.sort_by(f64::total_cmp);
    Timing {
        planner,
        repetitions: samples.len(),
        median_us: quantile(samples, 0.5),
        p25_us: quantile(samples, 0.25),
        p75_us: quantile(samples, 0.75),
        min_us: samples.first().copied().unwrap_or(f64::NAN),
    }
}

/// The `q` quantile of sorted `xs` by linear interpolation between order statistics; NaN
/// for no samples.
pub fn quantile(xs: &[f64], q: f64) -> f64 {
    match xs.len() {
        0 => f64::NAN,
        n => {
            let at = q.clamp(0.0, 1.0) * (n - 1) as f64;
            let (lo, hi) = (at.floor() as usize, at.ceil() as usize);
            xs[lo] + (xs[hi] - xs[lo]) * (at - lo as f64)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_interpolate() {
        let xs = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(quantile(&xs, 0.5), 2.5);
        assert_eq!(quantile(&xs, 0.0), 1.0);
        assert_eq!(quantile(&xs, 1.0), 4.0);
        assert!(quantile(&[], 0.5).is_nan());
    }

    #[test]
    fn every_planner_answers_an_open_grid_optimally() {
        let g = Grid::new(6, 4).unwrap();
        let m = measure(&g, Cell::new(0, 0), Cell::new(5, 3), 2).unwrap();
        assert_eq!(m.figures.len(), VARIANTS.len());
        for f in &m.figures {
            assert!(f.found, "{f:?}");
            assert_eq!(f.steps, 5, "{f:?}");
            assert!((f.length - (2.0 + 3.0 * std::f64::consts::SQRT_2)).abs() < 1e-9);
        }
        assert!(m
            .timings
            .iter()
            .all(|t| t.repetitions == 2 && t.min_us > 0.0));
        assert_eq!(m.figures[HNAV_TANH_FULL].planner, "hnav tanh full");
    }
}
