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
//! Before step 1 a process may report a slow phase of its start-up on `ready`
//! ([`LifecyclePorts::report_phase`], e.g. an agent building its neural map), so that a
//! supervisor that gives up can say what each late process was doing. The supervisor's
//! bound, and each process's bound on its wait for `Start`, is the scenario's one start-up
//! timeout ([`Scenario::startup_timeout`]); a process starts its clock after the
//! supervisor, so it never gives up first.
//!
//! A process the supervisor restarts (`--resume`) skips step 3: its peers are already
//! running, and a new publisher connects to existing subscribers on its first send. During
//! the run the supervisor publishes `Down` and `Restarted` for processes that die and come
//! back, and `Stop` (with a [`StopReason`]) to end the run politely. The supervisor's half of
//! steps 1 and 2 is `supervisor::startup`.

use std::ffi::OsString;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use crate::msg::{Lifecycle, LifecycleEvent, Role, StartupPhase, StopReason};
use crate::scenario::params::{CoordinatorParams, SimKind};
use crate::scenario::{fault_arg, ClockMode, FaultSpec, FaultTarget, Loc, Scenario, ScenarioError};
use crate::topics;
use crate::transport::{Receiver, RunId, Sender, Transport, TransportError, Wake};

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
    pub mode: Option<ClockMode>,
    /// Coordinator replicas agreeing by Raft: 1, 3 or 5 [default: the scenario's
    /// coordinator.replicas].
    #[arg(long, value_name = "N")]
    pub replicas: Option<u32>,
    /// The run's output directory (the coordinator keeps its consensus log in DIR/log).
    #[arg(long, value_name = "DIR")]
    pub dir: Option<PathBuf>,
    /// Restarted by the supervisor: the run is under way, skip the start handshake.
    #[arg(long)]
    pub resume: bool,
    /// Faults of `hnav run --kill/--term/--freeze`, appended to the scenario's `[[faults]]`
    /// (`kill=agent:3@round:40`; see `scenario::fault_arg`).
    #[arg(long = "fault", value_name = "FLAG=FAULT", hide = true,
          value_parser = crate::scenario::fault_arg::parse_process_arg)]
    pub faults: Vec<FaultSpec>,
}

impl ProcessArgs {
    /// The arguments of run `run` of `scenario` with no override: the scenario as written.
    pub fn new(run: impl Into<String>, scenario: impl Into<PathBuf>) -> Self {
        ProcessArgs {
            run: run.into(),
            scenario: scenario.into(),
            agents: None,
            seed: None,
            mode: None,
            replicas: None,
            dir: None,
            resume: false,
            faults: Vec::new(),
        }
    }

    /// The scenario with the overrides applied: `--seed` replaces `sim.seed`, `--agents`
    /// takes the first N agents or adds seeded random ones, `--mode` replaces `sim.clock`,
    /// `--replicas` replaces `coordinator.replicas`, and the command line's faults follow the
    /// scenario's.
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
        if let Some(m) = self.mode {
            if m == ClockMode::Lockstep && s.sim.kind == SimKind::Ros2 {
                return Err(ScenarioError::InvalidParameter {
                    at: Loc::new("the command line", 0),
                    key: "--mode".into(),
                    problem: "lockstep: the scenario's [sim] kind = \"ros2\" runs in realtime only"
                        .into(),
                });
            }
            s.sim.clock = m;
        }
        if let Some(r) = self.replicas {
            if !CoordinatorParams::REPLICAS.contains(&r) {
                return Err(ScenarioError::InvalidParameter {
                    at: Loc::new("the command line", 0),
                    key: "--replicas".into(),
                    problem: format!("{r} replicas; a cluster has 1 (no replication), 3 or 5"),
                });
            }
            s.coordinator.replicas = r;
        }
        for f in &self.faults {
            if let FaultTarget::Agent(a) = f.target {
                if a >= s.agents.len() {
                    return Err(ScenarioError::FaultAgentOutOfRange {
                        at: Loc::new("the command line", 0),
                        fault: s.faults.len(),
                        index: i64::try_from(a).unwrap_or(i64::MAX),
                        agents: s.agents.len(),
                    });
                }
            }
            s.faults.push(*f);
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
        if let Some(r) = self.replicas {
            a.extend(["--replicas".into(), r.to_string().into()]);
        }
        if let Some(d) = &self.dir {
            a.extend(["--dir".into(), d.clone().into()]);
        }
        if self.resume {
            a.push("--resume".into());
        }
        for f in &self.faults {
            a.extend(["--fault".into(), fault_arg::to_process_arg(f).into()]);
        }
        a
    }
}

