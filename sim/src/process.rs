//! The `hnav-sim` process: wheel commands in, odometry and ground truth out, over the run's
//! transport, in lockstep or realtime per the scenario's `sim.clock`.
//!
//! A control period is one odometry period (`1 / sim.odometry_hz`). In lockstep a period is
//! stepped only when every live robot's command for it is in; a robot whose publisher died or
//! left, or that misses [`LOCKSTEP_DEADLINE`], counts as down and brakes until it sends again.
//! In realtime the world follows the wall clock and commands apply when they arrive. The
//! process blocks in a WaitSet throughout (listeners on the wheel topics, plus an interval in
//! realtime or the deadline in lockstep as a timeout).

use crate::error::SimError;
use crate::world::World;
use hnav_runtime::msg::{Odometry, Truth, WheelCommand};
use hnav_runtime::scenario::params::ClockMode;
use hnav_runtime::scenario::Scenario;
use hnav_runtime::transport::{Qos, Receiver, Sender, Transport, TransportError};
use iceoryx2::prelude::CallbackProgression;
use iceoryx2::waitset::WaitSetRunResult;
use std::time::{Duration, Instant};

/// How long lockstep waits for missing commands before counting their robots as down.
/// Should move to the scenario's `[sim]` section.
pub const LOCKSTEP_DEADLINE: Duration = Duration::from_millis(500);

/// Topic of robot `i`'s wheel commands.
pub fn wheels_topic(i: usize) -> String {
    format!("wheels/{i}")
}

/// Topic of robot `i`'s odometry.
pub fn odometry_topic(i: usize) -> String {
    format!("odom/{i}")
}

/// Topic of the ground truth.
pub const TRUTH_TOPIC: &str = "truth";

/// QoS of the wheel, odometry and truth topics (superseding state, latest kept).
pub fn topic_qos() -> Qos {
    Qos::latest()
}

/// What stopped or broke the process.
#[derive(Debug, thiserror::Error)]
pub enum ProcessError {
    /// The scenario's parameters are unusable.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The transport failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// The WaitSet failed.
    #[error("waitset: {0}")]
    WaitSet(String),
}

/// How a run of the process ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Outcome {
    /// Control periods completed.
    pub periods: u64,
    /// Collisions recorded.
    pub collisions: usize,
    /// Whether a termination signal ended the run (else the period limit did).
    pub signalled: bool,
}

/// The simulator's state and ports.
pub struct SimProcess<'t> {
    transport: &'t Transport,
    world: World,
    clock: ClockMode,
    wheels: Vec<Receiver<WheelCommand>>,
    odom: Vec<Sender<Odometry>>,
    truth_tx: Sender<Truth>,
    live: Vec<bool>,
    have: Vec<bool>,
    period: u64,
}

impl<'t> SimProcess<'t> {
    /// Builds the world from `scenario` (robots at their start cells' centres, heading 0)
    /// and opens the ports.
    pub fn new(transport: &'t Transport, scenario: &Scenario) -> Result<Self, ProcessError> {
        let cs = scenario.robot.cell_size_m;
        let starts: Vec<_> = scenario
            .agents
            .iter()
            .map(|a| World::cell_centre(cs, a.start, 0.0))
            .collect();
        let world = World::new(
            &scenario.robot,
            &scenario.sim,
            scenario.map.grid.clone(),
            &starts,
        )?;
        let n = starts.len();
        let q = topic_qos();
        let wheels = (0..n)
            .map(|i| transport.receiver(&wheels_topic(i), q))
            .collect::<Result<Vec<_>, _>>()?;
        let odom = (0..n)
            .map(|i| transport.sender(&odometry_topic(i), q))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(SimProcess {
            truth_tx: transport.sender(TRUTH_TOPIC, q)?,
            transport,
            world,
            clock: scenario.sim.clock,
            wheels,
            odom,
            live: vec![true; n],
            have: vec![false; n],
            period: 0,
        })
    }

