//! `hnav run`: one run of a scenario, end to end.
//!
//! 1. Clean the runs of the registry whose supervisor is dead ([`super::clean`]); claim the
//!    run id (refused while a live supervisor holds it) and then the run directory (refused
//!    while a live run holds it, and when it holds a finished run's outputs unless `--force`,
//!    see [`super::run_dir`]), both before anything is spawned; register the run for
//!    `hnav ps`.
//! 2. Spawn `hnav-sim`, `hnav-coordinator` and one `hnav-agent` per robot, each in its own
//!    process group with its output in `DIR/logs/<node>.log`, and wait until every one has
//!    announced itself on `ready`; then publish `Start` (see [`hnav_runtime::launch`] and
//!    [`super::startup`]).
//! 3. Watch (module `watch`): block in a `Waiter` on the children's exit descriptors (a
//!    child's death wakes it at once) with a short tick for the progress bar and the fault
//!    schedule. A dead child is reaped, the others told on the lifecycle topic, its stale
//!    iceoryx2 resources removed on the sweeper's thread (which wakes its peers with a "peer
//!    dead" event), and it is
//!    restarted under its role's policy with `--resume` (module `slots`). The progress bar
//!    (`progress`) follows the coordinator's progress topic; the scenario's planned faults
//!    (`faults`) too in realtime, and the sim's `Hold` at each fault's round in lockstep.
//!    Every process that is up has a hang deadline (`hang`): one silent past it is SIGKILLed
//!    and takes the same path. A process the supervisor SIGKILLed itself is told `Down` as
//!    soon as every thread of it has entered the kernel's exit (`dying`), not at the reap.
//!    The fault schedule, the hang watch and the slots only decide, and return actions
//!    (`action`); the watch alone carries them out.
//! 4. End when the coordinator reports every agent at its goal, or (lockstep) the last round
//!    of the time limit committed; when the time limit passes on the wall clock (realtime);
//!    when the run cannot go on (the sim or the coordinator down and not restarted, or no
//!    agent left); or when the supervisor is asked to stop (SIGINT/SIGTERM): publish `Stop`
//!    with its [`StopReason`], give the children a grace period, then SIGTERM and SIGKILL
//!    their process groups; remove the run's shared memory; write `DIR/summary.json` from
//!    the consensus log and the last ground truth.
//! 5. Record and draw: unless `--no-record`, the recorder thread ([`super::recorder`]) writes
//!    `DIR/recording/` from the run's first truth message until just before `Stop`, and its
//!    counts go into the summary; after the summary, `DIR/report.svg` is drawn
//!    ([`crate::report`]) from the log, the recording and the copy of the run's map that
//!    step 1 wrote (`DIR/map.map`). A report that cannot be drawn is a warning on stderr and
//!    the summary's `report_error`, never a failed run.

// Modules, highest first (a module uses only those below it):
//
// | module | what it holds |
// |---|---|
// | `watch` | the watch from `Start` to the end: its loop, and the one place its actions are carried out |
// | `faults` | the planned faults: when each is due, its signal, the lockstep hold, the end of a freeze |
// | `hang` | the hang deadlines of the processes that are up, and the kill of a silent one |
// | `progress` | the progress bar (or line) |
// | `dying` | processes the supervisor SIGKILLed, told `Down` once they can no longer act, before the kernel has torn them down |
// | `slots` | the run's processes: spawn, reap, restart under their policy, `Up`s announced |
// | `sweeper` | dead nodes' shared memory removed on a thread of its own, so that it never delays a reap |
// | `ros2` | `hnav-ros2`, the run's ROS 2 publisher: a process beside the roster |
// | `host` | this host's part of a run across hosts; the list of a run's processes |
// | `action` | what the watch's parts want done: signals, journal lines, lifecycle messages, respawns |
// | `error` | [`RunError`] |
mod watch;

mod faults;
mod hang;
mod progress;

mod dying;

mod slots;
mod sweeper;

mod ros2;

mod host;

mod action;
mod error;

#[cfg(test)]
mod across_tests;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::child::Child;
use super::clean::clean_dead_runs;
use super::events::RunEvents;
use super::recorder::{Recorder, RecordingSummary};
use super::registry::{RunRecord, RunRegistry};
use super::run_dir::RunDir;
use super::startup::{Roll, Startup};
use super::stop::stop_all;
use super::summary::RunSummary;
use crate::invocation::Invocation;
use error::io;
use faults::FaultSchedule;
use hang::HangWatch;
use hnav_runtime::consensus_log::EndReason;
use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::msg::{Lifecycle, Role, StopReason, TruthView};
use hnav_runtime::scenario::{Scenario, SimKind};
use hnav_runtime::transport::{purge_run, Bell, RunId};
use slots::Slots;
use watch::{End, Ports, Seen, Watch};

