//! `hnav run`: one run of a scenario, end to end.
//!
//! 1. Prepare the run directory (a previous run's log and checkpoints are removed: a log
//!    left there would make the new coordinator resume the old run) and register the run for
//!    `hnav ps`.
//! 2. Spawn `hnav-sim`, `hnav-coordinator` and one `hnav-agent` per robot, each in its own
//!    process group with its output in `DIR/logs/<node>.log`, and wait until every one has
//!    announced itself on `ready`; then publish `Start` (see [`crate::launch`]).
//! 3. Watch: block in a WaitSet on the children's exit descriptors (a child's death wakes it
//!    at once) with a short tick for the progress bar and the fault schedule. A dead child is
//!    reaped, its stale iceoryx2 resources removed (which wakes its peers with a "peer dead"
//!    event), the others told on the lifecycle topic, and it is restarted under its role's
//!    policy with `--resume`.
//! 4. End when the coordinator reports every agent at its goal, the time limit passes, or
//!    the supervisor is asked to stop (SIGINT/SIGTERM): publish `Stop`, give the children a
//!    grace period, then SIGTERM and SIGKILL their process groups; remove the run's shared
//!    memory; write `DIR/summary.json` from the consensus log and the last ground truth.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use iceoryx2::prelude::CallbackProgression;
use iceoryx2::waitset::WaitSetRunResult;

use super::child::{Child, ChildError, ChildSpec, Signal};
use super::registry::{node_name, RunRecord, RunRegistry};
use super::restart::{RestartDecision, RestartTracker};
use super::stop::stop_all;
use super::summary::RunSummary;
use crate::launch::{now_ns, ProcessArgs};
use crate::msg::{Lifecycle, LifecycleEvent, Progress, Role, Truth};
use crate::scenario::{FaultSignal, FaultTarget, Scenario, ScenarioError};
use crate::topics;
use crate::transport::{purge_run, Receiver, RunId, Sender, Transport, TransportError};

/// How long the processes get to come up.
pub const STARTUP_TIMEOUT: Duration = Duration::from_secs(60);
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
    /// Show a progress bar (on a terminal).
    pub progress: bool,
}

