//! The `hnav-agent` process: one robot's agent (or several, `[run] agents_per_process`),
//! wired to the run's services.
//!
//! A process that hosts several robots has one node, one waiter, one commit subscriber, one
//! candidate publisher, one heartbeat and one side of the lifecycle protocol, all under its
//! first robot's name, and one odometry, view and wheel topic that carry its robots in one
//! sample each; each robot keeps its own neural-map and estimate topics, state and
//! checkpoint, and its log lines carry an `agent{index=…}` span. A commit is received once
//! and applied by each robot, and a period's odometry arrives once for every robot, so the
//! coordinator and the sim wake one listener per process, not one per robot.
//!
//! Inputs: its robots' odometry (`odom/<first>`), the coordinator's commits, the
//! supervisor's lifecycle events. Outputs: candidates, wheel commands (`wheels/<first>`) and
//! neural-map snapshots (`map/<i>`, written in place into loaned shared memory). It blocks in one
//! [`Waiter`](hnav_runtime::transport::Waiter) on the three inputs; its one timer is its
//! heartbeat ([`hnav_runtime::health`]), beaten from that loop.
//!
//! Every control period (one odometry reading) the agent updates its dead reckoning, notices
//! arrival at `next`, and, unless a candidate of its own is still unanswered, publishes the
//! candidate for round `last commit + 1`. In **lockstep** it sends the wheel command for the
//! following period only once that round's commit is in, so the sim cannot step before the
//! swarm has decided: round r and period r are the same instant and the run is
//! deterministic. In **realtime** it answers every odometry reading with a wheel command at
//! once and applies commits whenever they arrive, as a robot would.
//!
//! A new coordinator (its notifier appearing on the commit topic after a restart) gets the
//! unanswered candidate again: the dead one may have taken it to its grave.
//!
//! | module | what |
//! |---|---|
//! | `ports` | the topics the process shares, and each robot's own |
//! | `state` | the agent's state and its handler for each input |
//! | `sightings` | what the robot saw change, for the coordinator's map (`[sensing]`) |
//! | `oracle` | the all-knowing baseline: the scenario's closes and opens told when they happen |
//! | [`checkpoint`] | the restart checkpoint in the run directory |

pub mod checkpoint;
mod oracle;
mod ports;
mod sightings;
mod state;

use std::path::Path;
use std::time::{Duration, Instant};

use hnav_runtime::health::Heartbeat;
use hnav_runtime::launch::{ProcessArgs, StartOutcome};
use hnav_runtime::msg::{CommitView, Role, StartupPhase};
use hnav_runtime::scenario::Scenario;
use hnav_runtime::transport::{Transport, TransportError, Wake};

use crate::navigator::Navigator;
use crate::neural_map::NeuralMap;
use checkpoint::CheckpointFile;
use ports::{Ports, RobotPorts};
use state::{Core, Inbox};

/// What stopped or broke the agent.
#[derive(Debug, thiserror::Error)]
pub enum AgentError {
    /// The scenario could not be loaded.
    #[error(transparent)]
    Scenario(#[from] hnav_runtime::scenario::ScenarioError),
    /// The agent index is not in the scenario.
    #[error("agent {index} is not in the scenario ({agents} agents)")]
    NoSuchAgent {
        /// The index asked for.
        index: u32,
        /// Agents in the scenario.
        agents: usize,
    },
    /// The transport failed (waiting included).
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// Planning failed.
    #[error(transparent)]
    Plan(#[from] crate::Error),
    /// The disk of the run directory is full: the checkpoint cannot be written.
    #[error("no space left on device writing the checkpoint {}", path.display())]
    NoSpace {
        /// The checkpoint file.
        path: std::path::PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
}

/// How the agent's run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AgentOutcome {
    /// Control periods seen.
    pub periods: u64,
    /// Last commit round applied.
    pub last_commit: u64,
    /// Whether the robot stood on its goal at the end.
    pub at_goal: bool,
}

/// One agent process: the robots `first .. first + count` of the run (one, unless
/// `[run] agents_per_process` says more).
pub struct AgentProcess<'t> {
    transport: &'t Transport,
    ports: Ports,
    robots: Robots,
    heart: Heartbeat,
    startup_timeout: Duration,
}

/// The robots of the process, by position: their state apart from their ports, so that the
/// loop can keep the ports attached to its waiter while it changes the state.
struct Robots {
    cores: Vec<Core>,
    ports: Vec<RobotPorts>,
    /// What the process's shared topics brought each robot in this pass.
    inbox: Vec<Inbox>,
    /// Names each robot in the log lines of a process that hosts several (none for one).
    spans: Vec<tracing::Span>,
}

impl<'t> AgentProcess<'t> {
    /// Loads agent `index` of the run described by `args` and opens its ports: a process of
    /// one robot. See [`AgentProcess::hosting`].
    pub fn new(
        transport: &'t Transport,
        args: &ProcessArgs,
        scenario: &Scenario,
        index: u32,
    ) -> Result<Self, AgentError> {
        Self::hosting(transport, args, scenario, (index, 1))
    }

