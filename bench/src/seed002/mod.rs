//! Seed 002, §4: A*, Basic Theta* and Lazy Theta* on a 50 x 50 m field with random circular
//! obstacles covering 10, 20 and 30 % of it, beside the thesis's Table 3.1.
//!
//! # Setup
//!
//! * **\[thesis\]** 50 x 50 m area, grid step 1 m (a 50 x 50 grid), random obstacles over 10 / 20 /
//!   30 % of the area, drawn as circles and inflated into "virtual obstacles"; metrics: path
//!   length `L` (m) and computation time `t` (s); planning on length alone (Table 3.1 gives no
//!   hazard).
//! * **\[inferred\]** Start and goal at the centres of opposite corner cells, (0.5, 0.5) m and
//!   (49.5, 49.5) m (the table's lengths suggest it). Circle centres uniform over the field,
//!   radii uniform in [`Seed002Config::radius`]; circles are added until the cells whose centres
//!   they cover reach the density (the last one may overshoot). The planning grid blocks every
//!   cell whose centre lies within `radius + inflation`. A circle whose inflated disc would
//!   cover the start or goal is redrawn. Maps on which the goal is unreachable are discarded
//!   and counted. Each density has its own ChaCha8 stream seeded from
//!   [`Seed002Config::seed`], so a report is reproducible. Corners may not be cut.
//! * The thesis reports single numbers from unspecified maps; ours are means over
//!   [`Seed002Config::trials`] maps. Its times are MATLAB seconds, ours Rust microseconds:
//!   compare ratios, not values. Extra metrics the notes ask for: expansions, line-of-sight
//!   checks, heading changes and total turn.

mod render;

use std::time::Instant;

use hnav_coordinator::planner::{heading_changes, PlannerConfig, PlannerKind};
use hnav_coordinator::PlanError;
use hnav_runtime::grid::geometry::{cell_centre_m, cell_index};
use hnav_runtime::grid::{Cell, CornerCutting, Grid};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Why the experiment could not run.
#[derive(Clone, PartialEq, Debug, thiserror::Error)]
pub enum Seed002Error {
    /// Parameters that cannot produce a map (a density out of range, radii out of order...).
    #[error("bad experiment parameters: {problem}")]
    BadParameters {
        /// What is wrong, in words.
        problem: String,
    },
    /// A planner refused a query.
    #[error(transparent)]
    Plan(#[from] PlanError),
}

/// Parameters of the experiment.
#[derive(Clone, PartialEq, Debug)]
pub struct Seed002Config {
    /// Side of the square field in cells of 1 m (50).
    pub side: u32,
    /// Obstacle densities, fractions of the area (0.10, 0.20, 0.30).
    pub densities: Vec<f64>,
    /// Solvable maps per density (100).
    pub trials: usize,
    /// Seed of the random streams (2).
    pub seed: u64,
    /// Smallest and largest obstacle radius, metres (1.0, 3.0). \[inferred\]
    pub radius: (f64, f64),
    /// Margin added to every obstacle's radius for the planning grid, metres (0.25: the
    /// s-bot's 0.058 m radius plus a safety margin). \[inferred\]
    pub inflation: f64,
    /// Timed runs of each query; the fastest counts (1).
    pub timing_repeats: usize,
    /// Corner rule of all planners (forbidden).
    pub corner_cutting: CornerCutting,
}

impl Default for Seed002Config {
    fn default() -> Self {
        Seed002Config {
            side: 50,
            densities: vec![0.10, 0.20, 0.30],
            trials: 100,
            seed: 2,
            radius: (1.0, 3.0),
            inflation: 0.25,
            timing_repeats: 1,
            corner_cutting: CornerCutting::Forbidden,
        }
    }
}

/// One row of the thesis's Table 3.1: `(L m, t s)` per planner.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct ThesisRow {
    /// Obstacle density, fraction of the area.
    pub density: f64,
    /// A*: length (m), time (s).
    pub astar: (f64, f64),
    /// Basic Theta*: length (m), time (s).
    pub basic_theta: (f64, f64),
    /// Lazy Theta*: length (m), time (s).
    pub lazy_theta: (f64, f64),
}

