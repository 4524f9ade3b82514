//! The `hnav-sim` process: wheel commands in, odometry and ground truth out, over the run's
//! transport, in lockstep or realtime per the scenario's `sim.clock`.
//!
//! A control period is one odometry period (`1 / sim.odometry_hz`). In lockstep a period is
//! stepped only when every live robot's command for it is in; a robot whose publisher died or
//! left, or (if `sim.lockstep_deadline_ms` > 0) that misses that deadline, counts as down and
//! brakes until it sends again. Joined to the run's lifecycle protocol
//! ([`SimProcess::with_lifecycle`]), it also learns of dead agents from the supervisor at
//! once. A robot whose agent the supervisor restarted gets its last odometry reading again
//! (it was published before the new agent subscribed) and is waited for from then on;
//! without the lifecycle protocol a robot counts as live again from its first fresh command,
//! never from a publisher merely appearing, which would stall the run.
//! With a fault plan, a lockstep sim holds before stepping the period of each fault's round
//! (every live robot's command for it in), says so with `Hold`, and steps on at the
//! supervisor's `Resume`, once the fault is done: a fault then fires at its round exactly and
//! the run stays a function of its scenario (see [`hnav_runtime::msg::LifecycleEvent`]).
//! In realtime the world follows the wall clock and commands apply when they arrive. The
//! process blocks in a [`Waiter`] throughout (on the wheel topics and the supervisor's
//! events), until the next period is due in realtime or, if set, until the lockstep deadline.
//!
//! | module | what |
//! |---|---|
//! | `ports` | the topics: wheel commands in; odometry, Truth and lifecycle out |
//! | `state` | the world, who is live and who has sent, and the handlers of each input |

mod checkpoint;
mod ports;
mod state;

use std::path::Path;
use std::time::{Duration, Instant};

use hnav_runtime::health::Heartbeat;
use hnav_runtime::launch::{LifecyclePorts, StartOutcome};
use hnav_runtime::msg::Role;
use hnav_runtime::scenario::params::ClockMode;
use hnav_runtime::scenario::Scenario;
use hnav_runtime::transport::{Transport, TransportError, Waiter, Wake};

use crate::error::SimError;
use crate::world::World;
pub use checkpoint::{CheckpointError, Restored, SimCheckpoint};
use ports::Ports;
use state::State;

/// What stopped the `hnav-sim` process: its world refused a parameter or an input, its
/// transport failed, or its checkpoint could not be written or used.
#[derive(Debug, thiserror::Error)]
pub enum SimProcessError {
    /// The world refused a parameter or an input.
    #[error(transparent)]
    Model(#[from] SimError),
    /// The run's transport failed: a port could not be opened, a send, receive or wait failed,
    /// or the supervisor never answered the start-up handshake.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// The restart checkpoint `DIR/sim.ckpt.{0,1}` could not be written, or a restarted sim could
    /// not use the one it found.
    #[error("sim checkpoint {0}")]
    Checkpoint(#[from] CheckpointError),
}

/// How a run of the process ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SimOutcome {
    /// Control periods completed.
    pub periods: u64,
    /// Collisions recorded.
    pub collisions: usize,
    /// Whether a stop request (the supervisor's `Stop` or a termination signal) ended the run
    /// (else the period limit did).
    pub signalled: bool,
}

/// The simulator's state and ports.
pub struct SimProcess<'t> {
    transport: &'t Transport,
    ports: Ports,
    state: State,
    heart: Heartbeat,
    /// Skip the wait for the supervisor's `Start` (a restarted process).
    resume: bool,
    /// The lockstep rounds of the run's planned faults (the scenario's and the command line's).
    fault_rounds: Vec<u64>,
    /// How long the handshake waits for `Start`: the scenario's start-up timeout.
    startup_timeout: Duration,
}

impl<'t> SimProcess<'t> {
    /// Builds the world from `scenario` (robots at their start cells' centres, facing their
    /// `start_heading_deg`) and opens the ports.
    pub fn new(transport: &'t Transport, scenario: &Scenario) -> Result<Self, SimProcessError> {
        let world = World::from_scenario(scenario)?;
        let ports = Ports::open(
            transport,
            scenario.run.agent_processes(world.robots()).collect(),
            scenario.sensing.is_some(),
            scenario.movers().count(),
        )?;
        let heart = Heartbeat::open(
            transport,
            Role::Sim,
            0,
            world.robots(),
            scenario.heartbeat(),
        )?;
        let lockstep_deadline = (scenario.sim.lockstep_deadline_ms > 0)
            .then(|| Duration::from_millis(scenario.sim.lockstep_deadline_ms.into()));
        Ok(SimProcess {
            transport,
            ports,
            state: State::new(world, scenario.sim.clock, lockstep_deadline)
                .with_views(scenario.sensing.map(|s| s.range)),
            heart,
            resume: false,
            fault_rounds: scenario
                .faults
                .iter()
                .map(|f| f.lockstep_round(&scenario.sim))
                .collect(),
            startup_timeout: scenario.startup_timeout(),
        })
    }