pub use error::RunError;
pub use host::HostPart;
pub use ros2::Ros2Options;

/// How long a child gets after `Stop`, and again after SIGTERM.
pub const STOP_GRACE: Duration = Duration::from_secs(3);

/// What `hnav run` needs.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// The processes' shared arguments (run id, scenario, overrides, run directory).
    pub args: ProcessArgs,
    /// Where `hnav-sim`, `hnav-coordinator` and `hnav-agent` are.
    pub bin_dir: PathBuf,
    /// Whether stderr is a terminal: a progress bar there, else a progress line every few
    /// seconds.
    pub progress: bool,
    /// Replace the outputs of a finished run in the run directory (`--force`).
    pub force: bool,
    /// Record trajectories and neural maps into `DIR/recording/` (off: `--no-record`).
    pub record: bool,
    /// In a run across hosts, this host's part (`--host NAME`): only its processes and its
    /// bridge are started here.
    pub host: Option<HostPart>,
    /// Publish the run as ROS 2 topics (`--ros2`, or the scenario's `[ros2]`): how
    /// `hnav-ros2` joins the graph.
    pub ros2: Option<Ros2Options>,
}

/// Runs the scenario to its end and returns the summary (also written to `DIR/summary.json`).
pub fn run(opts: &RunOptions) -> Result<RunSummary, RunError> {
    let scenario = opts.args.scenario()?;
    let run = match &opts.host {
        Some(h) => h.run_id(opts.args.run_id()?)?,
        None => opts.args.run_id()?,
    };
    let dir = opts.args.dir.clone().ok_or(RunError::NoRunDir)?;
    let registry = RunRegistry::default_location();
    for cleaned in clean_dead_runs(&registry) {
        match cleaned {
            Ok(c) => tracing::info!("{c} (its supervisor was dead)"),
            Err(e) => tracing::warn!("a dead run was not cleaned: {e}"),
        }
    }
    let id = registry.claim(&run, &dir)?;
    let result = RunDir::claim(&dir, &run, opts.force)
        .map_err(RunError::from)
        .and_then(|owned| {
            let result = run_owned(opts, scenario, run, dir, &registry);
            owned.release()?;
            result
        });
    id.release()?;
    result
}

/// Set to `1`, the supervisor runs without the commit [`Bell`] (for comparisons).
pub const NO_BELL_ENV: &str = "HNAV_NO_BELL";

/// The run once its id and directory are its own: prepared, started and watched, stopped,
/// summed up.
fn run_owned(
    opts: &RunOptions,
    scenario: Scenario,
    run: RunId,
    dir: PathBuf,
    registry: &RunRegistry,
) -> Result<RunSummary, RunError> {
    prepare_dir(&dir, &scenario)?;
    Invocation::new(&opts.args, &scenario)
        .write(&dir)
        .map_err(io(&dir))?;
    let ports = Ports::open(&run, scenario.agents.len(), opts.host.is_some())?;
    // Started before any process, so the recording begins with the first truth message.
    let recorder = start_recorder(opts, &run, &scenario, &dir);
    let outside = scenario.sim.kind == SimKind::Ros2;
    let ros2 = (!outside)
        .then(|| start_ros2(opts, &dir, run.domain()))
        .flatten();
    let mut record = registry.new_record(&run, &dir);
    record.set_process_args(&opts.args);
    let started = Instant::now();
    let bell = open_bell()?;
    let host = opts.host.as_ref();
    let mut slots = Slots::new(
        &opts.args,
        &opts.bin_dir,
        &scenario,
        &dir,
        bell.as_ref(),
        host,
        run.domain(),
    );
    if let (true, Some(r)) = (outside, &opts.ros2) {
        slots = slots.with_outside_robots(&opts.bin_dir, r);
    }
    let journal = RunEvents::create(&dir);
    // The last ground truth seen: a sample does not outlive its publisher, so a sim that is
    // down at the end (or gone for good) leaves only what was taken while it ran.
    let mut seen = Seen::default();
    let result = supervise(
        &ports,
        &scenario,
        &mut slots,
        journal,
        &mut record,
        opts.progress,
        &mut seen,
    );
    // Taken while the sim still runs; after the end of the run nothing moves any more in
    // lockstep.
    (ports.truth).drain(|h, p| seen.hold_truth(TruthView::new(h, p)))?;
    let recording = recorder.map(|r| r.map_or_else(|failed| failed, Recorder::finish));
    let reason = match result {
        Ok(End::TimeLimit) => StopReason::TimeLimit,
        _ => StopReason::Requested,
    };
    if let Some(p) = ros2 {
        p.stop(STOP_GRACE);
    }
    stop_run(ports, &slots, reason, &run, &record);
    let ended = Ended {
        end: result?,
        seen,
        lost: slots.lost_agents(),
        restarts: slots.restarts(),
        recording,
        elapsed_s: started.elapsed().as_secs_f64(),
    };
    summarize(host, &scenario, &run, &dir, ended)
}