/// Table 3.1 of the thesis, verbatim (MATLAB, one unspecified map per row).
pub const THESIS_TABLE_3_1: [ThesisRow; 3] = [
    ThesisRow {
        density: 0.10,
        astar: (70.486, 0.207),
        basic_theta: (70.205, 0.305),
        lazy_theta: (70.202, 0.304),
    },
    ThesisRow {
        density: 0.20,
        astar: (72.801, 0.208),
        basic_theta: (72.206, 0.307),
        lazy_theta: (72.203, 0.306),
    },
    ThesisRow {
        density: 0.30,
        astar: (75.307, 0.209),
        basic_theta: (76.207, 0.309),
        lazy_theta: (76.204, 0.308),
    },
];

/// One planner's result on one map.
#[derive(Clone, Copy, PartialEq, Debug, Default)]
pub struct RunMetrics {
    /// Path length, metres.
    pub length: f64,
    /// Fastest of the timed runs, microseconds.
    pub time_us: f64,
    /// Node expansions.
    pub expansions: u64,
    /// Line-of-sight checks.
    pub los_checks: u64,
    /// Direction changes along the path.
    pub heading_changes: usize,
    /// Sum of the absolute turn angles, degrees.
    pub turn_deg: f64,
}

/// All planners on one map.
#[derive(Clone, PartialEq, Debug)]
pub struct Trial {
    /// Fraction of cells covered by the real (not inflated) obstacles.
    pub coverage: f64,
    /// Fraction of cells blocked in the planning grid (inflated obstacles).
    pub blocked: f64,
    /// One entry per planner, in [`PlannerKind::ALL`] order.
    pub runs: [RunMetrics; 3],
}

/// The maps and results of one density.
#[derive(Clone, PartialEq, Debug)]
pub struct DensityResult {
    /// Target density.
    pub density: f64,
    /// Maps discarded because the goal was unreachable.
    pub rejected_maps: usize,
    /// The solvable maps.
    pub trials: Vec<Trial>,
}

impl DensityResult {
    /// Mean of a metric of planner `k` (index into [`PlannerKind::ALL`]) over the trials.
    pub fn mean(&self, k: usize, metric: impl Fn(&RunMetrics) -> f64) -> f64 {
        let n = self.trials.len().max(1) as f64;
        self.trials.iter().map(|t| metric(&t.runs[k])).sum::<f64>() / n
    }
}

/// The whole experiment.
#[derive(Clone, PartialEq, Debug)]
pub struct Seed002Report {
    /// What was run.
    pub config: Seed002Config,
    /// One entry per density, in the config's order.
    pub densities: Vec<DensityResult>,
}

/// A random field of circles at one density: the planning grid and the real coverage.
pub fn obstacle_field(
    config: &Seed002Config,
    density: f64,
    rng: &mut impl Rng,
) -> Result<(Grid, f64), Seed002Error> {
    let side = config.side;
    let n = side as usize * side as usize;
    let mut covered = vec![false; n];
    let mut blocked = vec![false; n];
    let mut covered_count = 0;
    let target = (density * n as f64).ceil() as usize;
    let (start, goal) = ((0.5, 0.5), (f64::from(side) - 0.5, f64::from(side) - 0.5));
    let (r_lo, r_hi) = config.radius;
    // Guard: a density the circles cannot reach (e.g. all draws rejected) must not hang.
    let max_draws = 100 * n;
    let mut draws = 0;
    while covered_count < target {
        draws += 1;
        if draws > max_draws {
            return Err(Seed002Error::BadParameters {
                problem: format!("density {density} not reached after {max_draws} circles"),
            });
        }
        let cx = rng.gen_range(0.0..f64::from(side));
        let cy = rng.gen_range(0.0..f64::from(side));
        let r = if r_hi > r_lo {
            rng.gen_range(r_lo..r_hi)
        } else {
            r_lo
        };
        let big = r + config.inflation;
        let dist = |(x, y): (f64, f64)| (x - cx).hypot(y - cy);
        if dist(start) <= big || dist(goal) <= big {
            continue;
        }
        let lo = |c: f64| (c - big - 1.0).floor().max(0.0) as u32;
        let hi = |c: f64| ((c + big + 1.0).ceil() as u32).min(side);
        for y in lo(cy)..hi(cy) {
            for x in lo(cx)..hi(cx) {
                let cell = Cell::new(x, y);
                let d = dist(cell_centre_m(1.0, cell));
                let i = cell_index(side, cell);
                if d <= r && !covered[i] {
                    covered[i] = true;
                    covered_count += 1;
                }
                if d <= big {
                    blocked[i] = true;
                }
            }
        }
    }
    let grid =
        Grid::from_blocked(side, side, &blocked).map_err(|e| Seed002Error::BadParameters {
            problem: e.to_string(),
        })?;
    Ok((grid, covered_count as f64 / n as f64))
}

