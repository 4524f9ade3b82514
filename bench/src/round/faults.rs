//! `hnav-bench round --faults`: how fast a dead agent is noticed, and how fast a restarted
//! one is back in the round loop.
//!
//! **Detection** (no coordinator process needed): a child (`sleep 60`) is spawned with the
//! supervisor's own [`Child::spawn`] (its own process group, a pidfd exit descriptor), the
//! descriptor is attached to a `Waiter`, and the child is sent SIGKILL. Measured from just
//! before `kill(2)`:
//!
//! - (a) the waiter wakes on the exit descriptor;
//! - (b1) the supervisor's reaction is done: reaped (`try_reap`, as `hnav run` does) and
//!   `Lifecycle::down` published on `lifecycle`;
//! - (b2) a subscriber in another thread, blocked in its own `Waiter` as the coordinator is,
//!   has taken that `Down` sample.
//!
//! Not included: the dead node's iceoryx2 clean-up (`hnav run` does it after publishing
//! `Down`; `sleep` has no node anyway) and the restart policy's backoff.
//!
//! **Rejoin** (c), with a real `hnav-coordinator` and 8 agents: agent 3 is reported `Down`
//! and sits out a few rounds; then its new ports are opened (what a restarted process does
//! before it announces itself), and the clock starts: `Restarted` is published, agent 3's
//! candidate (flagged `RESTARTED`) is sent at once, the other 7 follow as in any round, and
//! the clock stops when agent 3's subscriber takes the first commit with a decision for it.
//! Not included: the restarted process's start-up (exec, opening its ports, building its
//! neural map) and the supervisor's restart backoff.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context, Result};

use hnav_operator::supervisor::child::{Child, ChildSpec, ExitInfo, Signal};
use hnav_operator::supervisor::exit_fd::WatchMode;
use hnav_runtime::msg::{Lifecycle, LifecycleEvent, Role};
use hnav_runtime::scenario::FsyncPolicy;
use hnav_runtime::topics;
use hnav_runtime::transport::{purge_run, RunId, Sender, Transport, Wake};

use super::observers::Observers;
use super::report::{Dist, FaultPoint};
use super::session::{with_coordinator, CoordinatorSetup};
use super::swarm::keep_going;

/// Agents of the rejoin measurement.
pub const REJOIN_AGENTS: usize = 8;
/// The agent that dies and comes back.
pub const VICTIM: usize = 3;
/// Rounds played before the first rejoin trial.
const REJOIN_WARMUP: u64 = 50;
/// Rounds played without the victim in each trial.
const DOWN_ROUNDS: u64 = 3;
/// Rounds the victim may take to get a decision before the trial fails.
const MAX_REJOIN_ROUNDS: u64 = 10;
/// Bound on every single wait of a detection trial.
const WAIT: Duration = Duration::from_secs(5);

/// Runs every fault measurement: detection (`trials` kills), then rejoin per fsync policy.
pub fn run(
    program: &Path,
    trials: usize,
    fsync: &[FsyncPolicy],
    mut each: impl FnMut(&FaultPoint),
) -> Result<Vec<FaultPoint>> {
    let mut points = Vec::new();
    hnav_runtime::errln!("fault detection: {trials} SIGKILLs of `sleep 60`");
    let (mode, det) = detection(trials)?;
    let how = match mode {
        WatchMode::Pidfd => "pidfd",
        _ => "waiter thread",
    };
    for (measure, label, samples) in [
        (
            "kill_to_wake",
            format!("(a) SIGKILL -> supervisor's waiter wakes ({how})"),
            &det.wake,
        ),
        (
            "kill_to_down_published",
            "(b1) SIGKILL -> reaped, Down published".to_string(),
            &det.published,
        ),
        (
            "kill_to_down_received",
            "(b2) SIGKILL -> Down taken by the coordinator's thread".to_string(),
            &det.received,
        ),
    ] {
        let p = FaultPoint {
            measure,
            label,
            coordinator: None,
            dist: Dist::from_ns(samples)?,
            stalled: 0,
        };
        each(&p);
        points.push(p);
    }
    for &policy in fsync {
        hnav_runtime::errln!(
            "rejoin: {REJOIN_AGENTS} agents, fsync {}: {trials} Down/Restarted trials of agent \
             {VICTIM}",
            super::layout::fsync_name(policy)
        );
        let (samples, late, stalled) = rejoin(program, policy, trials)?;
        if late > 0 {
            hnav_runtime::errln!(
                "note: in {late} of {trials} trials agent {VICTIM}'s first candidate missed \
                 the round and its decision came a round later"
            );
        }
        let p = FaultPoint {
            measure: "restarted_to_decision",
            label: format!(
                "(c) Restarted -> agent {VICTIM}'s decision ({REJOIN_AGENTS} agents, {})",
                super::layout::fsync_name(policy)
            ),
            coordinator: Some((REJOIN_AGENTS, policy)),
            dist: Dist::from_ns(&samples)?,
            stalled,
        };
        each(&p);
        points.push(p);
    }
    Ok(points)
}

