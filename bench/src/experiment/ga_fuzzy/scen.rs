//! The MovingAI half: a seeded sample of each `.scen` file's entries (the files of
//! [`SCEN_FILES`], read with the runtime's reader), every planner on each, the entry's
//! optimal length as the oracle. Nothing moves on these maps, so the GA's layers are the walls
//! alone, as deep as the map has cells (what the route planner `"ga-fuzzy"` uses).

use anyhow::{Context, Result};
use hnav_agent::ga_fuzzy::{GaOptions, TimeGrid};
use hnav_runtime::grid::{read_map_file, read_scen_file, CornerCutting};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::planners::{answer, PLANNERS};
use super::Task;
use crate::experiment::hnav_vs_astar::movingai::SCEN_FILES;
use crate::experiment::hnav_vs_astar::tasks::maps_dir;

/// One map's sample: its name and every sampled entry answered.
#[derive(Clone, Debug)]
pub struct Sample {
    /// The map's name (the `.map` file without the extension).
    pub map: String,
    /// The sampled entries, in file order.
    pub tasks: Vec<Task>,
}

/// Samples `per_file` entries of each file of [`SCEN_FILES`] with `seed` (the same entries
/// for the same seed) and answers each with every planner.
pub fn run(per_file: usize, ga: GaOptions, seed: u64) -> Result<Vec<Sample>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let dir = maps_dir();
    let mut out = Vec::with_capacity(SCEN_FILES.len());
    for (map, scen) in SCEN_FILES {
        let grid = read_map_file(dir.join(map)).map_err(anyhow::Error::msg)?;
        let file = read_scen_file(dir.join(scen)).map_err(anyhow::Error::msg)?;
        let n = per_file.min(file.entries.len());
        let mut picked = rand::seq::index::sample(&mut rng, file.entries.len(), n).into_vec();
        picked.sort_unstable();
        let tg = TimeGrid::fixed(grid.clone(), CornerCutting::Forbidden, grid.len().max(2))?;
        let mut tasks = Vec::with_capacity(n);
        for i in picked {
            let e = &file.entries[i];
            e.validate(&grid, &file.source_name)
                .map_err(anyhow::Error::msg)?;
            let answers = PLANNERS
                .iter()
                .map(|&p| answer(p, ga, &tg, e.start, e.goal))
                .collect::<Result<Vec<_>>>()
                .with_context(|| format!("{scen}:{}", e.line))?;
            tasks.push(Task {
                label: format!("{scen}:{}", e.line),
                endpoints: (e.start, e.goal),
                optimal: e.optimal_length,
                answers,
            });
        }
        out.push(Sample {
            map: map.trim_end_matches(".map").to_string(),
            tasks,
        });
    }
    Ok(out)
}