/// What can stop a run from happening at all.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario is unusable.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The transport failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// A process could not be started.
    #[error(transparent)]
    Child(#[from] ChildError),
    /// The run directory could not be prepared or the summary written.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// A process did not come up.
    #[error("start-up failed: {0}")]
    Startup(String),
    /// The consensus log could not be read for the summary.
    #[error(transparent)]
    Log(#[from] crate::consensus_log::LogError),
    /// The WaitSet failed.
    #[error("waitset: {0}")]
    WaitSet(String),
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + '_ {
    move |source| RunError::Io {
        path: path.to_path_buf(),
        source,
    }
}

struct Slot {
    spec: ChildSpec,
    child: Option<Child>,
    tracker: RestartTracker,
    restart_at: Option<Instant>,
    /// Restarted, `Restarted` not yet announced: that waits until the new process is up, so
    /// that peers reacting to it (the sim resends odometry) find its ports.
    announce: std::cell::Cell<bool>,
}

struct Ports {
    ready: Receiver<Lifecycle>,
    life: Sender<Lifecycle>,
    progress: Receiver<Progress>,
    truth: Receiver<Truth>,
}

/// Runs the scenario to its end and returns the summary (also written to `DIR/summary.json`).
pub fn run(opts: &RunOptions) -> Result<RunSummary, RunError> {
    let scenario = opts.args.scenario()?;
    let run = opts.args.run_id()?;
    let dir = opts
        .args
        .dir
        .clone()
        .ok_or_else(|| RunError::Startup("no run directory".into()))?;
    prepare_dir(&dir)?;
    let transport = Transport::builder(&run)
        .node_name("supervisor")
        .handle_signals(true)
        .create()?;
    let n = scenario.agents.len();
    let ports = Ports {
        ready: transport.receiver(topics::READY, topics::lifecycle_qos(n))?,
        life: transport.sender(topics::LIFECYCLE, topics::lifecycle_qos(n))?,
        progress: transport.receiver(topics::PROGRESS, topics::state_qos())?,
        truth: transport.receiver(topics::TRUTH, topics::state_qos())?,
    };
    let registry = RunRegistry::default_location();
    let mut record = registry.new_record(&run, &dir);
    let started = Instant::now();
    let mut slots = specs(opts, &scenario, &dir);
    let result = supervise(
        &transport,
        &ports,
        &scenario,
        &mut slots,
        &mut record,
        opts.progress,
    );
    // The last ground truth, taken while the sim still runs (a sample does not outlive its
    // publisher). After the end of the run nothing moves any more in lockstep.
    let mut truth = None;
    ports.truth.drain(|t| truth = Some(*t))?;
    let time_limit = result.as_ref().is_ok_and(|e| *e == End::TimeLimit);
    let _ = ports.life.send(event(
        Role::Sim,
        u32::from(time_limit),
        LifecycleEvent::Stop,
        0,
    ));
    let children: Vec<&Child> = slots.iter().filter_map(|s| s.child.as_ref()).collect();
    for s in stop_all(children, STOP_GRACE) {
        tracing::debug!(node = node_name(s.role, s.index), how = ?s.how, "stopped");
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
    result?;
    let summary = RunSummary::from_log(
        run.as_str(),
        &dir.join("log"),
        truth.as_ref(),
        scenario.robot.cell_size_m,
        started.elapsed().as_secs_f64(),
    )?;
    summary.write_json(&dir).map_err(io(&dir))?;
    Ok(summary)
}

/// Removes what a previous run left in `dir` that a new one would mistake for its own.
fn prepare_dir(dir: &Path) -> Result<(), RunError> {
    for sub in ["log", "agents", "logs"] {
        let p = dir.join(sub);
        if p.exists() {
            std::fs::remove_dir_all(&p).map_err(io(&p))?;
        }
    }
    let logs = dir.join("logs");
    std::fs::create_dir_all(&logs).map_err(io(&logs))?;
    let _ = std::fs::remove_file(dir.join("summary.json"));
    Ok(())
}

fn specs(opts: &RunOptions, scenario: &Scenario, dir: &Path) -> Vec<Slot> {
    let mut out = Vec::new();
    let mut add = |role: Role, index: u32, program: &str| {
        let rule = match role {
            Role::Sim => scenario.restart.sim,
            Role::Coordinator => scenario.restart.coordinator,
            Role::Agent => scenario.restart.agent,
        };
        let log = dir
            .join("logs")
            .join(format!("{}.log", node_name(role, index)));
        let mut spec = ChildSpec::new(role, index, opts.bin_dir.join(program), log);
        let args: Vec<OsString> = opts.args.to_args();
        for a in args {
            spec = spec.arg(a);
        }
        if role == Role::Agent {
            spec = spec.arg("--index").arg(index.to_string());
        }
        out.push(Slot {
            spec,
            child: None,
            tracker: RestartTracker::new(rule),
            restart_at: None,
            announce: std::cell::Cell::new(false),
        });
    };
    add(Role::Sim, 0, "hnav-sim");
    add(Role::Coordinator, 0, "hnav-coordinator");
    for i in 0..scenario.agents.len() as u32 {
        add(Role::Agent, i, "hnav-agent");
    }
    out
}

fn event(role: Role, index: u32, ev: LifecycleEvent, restarts: u32) -> Lifecycle {
    Lifecycle {
        time_ns: now_ns(),
        pid: 0,
        index,
        role: role as u8,
        event: ev as u8,
        reserved: 0,
        restarts,
    }
}

/// How the watched part of a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum End {
    AllAtGoal,
    TimeLimit,
    Signalled,
}

fn update_record(record: &mut RunRecord, slots: &[Slot]) {
    for s in slots {
        if let Some(c) = &s.child {
            record.set_process(s.spec.role, s.spec.index, c.pid(), s.tracker.restarts());
        }
    }
    if let Err(e) = record.write() {
        tracing::warn!("run registry entry not written: {e}");
    }
}

fn supervise(
    transport: &Transport,
    ports: &Ports,
    scenario: &Scenario,
    slots: &mut [Slot],
    record: &mut RunRecord,
    show_progress: bool,
) -> Result<End, RunError> {
    for s in slots.iter_mut() {
        s.child = Some(Child::spawn(&s.spec)?);
    }
    update_record(record, slots);
    if !wait_ready(transport, ports, slots)? {
        return Ok(End::Signalled);
    }
    ports
        .life
        .send(event(Role::Sim, 0, LifecycleEvent::Start, 0))?;
    let bar = progress_bar(show_progress, scenario.agents.len());
    let limit = Duration::from_secs_f64(scenario.coordinator.time_limit_s.max(0.0));
    let t0 = Instant::now();
    let mut faults_done = vec![false; scenario.faults.len()];
    let ws_err = |e: &dyn std::fmt::Debug| RunError::WaitSet(format!("{e:?}"));
    loop {
        let ws = transport.waitset()?;
        let mut guards = vec![ws
            .attach_notification(ports.ready.listener())
            .map_err(|e| ws_err(&e))?];
        for s in slots.iter() {
            if let Some(c) = &s.child {
                guards.push(
                    ws.attach_notification(c.exit_fd())
                        .map_err(|e| ws_err(&e))?,
                );
            }
        }
        let mut exited = false;
        let end = loop {
            announce_restarts(ports, slots)?;
            let mut last = None;
            ports.progress.take_wakeup()?;
            ports.progress.drain(|p| last = Some(*p))?;
            if let Some(p) = last {
                if let Some(b) = &bar {
                    b.set_position(u64::from(p.at_goal));
                    b.set_message(format!(
                        "round {}  conflicts {}  replans {}",
                        p.round, p.conflicts, p.replans
                    ));
                }
                fire_faults(scenario, slots, p.round, &mut faults_done);
                if p.done == 1 {
                    break Some(End::AllAtGoal);
                }
            }
            if t0.elapsed() >= limit {
                break Some(End::TimeLimit);
            }
            let now = Instant::now();
            let due = slots.iter().filter_map(|s| s.restart_at).min();
            if due.is_some_and(|d| d <= now) {
                break None;
            }
            let mut timeout = TICK.min(limit.saturating_sub(t0.elapsed()));
            if let Some(d) = due {
                timeout = timeout.min(d - now);
            }
            match ws.wait_and_process_once_with_timeout(
                |_| {
                    exited = true;
                    CallbackProgression::Continue
                },
                timeout,
            ) {
                Ok(WaitSetRunResult::TerminationRequest | WaitSetRunResult::Interrupt) => {
                    break Some(End::Signalled)
                }
                Ok(_) => {}
                Err(e) => return Err(ws_err(&e)),
            }
            if exited {
                break None;
            }
        };
        drop(guards);
        drop(ws);
        if let Some(end) = end {
            if let Some(b) = bar {
                b.finish_and_clear();
            }
            return Ok(end);
        }
        reap_and_restart(transport, ports, slots)?;
        update_record(record, slots);
    }
}

/// Waits until every child has published `Up` on `ready`; `false` if a signal came first.
fn wait_ready(transport: &Transport, ports: &Ports, slots: &[Slot]) -> Result<bool, RunError> {
    let mut up = vec![false; slots.len()];
    let ws = transport.waitset()?;
    let ws_err = |e: &dyn std::fmt::Debug| RunError::WaitSet(format!("{e:?}"));
    let _g = ws
        .attach_notification(ports.ready.listener())
        .map_err(|e| ws_err(&e))?;
    let deadline = Instant::now() + STARTUP_TIMEOUT;
    loop {
        ports.ready.take_wakeup()?;
        ports.ready.drain(|l| {
            if let Some(role) = Role::from_u8(l.role) {
                if let Some(i) = slots
                    .iter()
                    .position(|s| s.spec.role == role && s.spec.index == l.index)
                {
                    up[i] = true;
                }
            }
        })?;
        if up.iter().all(|&u| u) {
            return Ok(true);
        }
        for s in slots {
            if let Some(exit) = s.child.as_ref().and_then(|c| c.try_reap()) {
                return Err(RunError::Startup(format!(
                    "{} exited during start-up ({exit}); see {}",
                    node_name(s.spec.role, s.spec.index),
                    s.spec.log_file.display()
                )));
            }
        }
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            let missing: Vec<String> = slots
                .iter()
                .zip(&up)
                .filter(|(_, &u)| !u)
                .map(|(s, _)| node_name(s.spec.role, s.spec.index))
                .collect();
            return Err(RunError::Startup(format!(
                "not up within {STARTUP_TIMEOUT:?}: {}",
                missing.join(", ")
            )));
        }
        match ws.wait_and_process_once_with_timeout(
            |_| CallbackProgression::Continue,
            left.min(Duration::from_millis(200)),
        ) {
            Ok(WaitSetRunResult::TerminationRequest | WaitSetRunResult::Interrupt) => {
                return Ok(false)
            }
            Ok(_) => {}
            Err(e) => return Err(ws_err(&e)),
        }
    }
}

