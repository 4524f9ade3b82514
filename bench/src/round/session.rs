//! A real `hnav-coordinator` (or a cluster of 3 or 5 replicas) under a stand-in supervisor:
//! scenario file, spawn, start-up handshake (`Up` on `ready`, `Start` on `lifecycle`),
//! lifecycle events, polite stop, and removal of the run's shared memory.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context, Result};

use hnav_operator::supervisor::child::{Child, ChildSpec, ExitInfo, Signal};
use hnav_operator::supervisor::run::NO_BELL_ENV;
use hnav_operator::supervisor::startup::{Startup, SupervisorPorts};
use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::msg::{Lifecycle, Role, StopReason};
use hnav_runtime::scenario::FsyncPolicy;
use hnav_runtime::transport::{purge_run, Bell, RunId, Transport, BELL_ENV};

use super::layout::Layout;
use super::observers::{Observers, Running};
use super::swarm::Swarm;

/// How long the coordinator gets to announce itself.
const STARTUP_TIMEOUT: Duration = Duration::from_secs(30);
/// How long it gets to exit after `Stop` (and again after SIGKILL).
const STOP_TIMEOUT: Duration = Duration::from_secs(10);
/// Lines of the coordinator's log quoted in an error.
const LOG_TAIL_LINES: usize = 12;

/// The `hnav-coordinator` binary next to the running benchmark executable.
pub fn coordinator_binary() -> Result<PathBuf> {
    let exe = std::env::current_exe().context("locate the hnav-bench executable")?;
    let dir = exe
        .parent()
        .ok_or_else(|| anyhow!("{} has no parent directory", exe.display()))?;
    let program = dir.join("hnav-coordinator");
    if !program.is_file() {
        bail!(
            "{} not found: build it next to hnav-bench (cargo build --release -p \
             hnav-coordinator -p hnav-bench)",
            program.display()
        );
    }
    Ok(program)
}

/// A running coordinator (or its replicas) and the supervisor's ports of its run.
pub struct Session {
    children: Vec<Child>,
    spawned: Instant,
    startup: std::cell::Cell<Option<Duration>>,
    life: SupervisorPorts,
    transport: Transport,
}

impl Session {
    /// The coordinator processes: one, or every replica (their exit descriptors wake a
    /// `Waiter` when they die).
    pub fn coordinators(&self) -> &[Child] {
        &self.children
    }

    /// How long the coordinators took from just before the first `spawn` to the last `Up` on
    /// `ready` (exec, scenario, ports, consensus log).
    pub fn startup(&self) -> Option<Duration> {
        self.startup.get()
    }

    /// The supervisor's lifecycle ports: events published there reach the coordinator as
    /// they would from `hnav run`.
    pub fn lifecycle(&self) -> &SupervisorPorts {
        &self.life
    }

    /// The supervisor's start-up handshake with the coordinators, as `hnav run` does it.
    fn handshake(&self) -> Result<()> {
        let children: Vec<&Child> = self.children.iter().collect();
        match self
            .life
            .start(&self.transport, &children, STARTUP_TIMEOUT)?
        {
            Startup::Started { all_up } => {
                self.startup.set(Some(all_up - self.spawned));
                Ok(())
            }
            Startup::Interrupted => bail!("interrupted"),
        }
    }

    /// `Stop` on `lifecycle`, then waits for every exit (bounded; SIGKILL after the bound).
    /// Every coordinator is waited for (or killed) even when an earlier one failed.
    fn stop(&self) -> Result<()> {
        let published = self
            .life
            .publish(Lifecycle::stop(StopReason::Requested))
            .context("publish Stop on lifecycle");
        let deadline = Instant::now() + STOP_TIMEOUT;
        let mut failed = Vec::new();
        for child in &self.children {
            let node = child.spec().role.node_name(child.spec().index);
            let left = deadline.saturating_duration_since(Instant::now());
            match child.wait(Some(left)) {
                Some(ExitInfo::Exited(0)) => {}
                Some(exit) => failed.push(format!("{node} ended with {exit}")),
                None => {
                    let _ = child.signal_group(Signal::SIGKILL);
                    let exit = child.wait(Some(STOP_TIMEOUT));
                    failed.push(format!(
                        "{node} did not exit within {STOP_TIMEOUT:?} of Stop; killed ({})",
                        exit.map_or("not reaped".to_string(), |e| e.to_string())
                    ));
                }
            }
        }
        published?;
        if failed.is_empty() {
            Ok(())
        } else {
            bail!("{}", failed.join("; "))
        }
    }

    /// The end of every coordinator's log, for an error message.
    fn log_tails(&self) -> String {
        let tails: Vec<String> = self
            .children
            .iter()
            .map(|c| log_tail(&c.spec().log_file))
            .collect();
        tails.join("\n")
    }
}

/// What the coordinator of a benchmark run is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CoordinatorSetup {
    /// The consensus log's fsync policy (every replica's).
    pub fsync: FsyncPolicy,
    /// 1 (one coordinator, today's behaviour), 3 or 5 Raft replicas.
    pub replicas: u32,
    /// The observers running beside it (`--observers`).
    pub observers: Observers,
    /// Robots per agent process (`--agents-per-process`, `[run] agents_per_process`).
    pub per_process: usize,
}