/// Starts the recorder thread, unless `--no-record` or, in a run across hosts, the sim runs
/// on another host. One that cannot start is a recording summary with its error: the run
/// goes on unrecorded.
fn start_recorder(
    opts: &RunOptions,
    run: &RunId,
    scenario: &Scenario,
    dir: &Path,
) -> Option<Result<Recorder, RecordingSummary>> {
    let sim_here = opts.host.as_ref().is_none_or(|h| h.this().sim);
    let recorder = (opts.record && sim_here).then(|| Recorder::start(run, scenario, dir))?;
    Some(recorder.map_err(|e| {
        tracing::warn!("no recording: {e}");
        RecordingSummary {
            error: Some(e.to_string()),
            ..RecordingSummary::default()
        }
    }))
}

/// Starts `hnav-ros2` when asked; one that cannot start is a warning, the run goes on.
fn start_ros2(opts: &RunOptions, dir: &Path, domain: Option<&str>) -> Option<ros2::Ros2Process> {
    let r = opts.ros2.as_ref()?;
    match ros2::Ros2Process::start(r, &opts.args, &opts.bin_dir, dir, domain) {
        Ok(p) => {
            tracing::info!("hnav-ros2 started, its log {}", p.log().display());
            Some(p)
        }
        Err(e) => {
            tracing::warn!("hnav-ros2 did not start: {e}; the run goes on without ROS 2");
            None
        }
    }
}

/// The commit bell, kept open for the whole run: restarted processes inherit it too.
/// `HNAV_NO_BELL=1` runs without it (one datagram per agent and commit, as before the bell),
/// to compare.
fn open_bell() -> Result<Option<Bell>, RunError> {
    match std::env::var_os(NO_BELL_ENV) {
        Some(v) if v == "1" => Ok(None),
        _ => Ok(Some(Bell::create()?)),
    }
}

/// Ends the run's processes: `Stop` with its `reason`, then the escalating stop of
/// [`stop_all`]. Then removes the run's shared memory and its registry entry; a failure
/// there is a warning, the run is over.
fn stop_run(ports: Ports, slots: &Slots, reason: StopReason, run: &RunId, record: &RunRecord) {
    let _ = ports.life.publish(Lifecycle::stop(reason));
    for s in stop_all(slots.children(), STOP_GRACE) {
        tracing::debug!(node = s.role.node_name(s.index), how = ?s.how, "stopped");
    }
    drop(ports);
    if let Err(e) = purge_run(run) {
        tracing::warn!(
            "shared memory of run {} not fully removed: {e}",
            run.as_str()
        );
    }
    if let Err(e) = record.remove() {
        tracing::warn!("run registry entry not removed: {e}");
    }
}

/// What the summary is made from, once the run's processes are stopped.
struct Ended {
    end: End,
    seen: Seen,
    /// The agents gone for good and why, by index.
    lost: Vec<(u32, String)>,
    /// Restarts per process restarted at least once.
    restarts: std::collections::BTreeMap<String, u32>,
    recording: Option<RecordingSummary>,
    elapsed_s: f64,
}

/// Writes `DIR/summary.json`, then draws `DIR/report.svg` from it (a report that cannot be
/// drawn is a warning and the summary's `report_error`). In a run across hosts, a host
/// without the coordinator has no log: its summary says what crossed the bridge.
fn summarize(
    host: Option<&HostPart>,
    scenario: &Scenario,
    run: &RunId,
    dir: &Path,
    ended: Ended,
) -> Result<RunSummary, RunError> {
    let (truth, progress) = (ended.seen.truth.as_ref(), ended.seen.progress.as_ref());
    if let Some(h) = host.filter(|h| h.this().coordinator.is_empty()) {
        let mut summary =
            RunSummary::from_truth(run.as_str(), scenario, truth, progress, ended.elapsed_s);
        summary.counts_on_host = Some(h.coordinator_host().to_string());
        summary.restarts = ended.restarts;
        summary.fill_criteria(scenario, dir);
        summary.write_json(dir).map_err(io(dir))?;
        return Ok(summary);
    }
    let log = dir.join("log");
    let cell_m = scenario.robot.cell_size_m;
    let lifelong = scenario
        .tasks
        .as_ref()
        .map(|_| scenario.sim.control_period_s());
    let mut summary =
        RunSummary::from_log(run.as_str(), &log, truth, cell_m, ended.elapsed_s, lifelong)?;
    summary.mark_lost(&ended.lost);
    summary.rules = scenario.coordinator.rules.name().to_string();
    summary.restarts = ended.restarts;
    // Replicas stop together at the supervisor's time limit, before the leader's end record
    // is committed: the log then has no end, but the supervisor knows why the run ended.
    if summary.end == "incomplete" && matches!(ended.end, End::TimeLimit) {
        summary.end = EndReason::TimeLimit.name().to_string();
    }
    // A replica on a host of its own may hear the run's `Stop` before the leader's end
    // record reaches it: the end is then what crossed the bridge (ground truth, progress).
    if summary.end == "incomplete" && host.is_some() && matches!(ended.end, End::AllAtGoal) {
        let crossed =
            RunSummary::from_truth(run.as_str(), scenario, truth, progress, ended.elapsed_s);
        summary.end = crossed.end;
    }
    if let End::CannotGoOn(why) = ended.end {
        summary.cannot_go_on = Some(why);
    }
    summary.fill_criteria(scenario, dir);
    summary.recording = ended.recording;
    summary.write_json(dir).map_err(io(dir))?;
    if let Err(e) = crate::report::write_report(dir, &crate::report::ReportOptions::default()) {
        hnav_runtime::errln!("warning: {e}");
        summary.report_error = Some(e.to_string());
        summary.write_json(dir).map_err(io(dir))?;
    }
    Ok(summary)
}