struct Detection {
    wake: Vec<u64>,
    published: Vec<u64>,
    received: Vec<u64>,
}

fn ns(d: Duration) -> u64 {
    u64::try_from(d.as_nanos()).unwrap_or(u64::MAX)
}

fn detection(trials: usize) -> Result<(WatchMode, Detection)> {
    let run = RunId::unique("faults");
    let dir = std::env::temp_dir().join(format!("hnav-bench-{}", run.as_str()));
    let stop = AtomicBool::new(false);
    let result: Result<(WatchMode, Detection)> = std::thread::scope(|s| {
        let (ready_tx, ready_rx) = mpsc::channel();
        let (down_tx, down_rx) = mpsc::channel();
        let listener = std::thread::Builder::new()
            .name("coordinator-stand-in".into())
            .spawn_scoped(s, || listen(&run, ready_tx, down_tx, &stop))
            .context("start the listener thread")?;
        let measured = match ready_rx.recv_timeout(WAIT) {
            Ok(()) => detect(&run, &dir, trials, &down_rx),
            Err(_) => Err(anyhow!("the listener thread did not come up")),
        };
        stop.store(true, Ordering::Relaxed);
        let listened = listener
            .join()
            .map_err(|_| anyhow!("the listener thread panicked"))?;
        let out = measured?;
        listened?;
        Ok(out)
    });
    let purged = purge_run(&run);
    let _ = std::fs::remove_dir_all(&dir);
    let out = result?;
    purged.context("remove the run's shared memory")?;
    Ok(out)
}

/// The coordinator's side: a `lifecycle` subscriber in a `Waiter`; reports each `Down` with
/// the instant its sample was taken.
fn listen(
    run: &RunId,
    ready: mpsc::Sender<()>,
    downs: mpsc::Sender<(u32, Instant)>,
    stop: &AtomicBool,
) -> Result<()> {
    let transport = Transport::builder(run)
        .node_name(&Role::Coordinator.node_name(0))
        .create()?;
    let rx =
        transport.receiver::<Lifecycle>(topics::LIFECYCLE, topics::lifecycle_qos(REJOIN_AGENTS))?;
    let waiter = transport.waiter()?;
    let _attached = waiter.attach(&rx)?;
    let _ = ready.send(());
    while !stop.load(Ordering::Relaxed) {
        // The bounded wait only lets the thread see `stop`.
        let deadline = Instant::now() + Duration::from_millis(200);
        if waiter.wait(Some(deadline))? == Wake::Stop {
            return Ok(());
        }
        rx.drain_pending(|l| {
            let taken = Instant::now();
            if l.event == LifecycleEvent::Down as u8 {
                let _ = downs.send((l.pid, taken));
            }
        })?;
    }
    Ok(())
}

fn detect(
    run: &RunId,
    dir: &Path,
    trials: usize,
    downs: &mpsc::Receiver<(u32, Instant)>,
) -> Result<(WatchMode, Detection)> {
    let transport = Transport::builder(run).node_name("supervisor").create()?;
    let life = transport.sender(topics::LIFECYCLE, topics::lifecycle_qos(REJOIN_AGENTS))?;
    let spec = ChildSpec::new(Role::Agent, VICTIM as u32, "sleep", dir.join("sleep.log")).arg("60");
    let mut det = Detection {
        wake: Vec::with_capacity(trials),
        published: Vec::with_capacity(trials),
        received: Vec::with_capacity(trials),
    };
    let mut mode = WatchMode::Pidfd;
    for trial in 0..trials {
        let child = Child::spawn(&spec).context("start `sleep 60`")?;
        mode = child.exit_fd().mode();
        let (wake, published, received) = kill_once(&transport, &life, &child, downs)
            .with_context(|| format!("trial {trial}"))?;
        det.wake.push(wake);
        det.published.push(published);
        det.received.push(received);
    }
    Ok((mode, det))
}

