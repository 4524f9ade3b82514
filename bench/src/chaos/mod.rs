//! The chaos campaign (`hnav-bench chaos`, `tests/tests/chaos.rs`): seeded fault plans run
//! against a small swarm, each run checked, and the detection and recovery figures over all
//! of them.
//!
//! - [`plan`]: the plans (kill 1–3 agents, kill the coordinator, freeze an agent, kill the
//!   sim, a mix at once; lockstep and realtime), rendered as `[[faults]]` or `hnav run` args;
//! - [`run`]: one run, `hnav run` as a child watched by an [`observer`] of the run's topics
//!   in the same [`Waiter`](hnav_runtime::transport::Waiter);
//! - [`checks`]: exit code, robots at goal, collisions, `hnav log verify`, the commits seen
//!   against the log, faults fired, files and processes left behind;
//! - [`figures`]: SIGKILL → `Down`, SIGSTOP → hang declared, respawn → first round, from
//!   `events.jsonl` and the observer's stamps;
//! - [`table`]: a row per class and mode.
//!
//! A plan whose fault the runtime cannot inject yet (see [`needs`]) is drawn and rendered,
//! and reported skipped with what it needs; it is never counted as passed.

pub mod checks;
pub mod figures;
pub mod observer;
pub mod plan;
pub mod run;
pub mod table;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use hnav_runtime::scenario::params::{RestartConfig, RestartPolicy};
use hnav_runtime::scenario::Scenario;

use figures::Figures;
use plan::{Class, Plan, PlanSpace};
use run::{run_plan, RunOutcome, RunSetup};

/// The chaos scenario (`scenarios/chaos.toml`), built into the harness so that the plans are
/// drawn against the swarm they run.
pub const CHAOS_SCENARIO: &str = include_str!("../../../scenarios/chaos.toml");

/// Runs of the campaign the test runs (`--quick`): 30 + 10 + 5 + 5 + 5 + 4.
pub const QUICK_RUNS: usize = 59;
/// Runs of the full campaign unless `--runs` says otherwise.
pub const FULL_RUNS: usize = 118;

/// Where the plans' faults land, for the chaos scenario: its shortest fault-free run lasts
/// about 400 rounds (lockstep, 4 s), so every fault at rounds 20..=220 hits a run under way.
/// A short freeze (20 ms, two control periods) is continued before any hang deadline of "a
/// few control periods"; a long one (1.5 s) well after it.
pub const CHAOS_SPACE: PlanSpace = PlanSpace {
    agents: 6,
    first_round: 20,
    last_round: 220,
    freeze_short_s: 0.02,
    freeze_long_s: 1.5,
};

/// What a campaign runs.
#[derive(Debug, Clone)]
pub struct CampaignConfig {
    /// Runs in all.
    pub runs: usize,
    /// The campaign's seed.
    pub seed: u64,
    /// Only this plan (by number), to reproduce one run.
    pub only: Option<usize>,
    /// Only runs of this class (all `runs` of them).
    pub class: Option<Class>,
    /// Where `hnav` and the process binaries are.
    pub bin_dir: PathBuf,
    /// Robots per agent process (`[run] agents_per_process`; 1: one process per robot).
    /// With more, a fault on `agent:N` takes down every robot of N's process.
    pub agents_per_process: u32,
}

/// What a campaign showed.
pub struct CampaignReport {
    /// Every run, in plan order.
    pub outcomes: Vec<RunOutcome>,
    /// The figures over them.
    pub figures: Figures,
    /// The campaign's wall time.
    pub elapsed: Duration,
    /// The directory failed runs were kept in, if any failed (every run, with `--only`).
    pub kept: Option<PathBuf>,
}

impl CampaignReport {
    /// Whether every run that ran passed every check (and at least one ran).
    pub fn passed(&self) -> bool {
        let ran = self.outcomes.iter().filter(|o| o.skipped.is_none()).count();
        ran > 0 && self.failures().is_empty()
    }

    /// One line per failed run: its plan (seed, faults) and every failed check.
    pub fn failures(&self) -> Vec<String> {
        self.outcomes
            .iter()
            .filter(|o| o.skipped.is_none() && !o.failures.is_empty())
            .map(|o| {
                format!(
                    "FAILED {}: {}; run dir kept: {}",
                    o.plan,
                    o.failures.join("; "),
                    o.dir.display()
                )
            })
            .collect()
    }

