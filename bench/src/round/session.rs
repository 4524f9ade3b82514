//! A real `hnav-coordinator` under a stand-in supervisor: scenario file, spawn, start-up
//! handshake (`Up` on `ready`, `Start` on `lifecycle`), lifecycle events, polite stop, and
//! removal of the run's shared memory.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context, Result};

use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::msg::{Lifecycle, Role, StopReason};
use hnav_runtime::scenario::FsyncPolicy;
use hnav_runtime::supervisor::child::{Child, ChildSpec, ExitInfo, Signal};
use hnav_runtime::supervisor::run::NO_BELL_ENV;
use hnav_runtime::supervisor::startup::{Startup, SupervisorPorts};
use hnav_runtime::transport::{purge_run, Bell, RunId, Transport, BELL_ENV};

use super::layout::Layout;
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

/// A running coordinator and the supervisor's ports of its run.
pub struct Session {
    child: Child,
    spawned: Instant,
    startup: std::cell::Cell<Option<Duration>>,
    log_file: PathBuf,
    life: SupervisorPorts,
    transport: Transport,
}

impl Session {
    /// The coordinator process (its exit descriptor wakes a `Waiter` when it dies).
    pub fn child(&self) -> &Child {
        &self.child
    }

    /// How long the coordinator took from just before `spawn` to its `Up` on `ready`
    /// (exec, scenario, ports, consensus log).
    pub fn startup(&self) -> Option<Duration> {
        self.startup.get()
    }

    /// The supervisor's lifecycle ports: events published there reach the coordinator as
    /// they would from `hnav run`.
    pub fn lifecycle(&self) -> &SupervisorPorts {
        &self.life
    }

    /// The supervisor's start-up handshake with the coordinator, as `hnav run` does it.
    fn handshake(&self) -> Result<()> {
        match self
            .life
            .start(&self.transport, &[&self.child], STARTUP_TIMEOUT)?
        {
            Startup::Started { all_up } => {
                self.startup.set(Some(all_up - self.spawned));
                Ok(())
            }
            Startup::Interrupted => bail!("interrupted"),
        }
    }

    /// `Stop` on `lifecycle`, then waits for the exit (bounded; SIGKILL after the bound).
    fn stop(&self) -> Result<()> {
        self.life
            .publish(Lifecycle::stop(StopReason::Requested))
            .context("publish Stop on lifecycle")?;
        match self.child.wait(Some(STOP_TIMEOUT)) {
            Some(ExitInfo::Exited(0)) => Ok(()),
            Some(exit) => bail!("hnav-coordinator ended with {exit}"),
            None => {
                self.child.signal_group(Signal::SIGKILL)?;
                let exit = self.child.wait(Some(STOP_TIMEOUT));
                bail!(
                    "hnav-coordinator did not exit within {STOP_TIMEOUT:?} of Stop; killed ({})",
                    exit.map_or("not reaped".to_string(), |e| e.to_string())
                )
            }
        }
    }
}

/// Starts a coordinator for `agents` agents and the given fsync policy, hands it and the
/// agents' ports to `f`, then stops it and removes the run's shared memory. The run's files
/// (scenario, consensus log, coordinator log) live in a temporary directory that is removed
/// afterwards, or kept and named when something failed.
pub fn with_coordinator<T>(
    program: &Path,
    agents: usize,
    fsync: FsyncPolicy,
    f: impl FnOnce(&Session, &mut Swarm) -> Result<T>,
) -> Result<T> {
    let layout = Layout::new(agents).map_err(|e| anyhow!(e))?;
    let run = RunId::unique("round");
    let dir = std::env::temp_dir().join(format!("hnav-bench-{}", run.as_str()));
    std::fs::create_dir_all(&dir).with_context(|| format!("create {}", dir.display()))?;
    let result = session(program, &run, &dir, layout, fsync, f);
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
    fsync: FsyncPolicy,
    f: impl FnOnce(&Session, &mut Swarm) -> Result<T>,
) -> Result<T> {
    let scenario = dir.join("scenario.toml");
    std::fs::write(&scenario, layout.scenario_toml(fsync))
        .with_context(|| format!("write {}", scenario.display()))?;
    let n = layout.agents();
    let transport = Transport::builder(run).node_name("supervisor").create()?;
    let life = SupervisorPorts::open(&transport, n)?;
    // The commit bell, as `hnav run` hands it out (and, like it, not with HNAV_NO_BELL=1).
    let bell = match std::env::var_os(NO_BELL_ENV) {
        Some(v) if v == "1" => None,
        _ => Some(Bell::create()?),
    };
    let env = bell
        .as_ref()
        .map(|b| (OsString::from(BELL_ENV), OsString::from(b.env_value())))
        .into_iter()
        .collect();
    // Every agent port exists before the coordinator starts, as after a real start-up.
    let mut swarm = Swarm::open(run, layout, bell)?;
    let args = ProcessArgs {
        run: run.as_str().to_string(),
        scenario,
        agents: None,
        seed: None,
        mode: None,
        replicas: None,
        dir: Some(dir.to_path_buf()),
        resume: false,
        faults: Vec::new(),
    };
    let log_file = dir.join("coordinator.log");
    let spec = ChildSpec {
        role: Role::Coordinator,
        index: 0,
        program: program.to_path_buf(),
        args: args.to_args(),
        log_file: log_file.clone(),
        env,
    };
    let spawned = Instant::now();
    let child = Child::spawn(&spec).context("start hnav-coordinator")?;
    let session = Session {
        child,
        spawned,
        startup: std::cell::Cell::new(None),
        log_file,
        life,
        transport,
    };
    let out = session.handshake().and_then(|()| f(&session, &mut swarm));
    let stopped = session.stop();
    drop(swarm);
    match (out, stopped) {
        (Ok(v), Ok(())) => Ok(v),
        (Ok(_), Err(e)) => Err(anyhow!("{e:#}\n{}", log_tail(&session.log_file))),
        (Err(e), Err(s)) => Err(anyhow!(
            "{e:#}; then {s:#}\n{}",
            log_tail(&session.log_file)
        )),
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