    /// Joins the run's lifecycle protocol: [`SimProcess::run`] then starts with the handshake,
    /// and the process hears the supervisor's `Stop` and learns of agents that died (their
    /// robots brake and are not waited for) or were restarted. In lockstep it also holds
    /// before stepping past the round of each planned fault until the supervisor's `Resume`.
    pub fn with_lifecycle(mut self, ports: LifecyclePorts) -> Self {
        self.ports.life = Some(ports);
        if self.state.clock == ClockMode::Lockstep {
            self.state.hold_at(self.fault_rounds.iter().copied());
        }
        self
    }

    /// Checkpoints every stepped period to `run_dir/sim.ckpt.{0,1}` (see [`SimCheckpoint`]); a
    /// restarted sim ([`SimProcess::resuming`]) resumes from it.
    pub fn with_checkpoint(mut self, run_dir: &Path, scenario: &Scenario) -> Self {
        self.state.checkpoint = Some(SimCheckpoint::in_dir(run_dir, scenario.scenario_hash()));
        self
    }

    /// Whether the process was restarted (`--resume`): its handshake then only announces it,
    /// without waiting for a `Start` the supervisor sent long ago.
    pub fn resuming(mut self, resume: bool) -> Self {
        self.resume = resume;
        self
    }

    /// The lifecycle ports, if joined.
    pub fn lifecycle(&self) -> Option<&LifecyclePorts> {
        self.ports.life.as_ref()
    }

    /// The world.
    pub fn world(&self) -> &World {
        &self.state.world
    }

    /// Joined to the lifecycle protocol, announces itself and waits for the start (unless
    /// resuming, the scenario's start-up timeout at most); then runs until a stop request or, if given,
    /// `max_periods` control periods.
    pub fn run(&mut self, max_periods: Option<u64>) -> Result<SimOutcome, SimProcessError> {
        if let Some(life) = &self.ports.life {
            let started = life.handshake(self.transport, self.resume, self.startup_timeout)?;
            if started == StartOutcome::Stopped {
                return Ok(self.state.outcome(true));
            }
        }
        if self.resume {
            if let Some(period) = self.state.resume(&self.ports)? {
                tracing::info!(period, "resumed from the checkpoint");
            }
        }
        let waiter = self.transport.waiter()?;
        let _attached = self.ports.attach(&waiter)?;
        let signalled = run_loop(
            &self.ports,
            &mut self.state,
            &waiter,
            &self.heart,
            max_periods,
        )?;
        Ok(self.state.outcome(signalled))
    }
}

/// The loop of [`SimProcess::run`]: drain, step every period that can be stepped, wait.
/// Returns whether a stop request ended it.
fn run_loop(
    ports: &Ports,
    st: &mut State,
    waiter: &Waiter,
    heart: &Heartbeat,
    max_periods: Option<u64>,
) -> Result<bool, SimProcessError> {
    let period_wall = st.period_wall();
    // Realtime periods are due from the loop's start on, counted from the period it starts
    // at (a resumed sim's is not 0).
    let (started, first) = (Instant::now(), st.period);
    // Lockstep: when the robots still missing are given up on. Runs from the last time
    // anything came in, as long as nothing does.
    let mut give_up: Option<Instant> = None;
    loop {
        // Every pass beats if due, not only a wait: a realtime sim catching up on overdue
        // periods steps them back to back without waiting, and is not hung.
        heart.beat()?;
        if max_periods.is_some_and(|m| st.period >= m) {
            return Ok(false);
        }
        let news = st.on_lifecycle(ports)?;
        if news.stop {
            return Ok(true);
        }
        if st.drain(ports)? || news.any {
            give_up = None;
        }
        let deadline = match st.clock {
            ClockMode::Lockstep => {
                if st.ready() {
                    if !st.holding(ports)? {
                        st.advance(ports)?;
                        give_up = None;
                        continue;
                    }
                    // Held for a fault: nothing is missing, the supervisor's `Resume` (or a
                    // restarted robot's first command) is what comes next.
                    None
                } else {
                    st.lockstep_deadline
                        .map(|d| *give_up.get_or_insert_with(|| Instant::now() + d))
                }
            }
            ClockMode::Realtime => {
                // From the start, not from the last step: the schedule does not drift.
                let due = started + period_wall.mul_f64((st.period + 1 - first) as f64);
                if Instant::now() >= due {
                    st.advance(ports)?;
                    continue;
                }
                Some(due)
            }
        };
        // The wait also ends at the next heartbeat, so a time-out is the lockstep deadline's
        // only once that has passed.
        match waiter.wait(heart.until(deadline)?)? {
            Wake::Data => {}
            Wake::Stop => return Ok(true),
            Wake::TimedOut => {
                if st.clock == ClockMode::Lockstep && give_up.is_some_and(|g| Instant::now() >= g) {
                    st.mark_missing_down();
                    give_up = None;
                }
            }
        }
    }
}
