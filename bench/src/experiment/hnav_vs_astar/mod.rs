//! `hnav-bench experiment hnav-vs-astar`: the dissertation's comparison of HNAV with A*
//! (Table 3-8), its activation and stop-rule claims (Table 3-9), and the same planners on
//! MovingAI scenario files against their optimal lengths.
//!
//! The dissertation's times are Python on a Xeon X5660; ours are Rust on whatever runs this,
//! so only ratios (HNAV / A*, tanh / linear, full / partial) are comparable. The JSON keeps
//! the machine-independent figures (`data.figures`: steps, lengths, sweeps, expansions; the
//! same for a seed on every run) apart from the wall times (`data.timings`).
//!
//! | module | what |
//! |---|---|
//! | [`tasks`] | the four reconstructed 20x20 tasks (`maps/dissertation/`) and Tables 3-8/3-9 as printed |
//! | [`measure`] | one query with every planner: figures once, times as median and quartiles of many interleaved repetitions |
//! | [`movingai`] | a seeded sample of the MovingAI `.scen` files' entries, length against the oracle |
//! | [`tables`] | the markdown tables and the JSON document |

pub mod measure;
pub mod movingai;
pub mod tables;
pub mod tasks;

use anyhow::Result;

use super::{Options, Report};

/// The experiment's name on the command line.
pub const NAME: &str = "hnav-vs-astar";

/// How much a run measures.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Size {
    /// Timed repetitions of each task query per planner.
    pub task_repetitions: usize,
    /// Entries sampled from each `.scen` file.
    pub entries_per_file: usize,
    /// Timed repetitions of each sampled entry per planner.
    pub entry_repetitions: usize,
}

impl Size {
    /// The full run, or the `--quick` one (same code paths, fewer repetitions and entries).
    pub fn of(options: Options) -> Size {
        if options.quick {
            Size {
                task_repetitions: 21,
                entries_per_file: 4,
                entry_repetitions: 1,
            }
        } else {
            Size {
                task_repetitions: 5001,
                entries_per_file: 100,
                entry_repetitions: 15,
            }
        }
    }
}

/// One task measured.
#[derive(Clone, Debug)]
pub struct TaskResult {
    /// The task.
    pub task: tasks::Task,
    /// Every planner on it.
    pub measured: measure::Measured,
}

/// Runs the experiment.
pub fn run(options: Options) -> Result<Report> {
    let size = Size::of(options);
    let mut task_results = Vec::new();
    for task in tasks::load()? {
        let e = &task.entry;
        let measured = measure::measure(&task.grid, e.start, e.goal, size.task_repetitions)?;
        task_results.push(TaskResult { task, measured });
    }
    let scen = movingai::run(size.entries_per_file, size.entry_repetitions, options.seed)?;
    Ok(Report {
        name: NAME,
        quick: options.quick,
        seed: options.seed,
        markdown: tables::markdown(&task_results, &scen, size),
        data: tables::json(&task_results, &scen, size),
    })
}