    /// Failures, the table and the figures.
    pub fn render(&self) -> String {
        let mut out = String::new();
        for f in self.failures() {
            out += &f;
            out.push('\n');
        }
        out += &table::render(&self.outcomes);
        out.push('\n');
        out += &self.figures.render();
        let ran = self.outcomes.iter().filter(|o| o.skipped.is_none()).count();
        out += &format!(
            "{ran} runs in {:.1} s ({} skipped)\n",
            self.elapsed.as_secs_f64(),
            self.outcomes.len() - ran
        );
        if let Some(dir) = &self.kept {
            out += &format!("run directories kept in {}\n", dir.display());
        }
        out
    }
}

/// Why `plan` cannot run on this build, if it cannot: what it needs.
///
/// A freeze needs `action = "freeze"` in `[[faults]]` (probed by parsing the plan's scenario
/// with the runtime linked here, the same source as the `hnav` beside it); a sim kill needs
/// the sim restarted by default (its default restart policy no longer `never`), since a sim
/// that is not restarted ends the run by design.
pub fn needs(plan: &Plan) -> Option<String> {
    match plan.class {
        Class::FreezeAgent => {
            Scenario::from_str(&plan.scenario(CHAOS_SCENARIO), "chaos.toml", Path::new("."))
                .err()
                .map(|e| {
                    format!("needs freeze faults in [[faults]] (action = \"freeze\"; here: {e})")
                })
        }
        Class::SimKill => {
            (RestartConfig::default().sim.policy == RestartPolicy::Never).then(|| {
                "needs sim restarts (the sim's default restart policy is still never)".to_string()
            })
        }
        _ => None,
    }
}

/// Runs the campaign, calling `progress` with a line after each run.
pub fn run_campaign(
    config: &CampaignConfig,
    mut progress: impl FnMut(&str),
) -> Result<CampaignReport, String> {
    let started = Instant::now();
    let root = tempfile::Builder::new()
        .prefix("hnav-chaos-")
        .tempdir()
        .map_err(|e| format!("cannot make the campaign's directory: {e}"))?;
    let base = match config.agents_per_process {
        1 => CHAOS_SCENARIO.to_string(),
        k => format!("{CHAOS_SCENARIO}\n[run]\nagents_per_process = {k}\n"),
    };
    let setup = RunSetup {
        bin_dir: &config.bin_dir,
        base_scenario: &base,
        agents: CHAOS_SPACE.agents as usize,
        root: root.path(),
        keep: config.only.is_some(),
    };
    let plans: Vec<Plan> = plan::generate(config.seed, config.runs, &CHAOS_SPACE, config.class)
        .into_iter()
        .filter(|p| config.only.is_none_or(|n| n == p.number))
        .collect();
    let mut outcomes = Vec::with_capacity(plans.len());
    let mut figures = Figures::default();
    for (i, p) in plans.iter().enumerate() {
        let outcome = match needs(p) {
            Some(why) => RunOutcome::skipped(p, why),
            None => run_plan(&setup, p),
        };
        figures.add_run(
            &format!("plan {}", p.number),
            &outcome.events,
            &outcome.seen,
        );
        progress(&progress_line(&outcome, i + 1, plans.len()));
        outcomes.push(outcome);
    }
    let any_failed = outcomes.iter().any(|o| !o.failures.is_empty());
    let kept = (any_failed || config.only.is_some()).then(|| root.keep());
    Ok(CampaignReport {
        outcomes,
        figures,
        elapsed: started.elapsed(),
        kept,
    })
}

fn progress_line(o: &RunOutcome, nth: usize, of: usize) -> String {
    let verdict = match (&o.skipped, o.failures.is_empty()) {
        (Some(why), _) => format!("skipped: {why}"),
        (None, true) => format!("ok in {:.1} s", o.wall.as_secs_f64()),
        (None, false) => format!("FAILED: {}", o.failures.join("; ")),
    };
    format!("[{nth}/{of}] {}: {verdict}", o.plan)
}