/// Waits (bounded) until `pid` runs `sleep`, so the kill hits the program, not a half-started
/// fork. Set-up only, outside the measurement: a short poll of `/proc`.
fn wait_exec(pid: u32) -> Result<()> {
    let comm = format!("/proc/{pid}/comm");
    let deadline = Instant::now() + WAIT;
    while Instant::now() < deadline {
        if std::fs::read_to_string(&comm).is_ok_and(|c| c.trim_end() == "sleep") {
            return Ok(());
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    bail!("pid {pid} did not exec `sleep` within {WAIT:?}")
}

/// One SIGKILL; returns (a), (b1), (b2) in ns.
fn kill_once(
    transport: &Transport,
    life: &Sender<Lifecycle>,
    child: &Child,
    downs: &mpsc::Receiver<(u32, Instant)>,
) -> Result<(u64, u64, u64)> {
    wait_exec(child.pid())?;
    // No lost-wake-up re-check: an exit descriptor is not an iceoryx2 event, and a re-check
    // would only end the wait early with nothing to show.
    let waiter = transport.waiter()?.with_recheck(None);
    let exit = child.watch(&waiter)?;
    let exit_id = exit.id();
    let mut woke = None;
    let killed = Instant::now();
    child.signal(Signal::SIGKILL)?;
    let deadline = killed + WAIT;
    while woke.is_none() && Instant::now() < deadline {
        let wake = waiter.wait_with(Some(deadline), |id| {
            if woke.is_none() && id == exit_id {
                woke = Some(Instant::now());
            }
        })?;
        if wake == Wake::Stop {
            bail!("interrupted");
        }
    }
    let woke = woke.ok_or_else(|| anyhow!("no exit of pid {} within {WAIT:?}", child.pid()))?;
    drop(exit);
    // What `hnav run` does on the wake-up: reap, then tell the others.
    match child.try_reap() {
        Some(ExitInfo::Signaled(Signal::SIGKILL)) => {}
        other => bail!("pid {}: unexpected exit {other:?}", child.pid()),
    }
    life.send(Lifecycle::down(Role::Agent, VICTIM as u32, 0).with_pid(child.pid()))?;
    let published = Instant::now();
    let received = loop {
        let (pid, at) = downs
            .recv_timeout(WAIT)
            .map_err(|_| anyhow!("Down not received within {WAIT:?}"))?;
        if pid == child.pid() {
            break at;
        }
    };
    Ok((
        ns(woke - killed),
        ns(published - killed),
        ns(received - killed),
    ))
}

/// (c): `trials` Down/Restarted cycles of agent [`VICTIM`] under a real coordinator; returns
/// the latencies, how many trials needed more than one round, and how many were left out
/// because a round stalled.
fn rejoin(program: &Path, fsync: FsyncPolicy, trials: usize) -> Result<(Vec<u64>, usize, usize)> {
    let setup = CoordinatorSetup {
        fsync,
        replicas: 1,
        observers: Observers::default(),
        per_process: 1,
    };
    with_coordinator(program, REJOIN_AGENTS, setup, |session, swarm| {
        if let Some(t) = session.startup() {
            hnav_runtime::errln!(
                "for scale, not in (c): this hnav-coordinator took {:.1} ms from spawn to Up",
                t.as_secs_f64() * 1e3
            );
        }
        let (coordinator, life) = (session.coordinators(), session.lifecycle());
        swarm.play(coordinator, life, REJOIN_WARMUP, |_| Ok(()), keep_going)?;
        let mut samples = Vec::with_capacity(trials);
        let mut late = 0;
        let mut stalled = 0;
        for trial in 0..trials {
            swarm.kill(VICTIM);
            life.publish(Lifecycle::down(Role::Agent, VICTIM as u32, 0))?;
            swarm.play(coordinator, life, DOWN_ROUNDS, |_| Ok(()), keep_going)?;
            swarm.restart(VICTIM)?;
            let mut t0 = None;
            let mut back = None;
            let mut stall = false;
            swarm.play(
                coordinator,
                life,
                MAX_REJOIN_ROUNDS,
                |round| {
                    if t0.is_none() {
                        t0 = Some((round, Instant::now()));
                        life.publish(Lifecycle::restarted(Role::Agent, VICTIM as u32, 0))?;
                    }
                    Ok(())
                },
                |obs| {
                    stall |= obs.stalled;
                    match obs.got[VICTIM] {
                        Some((at, true)) => {
                            back = Some((obs.round, at));
                            std::ops::ControlFlow::Break(())
                        }
                        _ => std::ops::ControlFlow::Continue(()),
                    }
                },
            )?;
            let (Some((first, t0)), Some((round, at))) = (t0, back) else {
                bail!(
                    "trial {trial}: agent {VICTIM} got no decision within {MAX_REJOIN_ROUNDS} \
                     rounds of Restarted"
                );
            };
            if stall {
                hnav_runtime::errln!(
                    "warning: trial {trial} stalled (lost wake-up of the coordinator, see \
                     `hnav-bench round`); left out"
                );
                stalled += 1;
                continue;
            }
            late += usize::from(round != first);
            samples.push(ns(at - t0));
        }
        Ok((samples, late, stalled))
    })
}