fn validate(config: &Seed002Config) -> Result<(), Seed002Error> {
    let bad = |problem: String| Err(Seed002Error::BadParameters { problem });
    let (lo, hi) = config.radius;
    if !(2..=4096).contains(&config.side) {
        return bad(format!("side {} must be in 2..=4096", config.side));
    }
    if config.densities.iter().any(|d| !(0.0..0.9).contains(d)) {
        return bad(format!(
            "densities {:?} must be in [0, 0.9)",
            config.densities
        ));
    }
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi >= lo) {
        return bad(format!(
            "radius range {lo}..{hi} must be positive and ordered"
        ));
    }
    if !(config.inflation.is_finite() && config.inflation >= 0.0) {
        return bad(format!("inflation {} must be >= 0", config.inflation));
    }
    Ok(())
}

/// Runs the experiment: for every density, `trials` solvable maps, every planner on each.
pub fn run(config: &Seed002Config) -> Result<Seed002Report, Seed002Error> {
    validate(config)?;
    let cfg = PlannerConfig::new(config.corner_cutting);
    let mut planners: Vec<_> = PlannerKind::ALL
        .iter()
        .map(|k| k.build(cfg.clone()))
        .collect();
    let (start, goal) = (Cell::new(0, 0), Cell::new(config.side - 1, config.side - 1));
    let mut densities = Vec::new();
    for (di, &density) in config.densities.iter().enumerate() {
        let mut rng = ChaCha8Rng::seed_from_u64(config.seed.wrapping_add(1_000_003 * di as u64));
        let mut result = DensityResult {
            density,
            rejected_maps: 0,
            trials: Vec::new(),
        };
        while result.trials.len() < config.trials {
            if result.rejected_maps > 100 * config.trials.max(1) {
                return Err(Seed002Error::BadParameters {
                    problem: format!("density {density}: almost no map is solvable"),
                });
            }
            let (grid, coverage) = obstacle_field(config, density, &mut rng)?;
            let mut runs = [RunMetrics::default(); 3];
            let mut solved = true;
            for (planner, run) in planners.iter_mut().zip(runs.iter_mut()) {
                let mut best = f64::INFINITY;
                let mut path = None;
                for _ in 0..config.timing_repeats.max(1) {
                    let t0 = Instant::now();
                    path = planner.plan(&grid, start, goal)?;
                    best = best.min(t0.elapsed().as_secs_f64() * 1e6);
                }
                let Some(path) = path else {
                    solved = false;
                    break;
                };
                let stats = planner.stats();
                let (turns, turn_deg) = heading_changes(&path.cells);
                *run = RunMetrics {
                    length: path.length,
                    time_us: best,
                    expansions: stats.expansions,
                    los_checks: stats.los_checks,
                    heading_changes: turns,
                    turn_deg,
                };
            }
            if solved {
                result.trials.push(Trial {
                    coverage,
                    blocked: grid.blocked_fraction(),
                    runs,
                });
            } else {
                result.rejected_maps += 1;
            }
        }
        densities.push(result);
    }
    Ok(Seed002Report {
        config: config.clone(),
        densities,
    })
}