/// Starts the coordinator (or its replicas) for `agents` agents, hands the session and the
/// agents' ports to `f`, then stops every coordinator and removes the run's shared memory.
/// The run's files (scenario, consensus logs, coordinator logs) live in a temporary
/// directory that is removed afterwards, or kept and named when something failed.
pub fn with_coordinator<T>(
    program: &Path,
    agents: usize,
    setup: CoordinatorSetup,
    f: impl FnOnce(&Session, &mut Swarm) -> Result<T>,
) -> Result<T> {
    let layout = Layout::new(agents).map_err(|e| anyhow!(e))?;
    let run = RunId::unique("round");
    let dir = std::env::temp_dir().join(format!("hnav-bench-{}", run.as_str()));
    std::fs::create_dir_all(&dir).with_context(|| format!("create {}", dir.display()))?;
    let result = session(program, &run, &dir, layout, setup, f);
    // Every node of the run is gone now (ours dropped, the coordinator reaped or killed).
    let purged = purge_run(&run);
    match &result {
        Ok(_) => {
            let _ = std::fs::remove_dir_all(&dir);
        }
        Err(_) => hnav_runtime::errln!("kept the run's files in {}", dir.display()),
    }
    let out = result?;
    purged.context("remove the run's shared memory")?;
    Ok(out)
}

fn session<T>(
    program: &Path,
    run: &RunId,
    dir: &Path,
    layout: Layout,
    setup: CoordinatorSetup,
    f: impl FnOnce(&Session, &mut Swarm) -> Result<T>,
) -> Result<T> {
    let scenario = dir.join("scenario.toml");
    std::fs::write(&scenario, layout.scenario_toml(setup.fsync, setup.replicas))
        .with_context(|| format!("write {}", scenario.display()))?;
    let n = layout.agents();
    let transport = Transport::builder(run).node_name("supervisor").create()?;
    let life = SupervisorPorts::open(&transport, n)?;
    // The commit bell, as `hnav run` hands it out (and, like it, not with HNAV_NO_BELL=1).
    let bell = match std::env::var_os(NO_BELL_ENV) {
        Some(v) if v == "1" => None,
        _ => Some(Bell::create()?),
    };
    let env: Vec<(OsString, OsString)> = bell
        .as_ref()
        .map(|b| (OsString::from(BELL_ENV), OsString::from(b.env_value())))
        .into_iter()
        .collect();
    // Every agent port exists before the coordinator starts, as after a real start-up.
    let mut swarm = Swarm::open(run, layout, setup.per_process, bell)?;
    let args = ProcessArgs {
        dir: Some(dir.to_path_buf()),
        ..ProcessArgs::new(run.as_str(), scenario)
    };
    // As the supervisor numbers them: index 0 for one coordinator, Raft ids 1..=n for
    // replicas (each told its id with `--replica`).
    let indices: Vec<u32> = match setup.replicas {
        1 => vec![0],
        n => (1..=n).collect(),
    };
    let spawned = Instant::now();
    let mut children = Vec::with_capacity(indices.len());
    let mut spawn_failed = None;
    for index in indices {
        let mut args = args.to_args();
        if index > 0 {
            args.extend([
                OsString::from("--replica"),
                OsString::from(index.to_string()),
            ]);
        }
        let spec = ChildSpec {
            role: Role::Coordinator,
            index,
            program: program.to_path_buf(),
            args,
            log_file: dir.join(format!("{}.log", Role::Coordinator.node_name(index))),
            env: env.clone(),
        };
        match Child::spawn(&spec) {
            Ok(child) => children.push(child),
            Err(e) => {
                spawn_failed = Some(anyhow!(e).context("start hnav-coordinator"));
                break;
            }
        }
    }
    let session = Session {
        children,
        spawned,
        startup: std::cell::Cell::new(None),
        life,
        transport,
    };
    let bin_dir = program.parent().unwrap_or(Path::new("."));
    let out = match spawn_failed {
        Some(e) => Err(e),
        None => session.handshake().and_then(|()| {
            // Started once the coordinator's ports exist; stopped before it is.
            let observers = Running::start(setup.observers, run, &args, dir, bin_dir)?;
            let out = f(&session, &mut swarm);
            observers.stop();
            out
        }),
    };
    let stopped = session.stop();
    drop(swarm);
    match (out, stopped) {
        (Ok(v), Ok(())) => Ok(v),
        (Ok(_), Err(e)) => Err(anyhow!("{e:#}\n{}", session.log_tails())),
        (Err(e), Err(s)) => Err(anyhow!("{e:#}; then {s:#}\n{}", session.log_tails())),
        (Err(e), Ok(())) => Err(e),
    }
}

/// The last lines of the coordinator's log, for an error message.
fn log_tail(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let lines: Vec<&str> = text.lines().collect();
    let tail = &lines[lines.len().saturating_sub(LOG_TAIL_LINES)..];
    if tail.is_empty() {
        format!("{} is empty", path.display())
    } else {
        format!("end of {}:\n{}", path.display(), tail.join("\n"))
    }
}
