//! The same comparison on the MovingAI scenario files in `maps/`: a seeded sample of each
//! file's entries, every planner of [`VARIANTS`] on each, the `.scen` optimal length as the
//! oracle of path quality.

use anyhow::{Context, Result};
use hnav_runtime::grid::{read_map_file, read_scen_file};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::measure::{measure, Figures, Timing, ASTAR, VARIANTS};
use super::tasks::maps_dir;
use crate::plan::Summary;

/// The map and scenario files sampled, in `maps/`.
pub const SCEN_FILES: [(&str, &str); 3] = [
    ("random-32-32-10.map", "random-32-32-10-random-1.scen"),
    ("random-32-32-20.map", "random-32-32-20-random-1.scen"),
    (
        "warehouse-10-20-10-2-1.map",
        "warehouse-10-20-10-2-1-random-1.scen",
    ),
];

/// One sampled entry: where it is and what every planner answered.
#[derive(Clone, Debug, Serialize)]
pub struct EntryFigures {
    /// Line of the entry in its `.scen`.
    pub line: usize,
    /// The `.scen` optimal length.
    pub optimal: f64,
    /// Per planner of [`VARIANTS`].
    pub planners: Vec<Figures>,
}

/// One scenario file's sample.
#[derive(Clone, Debug)]
pub struct ScenResult {
    /// The `.scen` file's name.
    pub scen: &'static str,
    /// The sampled entries' answers (deterministic).
    pub entries: Vec<EntryFigures>,
    /// Per planner: found, optimal and the length ratio against the oracle (deterministic).
    pub summaries: Vec<Summary>,
    /// Per planner: mean sweeps (HNAV) or expansions (A*) over the entries (deterministic).
    pub mean_iterations: Vec<f64>,
    /// Per entry, per planner (timings).
    pub timings: Vec<Vec<Timing>>,
}

impl ScenResult {
    /// Per planner: the median over the entries of the entry's median time, µs.
    pub fn median_time_us(&self, planner: usize) -> f64 {
        median(self.timings.iter().map(|t| t[planner].median_us))
    }

    /// Per planner: the median over the entries of (its median time / A*'s median time).
    pub fn median_ratio_to_astar(&self, planner: usize) -> f64 {
        median(
            self.timings
                .iter()
                .map(|t| t[planner].median_us / t[ASTAR].median_us),
        )
    }
}

fn median(xs: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = xs.collect();
    v.sort_by(f64::total_cmp);
    super::measure::quantile(&v, 0.5)
}

/// Samples `per_file` entries of each file of [`SCEN_FILES`] with `seed` (the same entries
/// for the same seed) and measures each with `repetitions` timed repetitions.
pub fn run(per_file: usize, repetitions: usize, seed: u64) -> Result<Vec<ScenResult>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let dir = maps_dir();
    let mut out = Vec::with_capacity(SCEN_FILES.len());
    for (map, scen) in SCEN_FILES {
        let grid = read_map_file(dir.join(map)).map_err(anyhow::Error::msg)?;
        let file = read_scen_file(dir.join(scen)).map_err(anyhow::Error::msg)?;
        let n = per_file.min(file.entries.len());
        let mut picked = rand::seq::index::sample(&mut rng, file.entries.len(), n).into_vec();
        picked.sort_unstable();
        let mut result = ScenResult {
            scen,
            entries: Vec::with_capacity(n),
            summaries: VARIANTS.iter().map(|_| Summary::new("")).collect(),
            mean_iterations: vec![0.0; VARIANTS.len()],
            timings: Vec::with_capacity(n),
        };
        for i in picked {
            let e = &file.entries[i];
            e.validate(&grid, &file.source_name)
                .map_err(anyhow::Error::msg)?;
            let m = measure(&grid, e.start, e.goal, repetitions)
                .with_context(|| format!("{scen}:{}", e.line))?;
            for (k, f) in m.figures.iter().enumerate() {
                result.summaries[k].add(&as_line(f, e.optimal_length));
                result.mean_iterations[k] += f.iterations as f64 / n as f64;
            }
            result.entries.push(EntryFigures {
                line: e.line,
                optimal: e.optimal_length,
                planners: m.figures,
            });
            result.timings.push(m.timings);
        }
        out.push(result);
    }
    Ok(out)
}

/// The figures as the plan command's line, so that its [`Summary`] does the counting.
fn as_line(f: &Figures, optimal: f64) -> hnav_runtime::plan::PlanResult {
    hnav_runtime::plan::PlanResult {
        planner: f.planner.clone(),
        found: f.found,
        steps: f.steps,
        length: f.length,
        iterations: f.iterations,
        path: Vec::new(),
        time_us: 0.0,
        los_checks: None,
        optimal: Some(optimal),
    }
}
