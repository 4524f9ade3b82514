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
//! 3. Watch: block in a `Waiter` on the children's exit descriptors (a child's death wakes it
//!    at once) with a short tick for the progress bar and the fault schedule. A dead child is
//!    reaped, its stale iceoryx2 resources removed (which wakes its peers with a "peer dead"
//!    event), the others told on the lifecycle topic, and it is restarted under its role's
//!    policy with `--resume` (module `slots`). The progress bar (`progress`) follows the
//!    coordinator's progress topic; the scenario's planned faults (`faults`) too in realtime,
//!    and the sim's `Hold` at each fault's round in lockstep. Every process that is up has a
//!    hang deadline (`hang`): one silent past it is SIGKILLed and takes the same path.
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

mod error;
mod faults;
mod hang;
mod host;
mod progress;
mod slots;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::child::Child;
use super::clean::clean_dead_runs;
use super::recorder::{Recorder, RecordingSummary};
use super::registry::{RunRecord, RunRegistry};
use super::run_dir::RunDir;
use super::startup::{Roll, Startup, SupervisorPorts};
use super::stop::stop_all;
use super::summary::RunSummary;
use crate::invocation::Invocation;
use error::io;
use faults::FaultSchedule;
use hang::HangWatch;
use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::msg::{Lifecycle, Progress, Role, StopReason, Truth};
use hnav_runtime::scenario::{ClockMode, Scenario};
use hnav_runtime::topics;
use hnav_runtime::transport::{purge_run, Bell, Receiver, RunId, Transport, Wake};
use progress::ProgressView;
use slots::Slots;

pub use error::RunError;
pub use host::HostPart;

/// How long a child gets after `Stop`, and again after SIGTERM.
pub const STOP_GRACE: Duration = Duration::from_secs(3);
/// Refresh period of the progress bar and the fault schedule.
const TICK: Duration = Duration::from_millis(50);

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
}

struct Ports {
    life: SupervisorPorts,
    progress: Receiver<Progress>,
    truth: Receiver<Truth>,
}