    /// Loads the `count` agents from `first` on of the run described by `args` and opens
    /// their ports. A restarted process (`args.resume`) resumes each robot from its
    /// checkpoint in the run directory if it has a valid one.
    pub fn hosting(
        transport: &'t Transport,
        args: &ProcessArgs,
        scenario: &Scenario,
        (first, count): (u32, u32),
    ) -> Result<Self, AgentError> {
        let agents = scenario.agents.len();
        let count = count.max(1);
        let last = first.saturating_add(count - 1);
        if last as usize >= agents {
            return Err(AgentError::NoSuchAgent {
                index: last,
                agents,
            });
        }
        let sensing = scenario.sensing.is_some();
        let grid = &scenario.map.grid;
        let ports = Ports::open(transport, (first, count, agents), sensing)?;
        // One heartbeat for the process, under its first robot's name: the supervisor
        // watches processes, and the robots of one process hang together.
        let heart = Heartbeat::open(transport, Role::Agent, first, agents, scenario.heartbeat())?;
        if !args.resume {
            // Only a first start has a supervisor waiting on a bound; a restarted agent
            // builds its maps just the same but nobody times it.
            let mib = (NeuralMap::footprint(grid) * count as usize).div_ceil(1 << 20);
            let size = u32::try_from(mib).unwrap_or(u32::MAX);
            ports
                .life
                .report_phase(StartupPhase::BuildingNeuralMap, size)?;
        }
        let building = Instant::now();
        let n = count as usize;
        let mut robots = Robots {
            cores: Vec::with_capacity(n),
            ports: Vec::with_capacity(n),
            inbox: vec![Inbox::default(); n],
            spans: Vec::with_capacity(n),
        };
        for index in first..=last {
            let spec = &scenario.agents[index as usize];
            let checkpoint = args.dir.as_deref().and_then(|d| open_checkpoint(d, index));
            let resumed = (checkpoint.as_ref())
                .filter(|_| args.resume)
                .and_then(|c| c.load());
            let span = match count {
                1 => tracing::Span::none(),
                _ => tracing::info_span!("agent", index),
            };
            let core = span
                .in_scope(|| Core::new(scenario, spec, index, checkpoint, resumed, args.resume))?;
            robots.cores.push(core);
            robots
                .ports
                .push(RobotPorts::open(transport, grid, (index, agents))?);
            robots.spans.push(span);
        }
        // What a user needs to pick `[run] startup_timeout_s` for a large map.
        tracing::info!(
            seconds = building.elapsed().as_secs_f64(),
            robots = n,
            "neural map built"
        );
        Ok(AgentProcess {
            startup_timeout: scenario.startup_timeout(),
            transport,
            ports,
            robots,
            heart,
        })
    }

    /// The navigator (row, map, target) of the process's first robot.
    pub fn navigator(&self) -> &Navigator {
        self.robots.cores[0].navigator()
    }

