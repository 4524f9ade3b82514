//! `hnav-bench experiment <name>`: the seeds' experiments, each printing a markdown table of
//! our figures beside the paper's, with the differences explained in the linked docs.
//!
//! Every experiment is deterministic for a seed (`--seed`, one seeded ChaCha stream per
//! experiment), finishes in at most five minutes on two cores, and has a `--quick` variant
//! (under 30 s) that a test runs. `--json` prints the same figures as one JSON document.
//!
//! | module | experiment | what |
//! |---|---|---|
//! | [`dynamic`] | `dynamic` | issue 35: a warehouse whose doors close and whose aisles people walk; partial correction against rebuild against an all-knowing baseline, beside §2.10 |
//! | [`fidelity`] | `fidelity` | every number the seeds publish that HNAV computes, beside ours, with a status; writes `docs/experiments/fidelity.md` |
//! | [`ga_fuzzy`] | `ga-fuzzy` | seed 004: the GA + fuzzy planner against A* and HNAV on the MovingAI maps and on the seed's setting with moving robots |
//! | [`hnav_vs_astar`] | `hnav-vs-astar` | dissertation Tables 3-8/3-9: HNAV against A* on four 20x20 tasks, tanh against linear, partial against full activation; then MovingAI scenario samples |
//! | [`pso`] | `pso` | seed 003's Tables 1 and 2: the original swarm against the modified one |
//! | [`pso_ablation`] | — | the `pso` experiment's ablation: the modified algorithm with one modification switched off, and how steps are counted |
//! | [`pso_paired`] | — | the `pso` experiment's paired step comparison: original against modified on the tasks both solve |
//! | [`pso_tasks`] | — | the `pso` experiment's paper rows, maps, endpoints and one setting's runs, which the three above read |
//! | [`stats`] | — | the intervals the tables print: Wilson for rates, bootstrap for means |

use serde::Serialize;

pub mod dynamic;
pub mod fidelity;
pub mod ga_fuzzy;
pub mod hnav_vs_astar;
pub mod pso;
pub mod pso_ablation;
pub mod pso_paired;
pub mod pso_tasks;
pub mod stats;

/// One experiment: its command-line name, a line for `--help`, and the function that runs it.
pub struct Experiment {
    /// The name after `hnav-bench experiment`.
    pub name: &'static str,
    /// What it reproduces.
    pub about: &'static str,
    /// Runs it.
    pub run: fn(Options) -> anyhow::Result<Report>,
}

/// Every experiment, in the order `--help` lists them. A new experiment is one row here and
/// one module.
pub const EXPERIMENTS: &[Experiment] = &[
    Experiment {
        name: hnav_vs_astar::NAME,
        about: "Tables 3-8/3-9: HNAV against A* (time, steps), tanh/linear, partial/full; MovingAI samples",
        run: hnav_vs_astar::run,
    },
    Experiment {
        name: "pso",
        about: "seed 003, Tables 1-2: original PSO (r_max 1/2/4) vs modified (n_lm 5/7/10)",
        run: pso::run,
    },
    Experiment {
        name: fidelity::NAME,
        about: "every number the seeds publish beside ours, with a status; the full run writes docs/experiments/fidelity.md",
        run: fidelity::run,
    },
    Experiment {
        name: ga_fuzzy::NAME,
        about: "seed 004: GA + fuzzy vs A* and HNAV on the MovingAI maps and the seed's moving-robot setting",
        run: ga_fuzzy::run,
    },
    Experiment {
        name: dynamic::NAME,
        about: "a changing warehouse (doors, walkers): partial correction vs rebuild vs all-knowing, beside §2.10",
        run: dynamic::run,
    },
];

/// What every experiment is run with.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Options {
    /// The reduced variant (under 30 s): fewer runs per setting, same code paths.
    pub quick: bool,
    /// Seed of the experiment's random stream.
    pub seed: u64,
    /// Experiments that run whole swarms (`dynamic`) keep their run directories (scenario,
    /// consensus log, process logs, recording) and say where, instead of deleting them: a
    /// surprising row can then be looked into, or run again with `hnav run`.
    pub keep: bool,
    /// Experiments with several swarm sizes (`dynamic`) run only this one.
    pub robots: Option<usize>,
    /// Experiments that run whole swarms (`dynamic`) run them under these conflict rules
    /// instead of their own choice.
    pub rules: Option<hnav_runtime::scenario::Rules>,
    /// Experiments that compare variants of a run (`dynamic`) run only the one of this name
    /// (a name the experiment gives, as in its tables).
    pub variant: Option<&'static str>,
}

/// What an experiment produced: the markdown table(s) for a reader and the same figures for a
/// program.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The experiment's name, as on the command line.
    pub name: &'static str,
    /// The options it ran with.
    pub quick: bool,
    /// The seed it ran with.
    pub seed: u64,
    /// Markdown: tables of ours beside the paper's, and a line on each difference.
    pub markdown: String,
    /// The figures behind the tables.
    pub data: serde_json::Value,
}

/// Runs the experiment called `name`; an unknown name is an error that lists the known ones.
pub fn run(name: &str, options: Options) -> anyhow::Result<Report> {
    match EXPERIMENTS.iter().find(|e| e.name == name) {
        Some(e) => (e.run)(options),
        None => {
            let known: Vec<&str> = EXPERIMENTS.iter().map(|e| e.name).collect();
            anyhow::bail!(
                "no experiment called {name:?}; the experiments are: {}",
                known.join(", ")
            )
        }
    }
}