    /// The world.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// Runs until a termination signal or, if given, `max_periods` control periods.
    pub fn run(&mut self, max_periods: Option<u64>) -> Result<Outcome, ProcessError> {
        let ws = self.transport.waitset().map_err(ProcessError::Transport)?;
        let wheels = std::mem::take(&mut self.wheels);
        let mut guards = Vec::with_capacity(wheels.len());
        for rx in &wheels {
            let g = ws
                .attach_notification(rx.listener())
                .map_err(|e| ProcessError::WaitSet(format!("{e:?}")))?;
            guards.push(g);
        }
        let period_s = self.world.steps_per_odometry() as f64 * self.world.model().dt;
        let period_wall = Duration::from_secs_f64(period_s);
        let started = Instant::now();
        let mut signalled = false;
        let result = loop {
            if max_periods.is_some_and(|m| self.period >= m) {
                break Ok(());
            }
            if let Err(e) = self.drain(&wheels) {
                break Err(e);
            }
            let timeout = match self.clock {
                ClockMode::Lockstep => {
                    if self.ready() {
                        if let Err(e) = self.advance() {
                            break Err(e);
                        }
                        continue;
                    }
                    LOCKSTEP_DEADLINE
                }
                ClockMode::Realtime => {
                    let due = period_wall.mul_f64((self.period + 1) as f64);
                    let now = started.elapsed();
                    if now >= due {
                        if let Err(e) = self.advance() {
                            break Err(e);
                        }
                        continue;
                    }
                    due - now
                }
            };
            let mut woke = false;
            let r = ws.wait_and_process_once_with_timeout(
                |_| {
                    woke = true;
                    CallbackProgression::Continue
                },
                timeout,
            );
            match r {
                Ok(WaitSetRunResult::TerminationRequest | WaitSetRunResult::Interrupt) => {
                    signalled = true;
                    break Ok(());
                }
                Ok(_) => {}
                Err(e) => break Err(ProcessError::WaitSet(format!("{e:?}"))),
            }
            if !woke && self.clock == ClockMode::Lockstep {
                // Deadline passed: whoever is still missing is down and brakes.
                for i in 0..self.live.len() {
                    if !self.have[i] {
                        self.live[i] = false;
                        self.world.brake(i as u32);
                    }
                }
            }
        };
        drop(guards);
        self.wheels = wheels;
        result.map(|()| Outcome {
            periods: self.period,
            collisions: self.world.collisions().len(),
            signalled,
        })
    }

    /// Reads every wheel topic: liveness from the wake-up events, commands for the current
    /// period (or later) applied at the current sim time; stale ones are dropped.
    fn drain(&mut self, wheels: &[Receiver<WheelCommand>]) -> Result<(), ProcessError> {
        let now = self.world.time_ns();
        for (i, rx) in wheels.iter().enumerate() {
            let w = rx.take_wakeup()?;
            if w.peer_dead || w.peer_left {
                self.live[i] = false;
                self.world.brake(i as u32);
            }
            if w.peer_up {
                self.live[i] = true;
            }
            let (world, have, live, period) =
                (&mut self.world, &mut self.have, &mut self.live, self.period);
            let realtime = self.clock == ClockMode::Realtime;
            rx.drain(|c| {
                let fresh = c.period >= period || realtime;
                if fresh && c.agent as usize == i {
                    // Non-finite set-points are dropped: a bad agent cannot stop the sim.
                    if world
                        .apply_command(c.agent, c.period, c.left_rad_s, c.right_rad_s, now)
                        .is_ok()
                    {
                        have[i] = true;
                        live[i] = true;
                    }
                }
            })?;
        }
        Ok(())
    }

    /// Whether every live robot's command for the current period is in.
    fn ready(&self) -> bool {
        self.live.iter().zip(&self.have).all(|(&l, &h)| !l || h)
    }

    /// Steps one control period and publishes odometry and truth for it.
    fn advance(&mut self) -> Result<(), ProcessError> {
        for _ in 0..self.world.steps_per_odometry() {
            self.world.step();
        }
        for (i, tx) in self.odom.iter().enumerate() {
            if let Some(o) = self.world.odometry(i as u32, self.period) {
                tx.send(o)?;
            }
        }
        let (world, period) = (&self.world, self.period);
        self.truth_tx
            .send_in_place(|t| world.fill_truth(period, t))?;
        self.period += 1;
        self.have.iter_mut().for_each(|h| *h = false);
        Ok(())
    }
}
