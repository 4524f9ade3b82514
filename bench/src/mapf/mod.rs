//! The MAPF benchmark (`hnav-bench mapf`): the N-agent instances of a MovingAI `.scen`
//! (its first N entries) run on its map by whole swarms, for a list of N and of coordinator
//! rules, each reported as robots at goal, collisions, makespan, sum of path lengths against
//! the `.scen`'s lower bound, conflicts, replans, wall time and the processes' memory.
//!
//! - [`instance`]: the `.scen` against its map, the first N entries, their scenario file;
//! - [`run`]: one run through `hnav run`, sampled by [`memory`], read back from
//!   `summary.json` and the consensus log, which must agree;
//! - [`report`]: the rows as a markdown table or JSON lines;
//! - [`search_only`]: `hnav-bench lacam`, the coordinator's LaCAM search alone on the
//!   instance, up to thousands of agents, against a wall-clock limit.

pub mod instance;
pub mod memory;
pub mod report;
pub mod run;
pub mod search_cli;
pub mod search_only;

use std::path::{Path, PathBuf};
use std::time::Duration;

use hnav_runtime::scenario::Scenario;

use instance::{Benchmark, Instance, RunSettings};
use report::Row;
use run::{run_instance, RunPlace};

/// The time limit of a run unless `--time-limit-s` is given: ten simulated seconds per cell
/// of the instance's longest optimal path, at least 600 s. A robot drives a cell in about
/// 1.4 s at the default 1 cell/s (turns on the spot included), so a limit of 10 s a cell
/// leaves every robot seven times its own solo trip for waiting in a dense swarm; a run that
/// needs more is stuck, not slow.
pub fn default_time_limit_s(instance: &Instance<'_>) -> f64 {
    (10.0 * instance.longest()).ceil().max(600.0)
}

/// The quick instance `--quick` runs (and `tests/tests/mapf_quick.rs`).
pub const QUICK_AGENTS: [usize; 2] = [8, 16];

/// The map and `.scen` of `--quick`: `maps/random-32-32-10` of this repository.
pub fn quick_files() -> (PathBuf, PathBuf) {
    let maps = Path::new(env!("CARGO_MANIFEST_DIR")).join("../maps");
    (
        maps.join("random-32-32-10.map"),
        maps.join("random-32-32-10-random-1.scen"),
    )
}

/// What a benchmark runs.
#[derive(Debug, Clone)]
pub struct MapfConfig {
    /// The MovingAI map.
    pub map: PathBuf,
    /// Its `.scen`.
    pub scen: PathBuf,
    /// The instance sizes, in order.
    pub agents: Vec<usize>,
    /// The coordinator rules, each run at every size.
    pub rules: Vec<String>,
    /// `lockstep` or `realtime`.
    pub mode: String,
    /// The scenario's time limit; `None`: [`default_time_limit_s`] per instance.
    pub time_limit_s: Option<f64>,
    /// Robots per agent process (`[run] agents_per_process`).
    pub agents_per_process: u32,
    /// The control rate (`[sim] odometry_hz`); `None`: the default, 100.
    pub odometry_hz: Option<u32>,
    /// The wall-clock cap of each run.
    pub wall_limit: Duration,
    /// Where each run gets its directory (`<map>-<rules>-<N>/`, replaced by the next run).
    pub out: PathBuf,
    /// Where `hnav` and the process binaries are.
    pub bin_dir: PathBuf,
}

/// The rules of the dissertation, the ones a runtime without a `rules` key runs.
pub const DISSERTATION: &str = "dissertation";

/// Parses a one-agent scenario with `[coordinator] rules = RULES` with the linked runtime
/// (the same source as the `hnav` beside it, as the chaos campaign probes its faults).
fn probe_rules(rules: &str) -> Result<(), String> {
    let text = format!(
        "name = \"probe\"\n[map]\nrows = [\"..\"]\n[coordinator]\nrules = {rules:?}\n\
         [[agents]]\nstart = [0, 0]\ngoal = [1, 0]\n"
    );
    Scenario::from_str(&text, "probe.toml", Path::new("."))
        .map(drop)
        .map_err(|e| e.to_string())
}

/// The `rules` key to write for `rules`: the name itself where the runtime takes it; `None`
/// (no key) for the dissertation's rules on a runtime without the key; an error, in the
/// parser's words, for rules it does not know.
fn rules_setting(rules: &str) -> Result<Option<String>, String> {
    let Err(e) = probe_rules(rules) else {
        return Ok(Some(rules.to_string()));
    };
    let has_key = probe_rules(DISSERTATION).is_ok();
    match (has_key, rules == DISSERTATION) {
        (false, true) => Ok(None),
        (false, false) => Err(format!(
            "rules {rules:?} cannot run: this build's scenarios have no [coordinator] rules \
             key, so only the dissertation's rules exist ({e})"
        )),
        (true, _) => Err(format!("rules {rules:?} cannot run: {e}")),
    }
}

/// Runs every size under every rules, calling `progress` with a line and `on_row` with the
/// row after each run (so that a script reading JSON lines has every finished run even if a
/// later one fails); returns the rows in that order. Stops at the first error (bad input, a
/// run that left no summary or an unreadable log).
pub fn run_benchmark(
    config: &MapfConfig,
    mut progress: impl FnMut(&str),
    mut on_row: impl FnMut(&Row),
) -> Result<Vec<Row>, String> {
    let benchmark = Benchmark::load(&config.map, &config.scen).map_err(|e| e.to_string())?;
    let instances = config
        .agents
        .iter()
        .map(|&n| benchmark.instance(n))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| e.to_string())?;
    let stem = benchmark
        .map
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut rows = Vec::new();
    for rules in &config.rules {
        let setting = rules_setting(rules)?;
        for instance in &instances {
            let settings = RunSettings {
                mode: config.mode.clone(),
                rules: setting.clone(),
                time_limit_s: config
                    .time_limit_s
                    .unwrap_or_else(|| default_time_limit_s(instance)),
                agents_per_process: config.agents_per_process,
                odometry_hz: config.odometry_hz,
            };
            let dir = config
                .out
                .join(format!("{stem}-{rules}-{}", instance.agents()));
            if dir.exists() {
                std::fs::remove_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
            }
            let place = RunPlace {
                bin_dir: &config.bin_dir,
                dir: &dir,
                wall_limit: config.wall_limit,
            };
            let mut row = run_instance(instance, &settings, &place)?;
            row.derive();
            progress(&format!(
                "{rules} N = {}: {}/{} at goal, {} collisions, {} rounds, {:.1} s wall, {} ({})",
                row.agents,
                row.at_goal,
                row.agents,
                row.collisions,
                row.rounds,
                row.wall_s,
                row.end,
                dir.display()
            ));
            on_row(&row);
            rows.push(row);
        }
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dissertation_rules_always_run_and_unknown_rules_never() {
        // With or without the key in this build, the dissertation's rules can be written.
        let setting = rules_setting(DISSERTATION).unwrap();
        assert!(setting.is_none() || setting.as_deref() == Some(DISSERTATION));
        let err = rules_setting("no-such-rules").unwrap_err();
        assert!(
            err.starts_with("rules \"no-such-rules\" cannot run: "),
            "{err}"
        );
    }
}
