//! `hnav-bench experiment ga-fuzzy`: seed 004's hybrid planner (the GA's coarse route with
//! the fuzzy fine switch) against A* and HNAV, on the MovingAI maps in `maps/` (their `.scen`
//! optimal lengths the oracle) and on the seed's own setting rebuilt: a robot of a group
//! crossing a coarse grid while the group's other robots move (see [`own`]).
//!
//! Seed 004 publishes no table, timing or map, so there is no paper figure to print beside
//! ours; the report says so. Success, lengths, ticks and collisions are the same for a seed
//! on every run (`data.figures`); the wall times are apart (`data.timings`) and never
//! compared.
//!
//! | module | what |
//! |---|---|
//! | [`planners`] | the three planners on one query: found, length, ticks, collisions, time |
//! | [`scen`] | a seeded sample of the MovingAI `.scen` entries |
//! | [`own`] | the seed's setting: a 32 x 32 grid, twenty other robots moving along known routes |
//! | [`tables`] | per setting and planner: success, paired length over the optimal, collisions; markdown and JSON |

pub mod own;
pub mod planners;
pub mod scen;
pub mod tables;

use anyhow::Result;
use hnav_agent::ga_fuzzy::GaOptions;
use hnav_runtime::grid::Cell;
use serde::Serialize;

use super::{Options, Report};
use planners::Answer;

/// The experiment's name on the command line.
pub const NAME: &str = "ga-fuzzy";

/// How much a run measures.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Serialize)]
pub struct Size {
    /// Entries sampled from each `.scen` file.
    pub entries_per_file: usize,
    /// Worlds of the seed's own setting.
    pub worlds: usize,
}

impl Size {
    /// The full run, or the `--quick` one (same code paths, fewer tasks).
    pub fn of(options: Options) -> Size {
        if options.quick {
            Size {
                entries_per_file: 4,
                worlds: 8,
            }
        } else {
            Size {
                entries_per_file: 200,
                worlds: 300,
            }
        }
    }
}

/// One query and every planner's answer to it.
#[derive(Clone, Debug, Serialize)]
pub struct Task {
    /// `file.scen:line`, or `world k`.
    pub label: String,
    /// Start and goal.
    pub endpoints: (Cell, Cell),
    /// The shortest octile length on the walls (the `.scen`'s figure on MovingAI maps).
    pub optimal: f64,
    /// Per planner of [`planners::PLANNERS`].
    pub answers: Vec<Answer>,
}

/// The GA's options in this experiment: the planner's defaults, seeded by the run's seed.
pub fn ga_options(seed: u64) -> GaOptions {
    GaOptions {
        seed,
        ..GaOptions::default()
    }
}

/// Runs the experiment.
pub fn run(options: Options) -> Result<Report> {
    let size = Size::of(options);
    let ga = ga_options(options.seed);
    let mut settings: Vec<(String, Vec<Task>)> =
        scen::run(size.entries_per_file, ga, options.seed)?
            .into_iter()
            .map(|s| (s.map, s.tasks))
            .collect();
    let worlds = own::run(size.worlds, ga, options.seed ^ 0x0004)?;
    settings.push((tables::OWN.to_string(), worlds));
    let summaries = tables::summarise(&settings, options.seed);
    Ok(Report {
        name: NAME,
        quick: options.quick,
        seed: options.seed,
        markdown: tables::markdown(&summaries, size),
        data: tables::json(&settings, &summaries, size),
    })
}