    /// Announces itself, waits for the start (unless resuming) and runs until the
    /// supervisor's `Stop` or a termination signal. Returns each robot's outcome, in order.
    pub fn run(&mut self, resume: bool) -> Result<Vec<AgentOutcome>, AgentError> {
        let started = self
            .ports
            .life
            .handshake(self.transport, resume, self.startup_timeout)?;
        let p = &self.ports;
        let robots = &mut self.robots;
        if started == StartOutcome::Stopped {
            return Ok(robots.cores.iter().map(Core::outcome).collect());
        }
        for ((core, r), span) in (robots.cores.iter_mut())
            .zip(&robots.ports)
            .zip(&robots.spans)
        {
            span.in_scope(|| core.begin(p, r, resume))?;
        }
        p.wheels.flush()?;
        let waiter = self.transport.waiter()?;
        let mut attached = Vec::with_capacity(3);
        attached.push(waiter.attach(&p.odom)?);
        attached.push(waiter.attach(&p.commit)?);
        let _bell = p.bell.as_ref().map(|b| waiter.attach_bell(b)).transpose()?;
        attached.push(waiter.attach(p.life.events())?);
        loop {
            self.heart.beat()?;
            if p.life.drain(|_, _, _| {})?.is_some() {
                break;
            }
            pass(p, robots)?;
            // The agent reacts to its inputs; its deadlines are the next beat and, in
            // realtime, the resend of an unanswered candidate. `TimedOut` means "look again".
            let resend = robots.cores.iter().filter_map(Core::resend_due).min();
            match waiter.wait(self.heart.until(resend)?)? {
                Wake::Data | Wake::TimedOut => {}
                Wake::Stop => break,
            }
        }
        Ok(robots.cores.iter().map(Core::outcome).collect())
    }
}

/// One pass over every input of the process: the new commits, the coordinator's map and the
/// robots' odometry and views, received once and handed to each robot, then each robot's
/// own work; the candidates and wheel commands the pass posted go out once.
fn pass(p: &Ports, robots: &mut Robots) -> Result<(), AgentError> {
    let Robots {
        cores,
        ports: rp,
        inbox,
        spans,
    } = robots;
    // Not `drain_pending`: applying a decision can fail, and the error must end the loop.
    let wake = p.commit.take_wakeup()?;
    while let Some(sample) = p.commit.receive()? {
        for (core, span) in cores.iter_mut().zip(spans.iter()) {
            let c = CommitView::new(sample.user_header(), sample.payload());
            span.in_scope(|| core.apply_commit(c))?;
        }
    }
    for ((core, r), span) in cores.iter_mut().zip(rp.iter()).zip(spans.iter()) {
        span.in_scope(|| core.after_commits(p, r, wake.peer_up))?;
    }
    if let Some(rx) = &p.world {
        let mut result = Ok(());
        rx.drain_pending(|h, cells| {
            for (core, span) in cores.iter_mut().zip(spans.iter()) {
                if result.is_ok() {
                    result = span.in_scope(|| core.learn_world(h, cells));
                }
            }
        })?;
        result?;
    }
    sort_into(p, cores, inbox)?;
    for (((core, r), span), inbox) in cores.iter_mut().zip(rp.iter()).zip(spans.iter()).zip(inbox) {
        span.in_scope(|| core.step(p, r, std::mem::take(inbox)))?;
        // iceoryx2 hands a publisher's history (the last snapshot) to a new subscriber
        // only when the publisher updates its connections, which a send does; the map is
        // sent only when it is rebuilt, so without this a viewer that joins late would
        // wait for the next rebuild. A counter compare unless someone joined.
        if let Err(e) = r.map.update_connections() {
            tracing::warn!("neural-map viewers not connected: {e}");
        }
    }
    p.candidates.flush()?;
    p.wheels.flush()?;
    Ok(())
}

/// Hands each robot the newest odometry reading and view the process's topics brought for
/// it; a reading for a robot the process does not host is dropped with a warning.
fn sort_into(p: &Ports, cores: &[Core], inbox: &mut [Inbox]) -> Result<(), AgentError> {
    let first = cores.first().map_or(0, Core::index);
    let slot = |agent: u32| agent.checked_sub(first).map(|k| k as usize);
    p.odom.drain_pending(|_, readings| {
        for o in readings {
            match slot(o.agent).and_then(|k| inbox.get_mut(k)) {
                Some(b) => b.odometry(o),
                None => tracing::warn!(
                    agent = first,
                    from = o.agent,
                    "odometry of another robot dropped"
                ),
            }
        }
    })?;
    if let Some(rx) = &p.view {
        rx.drain_pending(|_, views| {
            for v in views {
                if let Some(b) = slot(v.agent).and_then(|k| inbox.get_mut(k)) {
                    b.view(v);
                }
            }
        })?;
    }
    Ok(())
}

/// The checkpoint file of agent `index` in the run directory `dir`; without one the agent
/// runs on but cannot resume.
fn open_checkpoint(dir: &Path, index: u32) -> Option<CheckpointFile> {
    let path = CheckpointFile::path_in(dir, index);
    match CheckpointFile::open(&path) {
        Ok(f) => Some(f),
        Err(e) => {
            tracing::warn!(path = %path.display(), "no checkpoint file: {e}");
            None
        }
    }
}
