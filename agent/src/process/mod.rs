//! The `hnav-agent` process: one robot's agent, wired to the run's services.
//!
//! Inputs: its robot's odometry (`odom/<i>`), the coordinator's commits, the supervisor's
//! lifecycle events. Outputs: candidates, wheel commands (`wheels/<i>`) and neural-map
//! snapshots (`map/<i>`, written in place into loaned shared memory). It blocks in one
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
//! | `ports` | the topics the agent opens |
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
use hnav_runtime::msg::{Role, StartupPhase};
use hnav_runtime::scenario::Scenario;
use hnav_runtime::transport::{Transport, TransportError, Wake};

use crate::navigator::Navigator;
use crate::neural_map::NeuralMap;
use checkpoint::CheckpointFile;
use ports::Ports;
use state::Core;

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

/// One agent process.
pub struct AgentProcess<'t> {
    transport: &'t Transport,
    ports: Ports,
    core: Core,
    heart: Heartbeat,
    startup_timeout: Duration,
}

impl<'t> AgentProcess<'t> {
    /// Loads agent `index` of the run described by `args` and opens its ports. A restarted
    /// agent (`args.resume`) resumes from its checkpoint in the run directory if there is a
    /// valid one.
    pub fn new(
        transport: &'t Transport,
        args: &ProcessArgs,
        scenario: &Scenario,
        index: u32,
    ) -> Result<Self, AgentError> {
        let agents = scenario.agents.len();
        let spec = scenario
            .agents
            .get(index as usize)
            .ok_or(AgentError::NoSuchAgent { index, agents })?;
        let sensing = scenario.sensing.is_some();
        let ports = Ports::open(transport, &scenario.map.grid, (index, agents), sensing)?;
        let heart = Heartbeat::open(transport, Role::Agent, index, agents, scenario.heartbeat())?;
        if !args.resume {
            // Only a first start has a supervisor waiting on a bound; a restarted agent
            // builds its map just the same but nobody times it.
            let mib = NeuralMap::footprint(&scenario.map.grid).div_ceil(1 << 20);
            let size = u32::try_from(mib).unwrap_or(u32::MAX);
            ports
                .life
                .report_phase(StartupPhase::BuildingNeuralMap, size)?;
        }
        let checkpoint = args.dir.as_deref().and_then(|d| open_checkpoint(d, index));
        let resumed = if args.resume {
            checkpoint.as_ref().and_then(|c| c.load())
        } else {
            None
        };
        let building = Instant::now();
        let core = Core::new(scenario, spec, index, checkpoint, resumed, args.resume)?;
        // What a user needs to pick `[run] startup_timeout_s` for a large map.
        tracing::info!(
            seconds = building.elapsed().as_secs_f64(),
            "neural map built"
        );
        Ok(AgentProcess {
            startup_timeout: scenario.startup_timeout(),
            transport,
            ports,
            core,
            heart,
        })
    }

    /// The navigator (row, map, target).
    pub fn navigator(&self) -> &Navigator {
        self.core.navigator()
    }

    /// Announces itself, waits for the start (unless resuming) and runs until the
    /// supervisor's `Stop` or a termination signal.
    pub fn run(&mut self, resume: bool) -> Result<AgentOutcome, AgentError> {
        let started = self
            .ports
            .life
            .handshake(self.transport, resume, self.startup_timeout)?;
        let (p, core) = (&self.ports, &mut self.core);
        if started == StartOutcome::Stopped {
            return Ok(core.outcome());
        }
        core.begin(p, resume)?;
        let waiter = self.transport.waiter()?;
        let _odom = waiter.attach(&p.odom)?;
        let _commit = waiter.attach(&p.commit)?;
        let _bell = p.bell.as_ref().map(|b| waiter.attach_bell(b)).transpose()?;
        let _life = waiter.attach(p.life.events())?;
        loop {
            self.heart.beat()?;
            if p.life.drain(|_, _, _| {})?.is_some() {
                break;
            }
            core.step(p)?;
            // iceoryx2 hands a publisher's history (the last snapshot) to a new subscriber
            // only when the publisher updates its connections, which a send does; the map is
            // sent only when it is rebuilt, so without this a viewer that joins late would
            // wait for the next rebuild. A counter compare unless someone joined.
            if let Err(e) = p.map.update_connections() {
                tracing::warn!("neural-map viewers not connected: {e}");
            }
            // The agent reacts to its inputs; its deadlines are the next beat and, in
            // realtime, the resend of an unanswered candidate. `TimedOut` means "look again".
            match waiter.wait(self.heart.until(core.resend_due())?)? {
                Wake::Data | Wake::TimedOut => {}
                Wake::Stop => break,
            }
        }
        Ok(core.outcome())
    }
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