/// Creates the directory of the processes' logs; [`RunDir::claim`] has removed (with
/// `--force`) or refused whatever an earlier run left.
/// Also keeps a copy of the run's map (`DIR/map.map`, MovingAI format) for the report: the
/// log's header has the agents' cells and the map's size but not its obstacles, and the
/// scenario may have named a file that changes or goes.
fn prepare_dir(dir: &Path, scenario: &Scenario) -> Result<(), RunError> {
    let logs = dir.join("logs");
    std::fs::create_dir_all(&logs).map_err(io(&logs))?;
    let map = dir.join(crate::report::MAP_FILE);
    std::fs::write(&map, hnav_runtime::grid::write_map(&scenario.map.grid)).map_err(io(&map))?;
    Ok(())
}

/// Spawns the processes, runs the start-up handshake, then watches until the run ends,
/// reaping and restarting whatever dies.
fn supervise(
    ports: &Ports,
    scenario: &Scenario,
    slots: &mut Slots,
    journal: RunEvents,
    record: &mut RunRecord,
    show_progress: bool,
    seen: &mut Seen,
) -> Result<End, RunError> {
    // Open before any process starts, so that no beat finds the topic missing.
    let hang = HangWatch::open(&ports.transport, scenario)?;
    if start_up(ports, scenario, slots, record)? == Startup::Interrupted {
        return Ok(End::Signalled);
    }
    let faults = FaultSchedule::new(scenario, slots.host());
    Watch::start(ports, scenario, faults, journal, hang, show_progress, seen)
        .until_end(slots, record)
}

/// Spawns the processes and runs the start-up handshake, up to `Start`. In a run across
/// hosts, the bridge first: nothing of this host may announce itself before the other hosts
/// can hear it.
fn start_up(
    ports: &Ports,
    scenario: &Scenario,
    slots: &mut Slots,
    record: &mut RunRecord,
) -> Result<Startup, RunError> {
    let transport = &ports.transport;
    let deadline = Instant::now() + scenario.startup_timeout();
    let mut roll = Roll::of(&[]);
    if let Some(h) = slots.host() {
        h.add_remote(&mut roll);
        slots.spawn_all(Some(Role::Bridge))?;
        let bridge: Vec<&Child> = slots.children().collect();
        roll.add(&bridge);
        let up = ports
            .life
            .wait_up(transport, &bridge, &mut roll, Some(Role::Bridge), deadline)?;
        if up.is_none() {
            return Ok(Startup::Interrupted);
        }
    }
    slots.spawn_all(None)?;
    slots.write_record(record);
    let children: Vec<&Child> = slots.children().collect();
    roll.add(&children);
    let left = deadline.saturating_duration_since(Instant::now());
    Ok(ports
        .life
        .start_roll(transport, &children, &mut roll, left)?)
}

/// The run directory `hnav run` uses when none is given: `target/hnav-out/<scenario name>`,
/// and for host `NAME` of a run across hosts (`host`) `target/hnav-out/<scenario name>-NAME`,
/// so that hosts sharing a machine do not share a directory.
pub fn default_run_dir(scenario: &Scenario, host: Option<&str>) -> PathBuf {
    match host {
        None => hnav_runtime::scenario::default_out_dir(&scenario.name),
        Some(h) => hnav_runtime::scenario::default_out_dir(&format!("{}-{h}", scenario.name)),
    }
}

/// A fresh run id for `hnav run`.
pub fn new_run_id() -> RunId {
    RunId::unique("run")
}
