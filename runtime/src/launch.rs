//! What every process of a run shares at start-up: its command line ([`ProcessArgs`]) and the
//! start-up handshake with the supervisor ([`LifecyclePorts`]).
//!
//! The supervisor starts `hnav-sim`, `hnav-coordinator` and `hnav-agent` with the same
//! `--run`, `--scenario`, `--agents`, `--seed` and `--mode`, and each process derives the
//! effective scenario from them with [`ProcessArgs::scenario`]. Passing the overrides instead
//! of a rewritten scenario file keeps one source of truth: the same file and the same
//! overrides give every process the same agents, bit for bit.
//!
//! ## Start-up handshake
//!
//! iceoryx2 delivers a sample only to subscribers that exist when it is sent. So no process
//! may send before every process has opened its ports:
//!
//! 1. each process opens all its ports, then publishes `Up` on the `ready` topic;
//! 2. the supervisor, once it has seen `Up` from all of them, publishes `Start` on the
//!    `lifecycle` topic;
//! 3. each process waits for `Start`, then runs.
//!
//! A process the supervisor restarts (`--resume`) skips step 3: its peers are already
//! running, and a new publisher connects to existing subscribers on its first send. During
//! the run the supervisor publishes `Down` and `Restarted` for processes that die and come
//! back, and `Stop` to end the run politely.

use std::ffi::OsString;
use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use iceoryx2::prelude::CallbackProgression;
use iceoryx2::waitset::WaitSetRunResult;

use crate::msg::{Lifecycle, LifecycleEvent, Role};
use crate::scenario::{ClockMode, Scenario, ScenarioError};
use crate::topics;
use crate::transport::{Receiver, RunId, Sender, Transport, TransportError};

/// The command line shared by the run's processes.
#[derive(clap::Args, Debug, Clone, PartialEq)]
pub struct ProcessArgs {
    /// Run id shared by the processes of the run.
    #[arg(long)]
    pub run: String,
    /// Scenario file (TOML).
    #[arg(long)]
    pub scenario: PathBuf,
    /// Use exactly N agents (the scenario's first N, or extra seeded random ones).
    #[arg(long, value_name = "N")]
    pub agents: Option<usize>,
    /// Seed for the sim's noise and for generated agents [default: the scenario's sim.seed].
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
    /// Clock mode [default: the scenario's sim.clock].
    #[arg(long, value_name = "lockstep|realtime")]
    pub mode: Option<Mode>,
    /// The run's output directory (the coordinator keeps its consensus log in DIR/log).
    #[arg(long, value_name = "DIR")]
    pub dir: Option<PathBuf>,
    /// Restarted by the supervisor: the run is under way, skip the start handshake.
    #[arg(long)]
    pub resume: bool,
}

/// A clock mode on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mode(pub ClockMode);

impl FromStr for Mode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "lockstep" => Ok(Mode(ClockMode::Lockstep)),
            "realtime" => Ok(Mode(ClockMode::Realtime)),
            other => Err(format!(
                "unknown mode {other:?}: expected lockstep or realtime"
            )),
        }
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self.0 {
            ClockMode::Lockstep => "lockstep",
            ClockMode::Realtime => "realtime",
        })
    }
}

impl ProcessArgs {
    /// The scenario with the overrides applied: `--seed` replaces `sim.seed`, `--agents`
    /// takes the first N agents or adds seeded random ones, `--mode` replaces `sim.clock`.
    pub fn scenario(&self) -> Result<Scenario, ScenarioError> {
        let mut s = Scenario::load(&self.scenario)?;
        if let Some(seed) = self.seed {
            s.sim.seed = seed;
        }
        if let Some(n) = self.agents {
            if n != s.agents.len() {
                s = s.with_agent_count(n, s.sim.seed)?;
            }
        }
        if let Some(Mode(m)) = self.mode {
            s.sim.clock = m;
        }
        Ok(s)
    }

    /// The run id.
    pub fn run_id(&self) -> Result<RunId, TransportError> {
        RunId::new(&self.run)
    }

    /// The arguments as a command line, for the supervisor to pass on.
    pub fn to_args(&self) -> Vec<OsString> {
        let mut a: Vec<OsString> = vec![
            "--run".into(),
            self.run.clone().into(),
            "--scenario".into(),
            self.scenario.clone().into(),
        ];
        if let Some(n) = self.agents {
            a.extend(["--agents".into(), n.to_string().into()]);
        }
        if let Some(s) = self.seed {
            a.extend(["--seed".into(), s.to_string().into()]);
        }
        if let Some(m) = self.mode {
            a.extend(["--mode".into(), m.to_string().into()]);
        }
        if let Some(d) = &self.dir {
            a.extend(["--dir".into(), d.clone().into()]);
        }
        if self.resume {
            a.push("--resume".into());
        }
        a
    }
}

/// The lost-wake-up re-check of the loops that still block in a raw WaitSet; it is
/// [`Waiter::LOST_WAKEUP_RECHECK`](crate::transport::Waiter::LOST_WAKEUP_RECHECK), which
/// documents the cause. Goes once every loop waits in a [`Waiter`](crate::transport::Waiter).
pub const LOST_WAKEUP_RECHECK: Duration = crate::transport::Waiter::LOST_WAKEUP_RECHECK;

