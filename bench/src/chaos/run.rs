//! One run of the campaign: `hnav run` as a child with the plan's scenario, the observer in
//! this thread, then every check.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use hnav_operator::supervisor::child::{Child, ChildSpec, ExitInfo, Signal};
use hnav_operator::supervisor::registry::RunRegistry;
use hnav_runtime::transport::{purge_run, RunId, Wake};

use super::checks::{self, CommitCount, EventLine};
use super::observer::{Observed, Observer};
use super::plan::Plan;
use crate::swarm_run::{self, hnav_run_spec, run_files};

/// The longest a run may take, start-up included: the chaos scenario's time limit (20 s)
/// is far below it, so only a run whose supervisor hangs meets it.
const RUN_TIMEOUT: Duration = Duration::from_secs(120);
/// How long the supervisor gets to exit once the observer has seen its `Stop`: its stop
/// grace (3 s, twice) and the summary.
const EXIT_TIMEOUT: Duration = Duration::from_secs(30);

/// Where a run takes its programs and its scenario.
pub struct RunSetup<'a> {
    /// The directory holding `hnav` and the process binaries.
    pub bin_dir: &'a Path,
    /// The chaos scenario the plan's faults are appended to.
    pub base_scenario: &'a str,
    /// Its agent count.
    pub agents: usize,
    /// The campaign's directory; the run gets `run-NNN/` in it.
    pub root: &'a Path,
    /// Keep a run's directory even when it passed (`--only N`: a plan looked at closely).
    pub keep: bool,
}

/// What one run showed.
pub struct RunOutcome {
    /// The plan it ran.
    pub plan: Plan,
    /// Why it was not run, if it was skipped (`needs ...`).
    pub skipped: Option<String>,
    /// How `hnav run` ended.
    pub exit: Option<ExitInfo>,
    /// Robots at goal and robots whose goal is reachable, from `summary.json`.
    pub at_goal: (usize, usize),
    /// Collisions in `summary.json`.
    pub collisions: u64,
    /// Whether `hnav log verify` passed.
    pub verified: bool,
    /// What the commit check counted, when it passed.
    pub commits: Option<CommitCount>,
    /// Files of the run left in `/dev/shm` or under iceoryx2's root.
    pub leaked_files: usize,
    /// Processes of the run alive after it.
    pub left_alive: usize,
    /// Every check that failed, in words.
    pub failures: Vec<String>,
    /// The supervisor's events.
    pub events: Vec<EventLine>,
    /// What the observer saw.
    pub seen: Observed,
    /// The run directory (kept when a check failed, removed otherwise).
    pub dir: PathBuf,
    /// Wall time of the run, start-up to exit.
    pub wall: Duration,
}

impl RunOutcome {
    fn new(plan: &Plan, dir: PathBuf) -> Self {
        RunOutcome {
            plan: plan.clone(),
            skipped: None,
            exit: None,
            at_goal: (0, 0),
            collisions: 0,
            verified: false,
            commits: None,
            leaked_files: 0,
            left_alive: 0,
            failures: Vec::new(),
            events: Vec::new(),
            seen: Observed::default(),
            dir,
            wall: Duration::ZERO,
        }
    }

    /// A plan that is rendered but not run, and why.
    pub fn skipped(plan: &Plan, why: String) -> Self {
        let mut o = RunOutcome::new(plan, PathBuf::new());
        o.skipped = Some(why);
        o
    }

    /// Whether it ran and every check passed.
    pub fn passed(&self) -> bool {
        self.skipped.is_none() && self.failures.is_empty()
    }
}

/// Runs `plan` and checks it. Errors of the harness itself (a directory that cannot be
/// made, the observer that cannot join) are failures of the run too, so nothing is hidden.
pub fn run_plan(setup: &RunSetup<'_>, plan: &Plan) -> RunOutcome {
    let dir = setup.root.join(format!("run-{:03}", plan.number));
    let mut outcome = RunOutcome::new(plan, dir.clone());
    let started = Instant::now();
    let run = RunId::unique("chaos");
    if let Err(e) = execute(setup, plan, &run, &dir, &mut outcome) {
        outcome.failures.push(e);
    }
    outcome.wall = started.elapsed();
    // The checks saw what was left; nothing of a failed run may stay on the machine.
    if !run_files(&run).is_empty() {
        let _ = purge_run(&run);
    }
    if outcome.failures.is_empty() && !setup.keep {
        let _ = std::fs::remove_dir_all(&dir);
    }
    outcome
}

fn execute(
    setup: &RunSetup<'_>,
    plan: &Plan,
    run: &RunId,
    dir: &Path,
    outcome: &mut RunOutcome,
) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let scenario = dir.join("scenario.toml");
    std::fs::write(&scenario, plan.scenario(setup.base_scenario))
        .map_err(|e| format!("{}: {e}", scenario.display()))?;
    let before = run_files(run);
    if !before.is_empty() {
        return Err(format!("files of a fresh run id already exist: {before:?}"));
    }
    let out = dir.join("out");
    let registry = dir.join("runs");
    let hnav = setup.bin_dir.join("hnav");
    let mut spec = hnav_run_spec(
        &hnav,
        &scenario,
        run,
        &out,
        plan.mode.name(),
        &registry,
        dir.join("hnav-run.log"),
    );
    if plan.class.replicas() > 1 {
        spec = spec
            .arg("--replicas")
            .arg(plan.class.replicas().to_string());
    }
    let (child, pids) = observe(run, setup.agents, &spec, &registry, outcome)?;
    let exit = match child.wait(Some(EXIT_TIMEOUT)) {
        Some(exit) => exit,
        None => {
            let _ = child.signal_group(Signal::SIGKILL);
            let exit = child.wait(Some(EXIT_TIMEOUT));
            outcome.failures.push(format!(
                "hnav run did not exit within {EXIT_TIMEOUT:?} of its Stop (killed)"
            ));
            exit.unwrap_or(ExitInfo::Lost)
        }
    };
    outcome.exit = Some(exit);
    check_run(setup, run, &out, exit, pids, child.pid(), outcome);
    Ok(())
}