/// Runs the scenario to its end and returns the summary (also written to `DIR/summary.json`).
pub fn run(opts: &RunOptions) -> Result<RunSummary, RunError> {
    let scenario = opts.args.scenario()?;
    let run = opts.args.run_id()?;
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

/// The run once its id and directory are its own.
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
    let transport = Transport::builder(&run)
        .node_name("supervisor")
        .handle_signals(true)
        .create()?;
    let n = scenario.agents.len();
    let ports = Ports {
        life: SupervisorPorts::open(&transport, n)?,
        progress: transport.receiver(topics::PROGRESS, topics::progress_qos())?,
        truth: transport.receiver(topics::TRUTH, topics::truth_qos())?,
    };
    // Started before any process, so the recording begins with the first truth message.
    // In a run across hosts, on the sim's host only.
    let sim_here = opts.host.as_ref().is_none_or(|h| h.this().sim);
    let recorder = (opts.record && sim_here)
        .then(|| Recorder::start(&run, &scenario, &dir))
        .map(|r| {
            r.map_err(|e| {
                tracing::warn!("no recording: {e}");
                RecordingSummary {
                    error: Some(e.to_string()),
                    ..RecordingSummary::default()
                }
            })
        });
    let mut record = registry.new_record(&run, &dir);
    record.set_process_args(&opts.args);
    let started = Instant::now();
    // Kept open for the whole run: restarted processes inherit it too. `HNAV_NO_BELL=1` runs
    // without it (one datagram per agent and commit, as before the bell), to compare.
    let bell = match std::env::var_os(NO_BELL_ENV) {
        Some(v) if v == "1" => None,
        _ => Some(Bell::create()?),
    };
    let host = opts.host.as_ref();
    let mut slots = Slots::new(
        &opts.args,
        &opts.bin_dir,
        &scenario,
        &dir,
        bell.as_ref(),
        host,
    );
    // The last ground truth seen: a sample does not outlive its publisher, so a sim that is
    // down at the end (or gone for good) leaves only what was taken while it ran.
    let mut seen = Seen::default();
    let result = supervise(
        &transport,
        &ports,
        &scenario,
        &mut slots,
        &mut record,
        opts.progress,
        &mut seen,
    );
    // Taken while the sim still runs; after the end of the run nothing moves any more in
    // lockstep.
    ports.truth.drain(|t| seen.truth = Some(*t))?;
    let recording = recorder.map(|r| r.map_or_else(|failed| failed, Recorder::finish));
    let reason = match result {
        Ok(End::TimeLimit) => StopReason::TimeLimit,
        _ => StopReason::Requested,
    };
    let _ = ports.life.publish(Lifecycle::stop(reason));
    for s in stop_all(slots.children(), STOP_GRACE) {
        tracing::debug!(node = s.role.node_name(s.index), how = ?s.how, "stopped");
    }
    drop(ports);
    drop(transport);
    if let Err(e) = purge_run(&run) {
        tracing::warn!(
            "shared memory of run {} not fully removed: {e}",
            run.as_str()
        );
    }
    if let Err(e) = record.remove() {
        tracing::warn!("run registry entry not removed: {e}");
    }
    let end = result?;
    if host.is_some_and(|h| !h.this().coordinator) {
        // The log is on the coordinator's host: say what crossed the bridge.
        let summary = RunSummary::from_truth(
            run.as_str(),
            &scenario,
            seen.truth.as_ref(),
            seen.progress.as_ref(),
            started.elapsed().as_secs_f64(),
        );
        summary.write_json(&dir).map_err(io(&dir))?;
        return Ok(summary);
    }
    let mut summary = RunSummary::from_log(
        run.as_str(),
        &dir.join("log"),
        seen.truth.as_ref(),
        scenario.robot.cell_size_m,
        started.elapsed().as_secs_f64(),
    )?;
    summary.mark_lost(&slots.lost_agents());
    if let End::CannotGoOn(why) = end {
        summary.cannot_go_on = Some(why);
    }
    summary.recording = recording;
    summary.write_json(&dir).map_err(io(&dir))?;
    if let Err(e) = crate::report::write_report(&dir, &crate::report::ReportOptions::default()) {
        hnav_runtime::errln!("warning: {e}");
        summary.report_error = Some(e.to_string());
        summary.write_json(&dir).map_err(io(&dir))?;
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

/// The latest of what the run's processes published that the summary needs.
#[derive(Default)]
struct Seen {
    truth: Option<Truth>,
    progress: Option<Progress>,
}

/// How the watched part of a run ended.
#[derive(Debug, Clone, PartialEq, Eq)]
enum End {
    AllAtGoal,
    TimeLimit,
    Signalled,
    /// The sim or the coordinator is gone for good, or no agent is left: why.
    CannotGoOn(String),
}

/// Spawns the processes, runs the start-up handshake, then watches until the run ends,
/// reaping and restarting whatever dies.
fn supervise(
    transport: &Transport,
    ports: &Ports,
    scenario: &Scenario,
    slots: &mut Slots,
    record: &mut RunRecord,
    show_progress: bool,
    seen: &mut Seen,
) -> Result<End, RunError> {
    // Open before any process starts, so that no beat finds the topic missing.
    let hang = HangWatch::open(transport, scenario)?;
    let deadline = Instant::now() + scenario.startup_timeout();
    let mut roll = Roll::of(&[]);
    if let Some(h) = slots.host() {
        h.add_remote(&mut roll);
    }
    if slots.host().is_some() {
        // The bridge first: nothing of this host may announce itself before the other hosts
        // can hear it.
        slots.spawn_all(Some(Role::Bridge))?;
        let bridge: Vec<&Child> = slots.children().collect();
        roll.add(&bridge);
        if ports
            .life
            .wait_up(transport, &bridge, &mut roll, Some(Role::Bridge), deadline)?
            .is_none()
        {
            return Ok(End::Signalled);
        }
    }
    slots.spawn_all(None)?;
    slots.write_record(record);
    let children: Vec<&Child> = slots.children().collect();
    roll.add(&children);
    let left = deadline.saturating_duration_since(Instant::now());
    if ports
        .life
        .start_roll(transport, &children, &mut roll, left)?
        == Startup::Interrupted
    {
        return Ok(End::Signalled);
    }
    let lockstep = scenario.sim.clock == ClockMode::Lockstep;
    let mut watch = Watch {
        view: ProgressView::new(show_progress, scenario.agents.len()),
        seen,
        faults: FaultSchedule::new(&scenario.faults, lockstep, &scenario.sim),
        hang,
        round: 0,
        t0: Instant::now(),
        // In lockstep the coordinator counts the limit in rounds and says when it is reached.
        // A limit too large for a Duration (a valid scenario may say 1e300 s) never ends it.
        limit: (!lockstep).then(|| {
            Duration::try_from_secs_f64(scenario.coordinator.time_limit_s.max(0.0))
                .unwrap_or(Duration::MAX)
        }),
    };
    let end = watch.until_end(transport, ports, slots, record);
    // A process the plan froze and has not continued yet could not stop politely.
    watch.faults.thaw_all(slots);
    watch.view.finish();
    end
}

/// The state of the watch between two changes of the set of running processes.
struct Watch<'s> {
    view: ProgressView,
    /// The latest ground truth and progress taken in.
    seen: &'s mut Seen,
    faults: FaultSchedule<'s>,
    hang: HangWatch,
    /// The last committed round the coordinator reported.
    round: u64,
    t0: Instant,
    /// The wall-clock limit (realtime only).
    limit: Option<Duration>,
}

impl Watch<'_> {
    /// Watches, reaping and restarting whatever dies, until the run ends.
    fn until_end(
        &mut self,
        transport: &Transport,
        ports: &Ports,
        slots: &mut Slots,
        record: &mut RunRecord,
    ) -> Result<End, RunError> {
        loop {
            if let Some(end) = self.until_change(transport, ports, slots)? {
                return Ok(end);
            }
            if let Some(why) = slots.reap_and_restart(transport, &ports.life)? {
                return Ok(End::CannotGoOn(why));
            }
            slots.write_record(record);
        }
    }

    /// Follows the run until it ends (`Some`) or until a child exits, a restart is due or a
    /// process announces itself (`None`: reap, restart, and watch the new set of children).
    fn until_change(
        &mut self,
        transport: &Transport,
        ports: &Ports,
        slots: &Slots,
    ) -> Result<Option<End>, RunError> {
        let waiter = transport.waiter()?;
        let mut attached = vec![waiter.attach(ports.life.ready())?];
        for c in slots.children() {
            attached.push(c.watch(&waiter)?);
        }
        loop {
            // Progress first: it names the leader of replicated coordinators, whom a fault
            // at "the coordinator" hits when the sim holds for it below.
            if let Some(end) = self.on_progress(ports, slots)? {
                return Ok(Some(end));
            }
            for period in slots.announce_restarts(&ports.life)? {
                self.faults.on_hold(slots, period);
            }
            if let Some(period) = self.faults.resume_due(slots) {
                ports.life.publish(Lifecycle::resume(period))?;
            }
            self.faults.thaw_due(slots, Instant::now());
            self.faults.fire_due(slots, self.t0.elapsed());
            let left = self.limit.map(|l| l.saturating_sub(self.t0.elapsed()));
            if left.is_some_and(|l| l.is_zero()) {
                return Ok(Some(End::TimeLimit));
            }
            self.hang.follow(slots);
            let hung_due = self.hang.check(slots, self.round)?;
            let now = Instant::now();
            let due = slots.next_restart();
            if due.is_some_and(|d| d <= now) {
                return Ok(None);
            }
            // The next tick of the progress bar and the fault schedule, sooner if a restart,
            // a hang deadline, a fault in seconds or the end of a freeze is due, never past
            // the time limit.
            let mut until = now + left.map_or(TICK, |l| TICK.min(l));
            let timed = [due, hung_due, self.faults.next_deadline(self.t0)];
            for d in timed.into_iter().flatten() {
                until = until.min(d);
            }
            self.hang.before_wait(until);
            match waiter.wait(Some(until))? {
                Wake::Stop => return Ok(Some(End::Signalled)),
                // A child's exit, an `Up`, or only a re-check: reap and look again.
                Wake::Data => return Ok(None),
                Wake::TimedOut => {}
            }
        }
    }

    /// Shows the coordinator's latest progress and, in realtime, fires the faults due by its
    /// round (or by the time since `Start`); `AllAtGoal` or `TimeLimit` once it reports that it ended the run.
    fn on_progress(&mut self, ports: &Ports, slots: &Slots) -> Result<Option<End>, RunError> {
        let seen = &mut *self.seen;
        ports.truth.drain_pending(|t| seen.truth = Some(*t))?;
        let mut last = None;
        ports.progress.drain_pending(|p| last = Some(*p))?;
        let Some(p) = last else {
            return Ok(None);
        };
        self.seen.progress = Some(p);
        self.view.show(&p);
        self.round = p.round;
        self.faults.on_round(p.round);
        self.faults.on_leader(p.leader);
        self.faults.fire_due(slots, self.t0.elapsed());
        Ok(match p.done {
            Progress::ALL_AT_GOAL => Some(End::AllAtGoal),
            Progress::TIME_LIMIT => Some(End::TimeLimit),
            _ => None,
        })
    }
}

/// The run directory `hnav run` uses when none is given: `target/hnav-out/<scenario name>`.
pub fn default_run_dir(scenario: &Scenario) -> PathBuf {
    hnav_runtime::scenario::default_out_dir(&scenario.name)
}

/// A fresh run id for `hnav run`.
pub fn new_run_id() -> RunId {
    RunId::unique("run")
}