/// The exit code of a process that stopped because the disk of the run directory is full
/// (ENOSPC's errno). The supervisor does not restart such a process: its successor would meet
/// the same full disk. It ends the run instead and names the cause.
pub const EXIT_NO_SPACE: u8 = 28;

/// The `main` of a process binary: sets up logging, parses the command line and runs `run`;
/// an error is printed as `NAME: error` and exits 1, or [`EXIT_NO_SPACE`] when the error is
/// a full disk (or the disk was too full to print it).
pub fn process_main<A: clap::Parser>(
    name: &str,
    run: impl FnOnce(&A) -> Result<(), Box<dyn std::error::Error>>,
) -> std::process::ExitCode {
    crate::logging::init();
    let args = A::parse();
    match run(&args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            crate::errln!("{name}: {e}");
            if crate::diag::is_no_space(e.as_ref()) || crate::diag::no_space_seen() {
                std::process::ExitCode::from(EXIT_NO_SPACE)
            } else {
                std::process::ExitCode::FAILURE
            }
        }
    }
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

    /// Tells the supervisor that this process has entered start-up `phase` of `size` (see
    /// [`StartupPhase`]). Only before `Up`, and only for phases that can take long: every
    /// report takes a slot of the `ready` buffer the `Up`s share.
    pub fn report_phase(&self, phase: StartupPhase, size: u32) -> Result<(), TransportError> {
        self.ready
            .send(Lifecycle::phase(self.role, self.index, phase, size))?;
        Ok(())
    }

    /// Publishes `Up` for this process (call once every other port is open).
    pub fn announce(&self) -> Result<(), TransportError> {
        self.ready.send(Lifecycle::up(self.role, self.index))?;
        Ok(())
    }

    /// The receiver of the supervisor's events, to attach to a `Waiter`.
    pub fn events(&self) -> &Receiver<Lifecycle> {
        &self.events
    }

    /// Tells the supervisor that the sim holds before stepping `period` (`Hold` on `ready`).
    pub fn hold(&self, period: u64) -> Result<(), TransportError> {
        self.ready.send(Lifecycle::hold(period))?;
        Ok(())
    }

    /// Hands every pending supervisor event with a known role and event (and, for `Stop`, a
    /// known reason) to `f`; returns the reason of the last `Stop` among them, if any.
    pub fn drain(
        &self,
        mut f: impl FnMut(Role, u32, LifecycleEvent),
    ) -> Result<Option<StopReason>, TransportError> {
        self.drain_samples(|role, ev, l| f(role, l.index, ev))
    }

    /// [`LifecyclePorts::drain`], handing `f` the whole sample too (a `Resume`'s period).
    pub fn drain_samples(
        &self,
        mut f: impl FnMut(Role, LifecycleEvent, &Lifecycle),
    ) -> Result<Option<StopReason>, TransportError> {
        let mut stop = None;
        self.events.drain_pending(|l| {
            let (Some(role), Some(ev)) = (Role::from_u8(l.role), LifecycleEvent::from_u8(l.event))
            else {
                return;
            };
            if ev == LifecycleEvent::Stop {
                match StopReason::from_u8(l.reason) {
                    Some(reason) => stop = Some(reason),
                    None => return,
                }
            }
            f(role, ev, l);
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
        // The supervisor's events are the only source here: no `WaitSet` needed.
        let waiter = transport.single_waiter(&self.events);
        let deadline = Instant::now() + timeout;
        loop {
            let mut started = false;
            let stop = self.drain(|_, _, ev| started |= ev == LifecycleEvent::Start)?;
            if stop.is_some() {
                return Ok(StartOutcome::Stopped);
            }
            if started {
                return Ok(StartOutcome::Started);
            }
            match waiter.wait(Some(deadline))? {
                Wake::Data => {}
                Wake::Stop => return Ok(StartOutcome::Stopped),
                Wake::TimedOut => {
                    return Err(TransportError::ipc(
                        "wait for start",
                        "lifecycle",
                        format!(
                            "no Start from the supervisor within {:.1} s",
                            timeout.as_secs_f64()
                        ),
                    ))
                }
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
            mode: Some(ClockMode::Realtime),
            replicas: None,
            dir: Some("out".into()),
            resume: true,
            faults: vec![
                FaultSpec {
                    at: crate::scenario::FaultTime::Seconds(2.5),
                    action: crate::scenario::FaultAction::Kill(crate::scenario::FaultSignal::Term),
                    target: FaultTarget::Coordinator,
                },
                FaultSpec {
                    at: crate::scenario::FaultTime::Round(60),
                    action: crate::scenario::FaultAction::Freeze { for_s: Some(0.3) },
                    target: FaultTarget::Agent(5),
                },
            ],
        };
        let mut argv: Vec<OsString> = vec!["x".into()];
        argv.extend(a.to_args());
        assert_eq!(Cli::parse_from(argv).args, a);
    }

    #[test]
    fn drain_reports_the_stop_reason_and_drops_what_it_cannot_decode() {
        let run = RunId::unique("drain");
        {
            let transport = Transport::builder(&run).create().unwrap();
            let ports = LifecyclePorts::open(&transport, Role::Agent, 0, 1).unwrap();
            let life = transport
                .sender(topics::LIFECYCLE, topics::lifecycle_qos(1))
                .unwrap();
            let mut seen = Vec::new();
            life.send(Lifecycle::down(Role::Agent, 0, 0)).unwrap();
            assert_eq!(ports.drain(|r, i, e| seen.push((r, i, e))).unwrap(), None);
            life.send(Lifecycle::stop(StopReason::TimeLimit)).unwrap();
            let stop = ports.drain(|r, i, e| seen.push((r, i, e))).unwrap();
            assert_eq!(stop, Some(StopReason::TimeLimit));
            let unknown_reason = Lifecycle {
                reason: 0,
                ..Lifecycle::stop(StopReason::Requested)
            };
            let unknown_role = Lifecycle {
                role: 0,
                ..Lifecycle::start()
            };
            life.send(unknown_reason).unwrap();
            life.send(unknown_role).unwrap();
            assert_eq!(ports.drain(|r, i, e| seen.push((r, i, e))).unwrap(), None);
            assert_eq!(
                seen,
                [
                    (Role::Agent, 0, LifecycleEvent::Down),
                    (Role::Sim, 0, LifecycleEvent::Stop)
                ]
            );
        }
        crate::transport::purge_run(&run).unwrap();
    }

    #[test]
    fn bad_mode_is_refused() {
        let argv = ["x", "--run", "r", "--scenario", "s.toml", "--mode"];
        let err = Cli::try_parse_from(argv.iter().chain(&["fast"]))
            .err()
            .unwrap();
        assert!(
            err.to_string()
                .contains("unknown mode \"fast\": expected lockstep or realtime"),
            "{err}"
        );
        let ok = Cli::try_parse_from(argv.iter().chain(&["lockstep"])).unwrap();
        assert_eq!(ok.args.mode, Some(ClockMode::Lockstep));
    }
}