/// The `main` of a process binary: sets up logging, parses the command line and runs `run`;
/// an error is printed as `NAME: error` and exits 1.
pub fn process_main<A: clap::Parser>(
    name: &str,
    run: impl FnOnce(&A) -> Result<(), Box<dyn std::error::Error>>,
) -> std::process::ExitCode {
    crate::logging::init();
    let args = A::parse();
    match run(&args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{name}: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// The node name of a process: `sim`, `coordinator` or `agent-<i>` (what `hnav ps` matches).
pub fn node_name(role: Role, index: u32) -> String {
    match role {
        Role::Agent => format!("agent-{index}"),
        other => crate::supervisor::registry::role_name(other).to_string(),
    }
}

/// Wall-clock nanoseconds since the Unix epoch (for lifecycle events, never for decisions).
pub fn now_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0)
}

/// How waiting for the supervisor's `Start` ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StartOutcome {
    /// `Start` arrived: run.
    Started,
    /// `Stop` arrived, or a termination signal: exit without running.
    Stopped,
}

/// A process's side of the lifecycle protocol: announces itself on `ready`, hears the
/// supervisor on `lifecycle`.
pub struct LifecyclePorts {
    role: Role,
    index: u32,
    ready: Sender<Lifecycle>,
    events: Receiver<Lifecycle>,
}

impl LifecyclePorts {
    /// Opens both topics for a process of `role` (and agent `index`) in a swarm of `agents`.
    pub fn open(
        transport: &Transport,
        role: Role,
        index: u32,
        agents: usize,
    ) -> Result<Self, TransportError> {
        let q = topics::lifecycle_qos(agents);
        Ok(Self {
            role,
            index,
            ready: transport.sender(topics::READY, q)?,
            events: transport.receiver(topics::LIFECYCLE, q)?,
        })
    }

    /// Publishes `Up` for this process (call once every other port is open).
    pub fn announce(&self) -> Result<(), TransportError> {
        self.ready.send(Lifecycle {
            time_ns: now_ns(),
            pid: std::process::id(),
            index: self.index,
            role: self.role as u8,
            event: LifecycleEvent::Up as u8,
            reserved: 0,
            restarts: 0,
        })?;
        Ok(())
    }

    /// The receiver of the supervisor's events, to attach to a WaitSet.
    pub fn events(&self) -> &Receiver<Lifecycle> {
        &self.events
    }

    /// Hands every pending supervisor event with a known role and event to `f`; returns
    /// whether a `Stop` was among them.
    pub fn drain(
        &self,
        mut f: impl FnMut(Role, u32, LifecycleEvent),
    ) -> Result<bool, TransportError> {
        self.events.take_wakeup()?;
        let mut stop = false;
        self.events.drain(|l| {
            if let (Some(role), Some(ev)) =
                (Role::from_u8(l.role), LifecycleEvent::from_u8(l.event))
            {
                stop |= ev == LifecycleEvent::Stop;
                f(role, l.index, ev);
            }
        })?;
        Ok(stop)
    }

    /// Announces `Up` and, unless `resume`, blocks until the supervisor's `Start` (or `Stop`,
    /// or a termination signal). `timeout` bounds the wait: a supervisor that never answers
    /// is an error, not a hang.
    pub fn handshake(
        &self,
        transport: &Transport,
        resume: bool,
        timeout: Duration,
    ) -> Result<StartOutcome, TransportError> {
        self.announce()?;
        if resume {
            return Ok(StartOutcome::Started);
        }
        let ws = transport.waitset()?;
        let _guard = ws
            .attach_notification(self.events.listener())
            .map_err(|e| TransportError::ipc("attach listener", "lifecycle", e))?;
        let deadline = std::time::Instant::now() + timeout;
        loop {
            let mut started = false;
            let stop = self.drain(|_, _, ev| started |= ev == LifecycleEvent::Start)?;
            if stop {
                return Ok(StartOutcome::Stopped);
            }
            if started {
                return Ok(StartOutcome::Started);
            }
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            if left.is_zero() {
                return Err(TransportError::ipc(
                    "wait for start",
                    "lifecycle",
                    format!("no Start from the supervisor within {timeout:?}"),
                ));
            }
            match ws.wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, left) {
                Ok(WaitSetRunResult::TerminationRequest | WaitSetRunResult::Interrupt) => {
                    return Ok(StartOutcome::Stopped)
                }
                Ok(_) => {}
                Err(e) => return Err(TransportError::ipc("wait for start", "lifecycle", e)),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: ProcessArgs,
    }

    #[test]
    fn args_round_trip_through_the_command_line() {
        let a = ProcessArgs {
            run: "r1".into(),
            scenario: "s.toml".into(),
            agents: Some(8),
            seed: Some(3),
            mode: Some(Mode(ClockMode::Realtime)),
            dir: Some("out".into()),
            resume: true,
        };
        let mut argv: Vec<OsString> = vec!["x".into()];
        argv.extend(a.to_args());
        assert_eq!(Cli::parse_from(argv).args, a);
    }

    #[test]
    fn bad_mode_is_refused() {
        assert!("fast".parse::<Mode>().is_err());
        assert_eq!(
            "lockstep".parse::<Mode>().unwrap(),
            Mode(ClockMode::Lockstep)
        );
    }

    #[test]
    fn node_names_match_roles() {
        assert_eq!(node_name(Role::Agent, 7), "agent-7");
        assert_eq!(node_name(Role::Sim, 0), "sim");
    }
}