/// Reaps exited children, tells the others, and restarts what is due.
fn reap_and_restart(
    transport: &Transport,
    ports: &Ports,
    slots: &mut [Slot],
) -> Result<(), RunError> {
    let mut died = false;
    for s in slots.iter_mut() {
        let Some(exit) = s.child.as_ref().and_then(|c| c.try_reap()) else {
            continue;
        };
        died = true;
        s.child = None;
        let (role, index) = (s.spec.role, s.spec.index);
        tracing::warn!(node = node_name(role, index), %exit, "process exited");
        ports.life.send(event(
            role,
            index,
            LifecycleEvent::Down,
            s.tracker.restarts(),
        ))?;
        match s.tracker.on_exit(&exit) {
            RestartDecision::Restart { after } => s.restart_at = Some(Instant::now() + after),
            RestartDecision::GiveUp(why) => {
                tracing::warn!(node = node_name(role, index), ?why, "not restarted")
            }
        }
    }
    if died {
        // Removing the dead nodes' resources wakes their peers with "peer dead".
        if let Err(e) = transport.cleanup_dead_nodes() {
            tracing::warn!("dead-node clean-up failed: {e}");
        }
    }
    let now = Instant::now();
    for s in slots.iter_mut() {
        if s.restart_at.is_some_and(|t| t <= now) {
            s.restart_at = None;
            let spec = s.spec.clone().arg("--resume");
            let child = Child::spawn(&spec)?;
            tracing::info!(
                node = node_name(spec.role, spec.index),
                pid = child.pid(),
                "restarted"
            );
            s.child = Some(child);
            s.announce.set(true);
        }
    }
    Ok(())
}