/// Starts `hnav run` and observes it until its `Stop` (or its exit); returns the child and
/// the pids the registry listed once the run had started.
fn observe(
    run: &RunId,
    agents: usize,
    spec: &ChildSpec,
    registry: &Path,
    outcome: &mut RunOutcome,
) -> Result<(Child, Vec<u32>), String> {
    let observer = Observer::join(run, agents).map_err(|e| format!("observer: {e}"))?;
    let mut seen = Observed::with_room(agents);
    let waiter = observer.waiter().map_err(|e| format!("observer: {e}"))?;
    let child = Child::spawn(spec).map_err(|e| e.to_string())?;
    let mut pids = Vec::new();
    let deadline = Instant::now() + RUN_TIMEOUT;
    {
        let _ports = observer
            .attach(&waiter)
            .map_err(|e| format!("observer: {e}"))?;
        let _exit = child.watch(&waiter).map_err(|e| format!("observer: {e}"))?;
        loop {
            let wake = waiter
                .wait(Some(deadline))
                .map_err(|e| format!("observer: {e}"))?;
            observer
                .drain(&mut seen)
                .map_err(|e| format!("observer: {e}"))?;
            if pids.is_empty() && seen.started_ns.is_some() {
                // Every process is up and registered by the time `Start` goes out.
                if let Ok(Some(record)) = RunRegistry::at(registry).find(run) {
                    pids.extend(record.processes.iter().map(|p| p.pid));
                }
            }
            if seen.stopped_ns.is_some() || child.try_reap().is_some() {
                break;
            }
            if wake == Wake::TimedOut && Instant::now() >= deadline {
                let _ = child.signal_group(Signal::SIGKILL);
                outcome.failures.push(format!(
                    "the run did not end within {RUN_TIMEOUT:?} (killed)"
                ));
                break;
            }
        }
    }
    // Leave before the supervisor's clean-up, which removes only what no live node holds.
    drop(waiter);
    drop(observer);
    outcome.seen = seen;
    Ok((child, pids))
}

/// Every check of a finished run, each failure added to `outcome.failures`.
fn check_run(
    setup: &RunSetup<'_>,
    run: &RunId,
    out: &Path,
    exit: ExitInfo,
    mut pids: Vec<u32>,
    supervisor: u32,
    outcome: &mut RunOutcome,
) {
    let fail = &mut outcome.failures;
    if exit != ExitInfo::Exited(0) {
        fail.push(format!("hnav run ended with {exit}, not exit code 0"));
    }
    match swarm_run::read_summary(out) {
        Ok(summary) => {
            outcome.collisions = summary["collisions"].as_u64().unwrap_or(0);
            outcome.at_goal = swarm_run::goal_counts(&summary);
            if let Err(e) = swarm_run::check_summary(&summary) {
                fail.push(e);
            }
        }
        Err(e) => fail.push(e),
    }
    let hnav = setup.bin_dir.join("hnav");
    match swarm_run::verify_log(&hnav, out) {
        Ok(()) => outcome.verified = true,
        Err(e) => fail.push(e),
    }
    let seen: Vec<(u64, u64)> = outcome
        .seen
        .commits
        .iter()
        .map(|c| (c.round, c.digest))
        .collect();
    // Against the log, and with replicas against every replica's committed log.
    for (name, log) in checks::logs_of(&out.join("log")) {
        match checks::logged_commits(&log).and_then(|logged| checks::check_commits(&seen, &logged))
        {
            Ok(count) => outcome.commits = Some(count),
            Err(e) => fail.push(format!("commits{name}: {e}")),
        }
    }
    match checks::read_events(out) {
        Ok(events) => outcome.events = events,
        Err(e) => fail.push(e),
    }
    for (i, f) in outcome.plan.faults.iter().enumerate() {
        let fired = outcome
            .events
            .iter()
            .any(|e| e.event == "signalled" && e.fault == Some(i));
        if !fired {
            fail.push(format!("fault {i} ({f}) never fired"));
        }
    }
    let left = run_files(run);
    outcome.leaked_files = left.len();
    if !left.is_empty() {
        fail.push(format!("left behind: {left:?}"));
    }
    pids.push(supervisor);
    pids.extend(outcome.events.iter().filter_map(|e| e.pid));
    pids.sort_unstable();
    pids.dedup();
    let alive = checks::alive_of_run(&pids, run.as_str());
    outcome.left_alive = alive.len();
    if !alive.is_empty() {
        fail.push(format!("processes of the run still alive: {alive:?}"));
        for pid in alive {
            let _ = nix::sys::signal::kill(
                nix::unistd::Pid::from_raw(pid as i32),
                nix::sys::signal::Signal::SIGKILL,
            );
        }
    }
}
