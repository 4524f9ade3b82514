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
//! In realtime the world follows the wall clock and commands apply when they arrive. The
//! process blocks in a WaitSet throughout (listeners on the wheel topics, plus an interval in
//! realtime or, if set, the deadline in lockstep as a timeout).

use crate::error::SimError;
use crate::world::World;
use hnav_runtime::launch::{LifecyclePorts, LOST_WAKEUP_RECHECK};
use hnav_runtime::msg::{LifecycleEvent, Role};
use hnav_runtime::msg::{Odometry, Truth, WheelCommand};
use hnav_runtime::scenario::params::ClockMode;
use hnav_runtime::scenario::Scenario;
use hnav_runtime::topics;
use hnav_runtime::transport::{Receiver, Sender, Transport, TransportError};
use iceoryx2::prelude::CallbackProgression;
use iceoryx2::waitset::WaitSetRunResult;
use std::time::{Duration, Instant};

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
    life: Option<LifecyclePorts>,
    /// `sim.lockstep_deadline_ms`, `None` for 0 (wait indefinitely).
    lockstep_deadline: Option<Duration>,
}

impl<'t> SimProcess<'t> {
    /// Builds the world from `scenario` (robots at their start cells' centres, facing their
    /// `start_heading_deg`) and opens the ports.
    pub fn new(transport: &'t Transport, scenario: &Scenario) -> Result<Self, ProcessError> {
        let world = World::from_scenario(scenario)?;
        let n = world.robots();
        let q = topics::state_qos();
        let wheels = (0..n)
            .map(|i| transport.receiver(&topics::wheels(i), q))
            .collect::<Result<Vec<_>, _>>()?;
        let odom = (0..n)
            .map(|i| transport.sender(&topics::odometry(i), q))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(SimProcess {
            truth_tx: transport.sender(topics::TRUTH, q)?,
            life: None,
            transport,
            world,
            clock: scenario.sim.clock,
            wheels,
            odom,
            live: vec![true; n],
            have: vec![false; n],
            period: 0,
            lockstep_deadline: (scenario.sim.lockstep_deadline_ms > 0)
                .then(|| Duration::from_millis(scenario.sim.lockstep_deadline_ms.into())),
        })
    }

    /// Joins the run's lifecycle protocol: the process then hears the supervisor's `Stop`
    /// and learns of agents that died (their robots brake and are not waited for) or were
    /// restarted.
    pub fn with_lifecycle(mut self, ports: LifecyclePorts) -> Self {
        self.life = Some(ports);
        self
    }

    /// The lifecycle ports, if joined.
    pub fn lifecycle(&self) -> Option<&LifecyclePorts> {
        self.life.as_ref()
    }

    /// The world.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// Runs until a termination signal or, if given, `max_periods` control periods.
    pub fn run(&mut self, max_periods: Option<u64>) -> Result<Outcome, ProcessError> {
        let ws = self.transport.waitset().map_err(ProcessError::Transport)?;
        let wheels = std::mem::take(&mut self.wheels);
        let life = self.life.take();
        let mut guards = Vec::with_capacity(wheels.len());
        for rx in &wheels {
            let g = ws
                .attach_notification(rx.listener())
                .map_err(|e| ProcessError::WaitSet(format!("{e:?}")))?;
            guards.push(g);
        }
        if let Some(l) = &life {
            let g = ws
                .attach_notification(l.events().listener())
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
            match self.on_lifecycle(life.as_ref()) {
                Ok(true) => {
                    signalled = true;
                    break Ok(());
                }
                Ok(false) => {}
                Err(e) => break Err(e),
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
                    self.lockstep_deadline.unwrap_or(LOST_WAKEUP_RECHECK)
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
            if !woke && self.clock == ClockMode::Lockstep && self.lockstep_deadline.is_some() {
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
        self.life = life;
        result.map(|()| Outcome {
            periods: self.period,
            collisions: self.world.collisions().len(),
            signalled,
        })
    }

    /// Applies the supervisor's events; returns whether it asked to stop. A dead agent's
    /// robot brakes and is not waited for; a restarted one counts again from its first fresh
    /// command (it needs this period's odometry before it can send one).
    fn on_lifecycle(&mut self, life: Option<&LifecyclePorts>) -> Result<bool, ProcessError> {
        let Some(l) = life else { return Ok(false) };
        let mut restarted = Vec::new();
        let (live, world) = (&mut self.live, &mut self.world);
        let stop = l.drain(|role, index, ev| {
            let Some(v) = live.get_mut(index as usize) else {
                return;
            };
            match (role, ev) {
                (Role::Agent, LifecycleEvent::Down) => {
                    *v = false;
                    world.brake(index);
                }
                (Role::Agent, LifecycleEvent::Restarted) => restarted.push(index),
                _ => {}
            }
        })?;
        // A restarted agent needs an odometry reading before it can command its wheels, and
        // the last one may have gone out before it subscribed: send it again and wait for the
        // agent from this period on. One that has already rejoined (its first fresh command
        // came in before the event) needs nothing, and its command must not be forgotten.
        if let Some(last) = self.period.checked_sub(1) {
            for i in restarted {
                let rejoined = self.live.get(i as usize).copied().unwrap_or(true);
                if let (false, Some(o), Some(tx)) = (
                    rejoined,
                    self.world.odometry(i, last),
                    self.odom.get(i as usize),
                ) {
                    tx.send(o)?;
                    self.live[i as usize] = true;
                }
            }
        }
        Ok(stop.is_some())
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