/// Publishes `Restarted` for every restarted process that has announced itself up.
fn announce_restarts(ports: &Ports, slots: &[Slot]) -> Result<(), RunError> {
    ports.ready.take_wakeup()?;
    let mut up = Vec::new();
    ports.ready.drain(|l| up.push((l.role, l.index)))?;
    for (role, index) in up {
        let slot = slots
            .iter()
            .find(|s| s.announce.get() && s.spec.role as u8 == role && s.spec.index == index);
        if let Some(s) = slot {
            s.announce.set(false);
            ports.life.send(event(
                s.spec.role,
                s.spec.index,
                LifecycleEvent::Restarted,
                s.tracker.restarts(),
            ))?;
        }
    }
    Ok(())
}

/// Sends the signals of the faults whose round has come.
fn fire_faults(scenario: &Scenario, slots: &[Slot], round: u64, done: &mut [bool]) {
    for (f, d) in scenario.faults.iter().zip(done.iter_mut()) {
        if *d || round < f.at_round {
            continue;
        }
        *d = true;
        let (role, index) = match f.target {
            FaultTarget::Agent(i) => (Role::Agent, i as u32),
            FaultTarget::Coordinator => (Role::Coordinator, 0),
            FaultTarget::Sim => (Role::Sim, 0),
        };
        let signal = match f.signal {
            FaultSignal::Kill => Signal::SIGKILL,
            FaultSignal::Term => Signal::SIGTERM,
        };
        let target = slots
            .iter()
            .find(|s| s.spec.role == role && s.spec.index == index)
            .and_then(|s| s.child.as_ref());
        if let Some(c) = target {
            tracing::warn!(
                node = node_name(role, index),
                ?signal,
                round,
                "fault injected"
            );
            if let Err(e) = c.signal(signal) {
                tracing::warn!("fault not injected: {e}");
            }
        }
    }
}

fn progress_bar(show: bool, agents: usize) -> Option<indicatif::ProgressBar> {
    if !show {
        return None;
    }
    let bar = indicatif::ProgressBar::new(agents as u64);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{elapsed_precise} [{bar:30}] {pos}/{len} at goal  {msg}",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    Some(bar)
}

/// The run directory `hnav run` uses when none is given: `target/hnav-out/<scenario name>`.
pub fn default_run_dir(scenario: &Scenario) -> PathBuf {
    crate::scenario::default_out_dir(&scenario.name)
}

/// A fresh run id for `hnav run`.
pub fn new_run_id() -> RunId {
    RunId::unique("run")
}
