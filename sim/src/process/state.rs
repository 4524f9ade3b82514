//! The simulator's state between wake-ups and its handlers: the world, which robots are live
//! and which have sent this period's command, and the period counter.

use std::collections::VecDeque;
use std::ops::Range;
use std::time::Duration;

use hnav_runtime::msg::{
    LifecycleEvent, MoversHeader, OdometryHeader, Role, RosterState, View, ViewsHeader,
};
use hnav_runtime::scenario::params::ClockMode;
use hnav_runtime::topics::OdometrySender;

use super::checkpoint::SimCheckpoint;
use super::ports::Ports;
use super::{SimOutcome, SimProcessError};
use crate::world::World;

/// What the loop of [`SimProcess`](super::SimProcess) mutates.
pub(crate) struct State {
    pub(crate) world: World,
    pub(crate) clock: ClockMode,
    /// Robot `i` is waited for in lockstep.
    live: Vec<bool>,
    /// Robot `i`'s command for the current period is in.
    have: Vec<bool>,
    /// The control period being collected (periods stepped so far).
    pub(crate) period: u64,
    /// `sim.lockstep_deadline_ms`, `None` for 0 (wait indefinitely).
    pub(crate) lockstep_deadline: Option<Duration>,
    /// Lockstep with a fault plan: the periods to hold before, ascending (the distinct
    /// lockstep rounds of the run's faults; round `r` is committed just before period `r`
    /// is stepped).
    holds: VecDeque<u64>,
    /// The `Hold` for the first of `holds` has been sent.
    hold_sent: bool,
    /// Where each stepped period is checkpointed for a restart, if the run has a directory.
    pub(crate) checkpoint: Option<SimCheckpoint>,
    /// The range of the robots' views, cells; none: the scenario senses nothing.
    view_range: Option<u32>,
}

/// What a lifecycle drain found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct LifecycleNews {
    /// The supervisor asked the process to stop.
    pub(crate) stop: bool,
    /// Some event came in.
    pub(crate) any: bool,
}

impl State {
    /// The state of a fresh run of `world`: every robot live, no command in, period 0.
    pub(crate) fn new(world: World, clock: ClockMode, lockstep_deadline: Option<Duration>) -> Self {
        let n = world.robots();
        Self {
            world,
            clock,
            live: vec![true; n],
            have: vec![false; n],
            period: 0,
            lockstep_deadline,
            holds: VecDeque::new(),
            hold_sent: false,
            checkpoint: None,
            view_range: None,
        }
    }

    /// Publishes each robot's view within `range` cells with its odometry (none: no views).
    pub(crate) fn with_views(mut self, range: Option<u32>) -> Self {
        self.view_range = range;
        self
    }

    /// Holds before stepping each of `periods` until the supervisor's `Resume` for it.
    pub(crate) fn hold_at(&mut self, periods: impl IntoIterator<Item = u64>) {
        let mut v: Vec<u64> = periods.into_iter().collect();
        v.sort_unstable();
        v.dedup();
        self.holds = v.into();
        self.hold_sent = false;
    }

    /// Whether the current period, ready to be stepped, waits for the supervisor's `Resume`;
    /// the first time, tells it with `Hold`. Fault rounds behind the current period are
    /// dropped; a restarted sim, which starts again at period 0, holds at every fault round
    /// once more (one resumed from its checkpoint, at those from its period on), and the
    /// supervisor resumes those already done at once.
    pub(crate) fn holding(&mut self, ports: &Ports) -> Result<bool, SimProcessError> {
        while self.holds.front().is_some_and(|&p| p < self.period) {
            self.holds.pop_front();
            self.hold_sent = false;
        }
        if self.holds.front() != Some(&self.period) {
            return Ok(false);
        }
        if !self.hold_sent {
            if let Some(l) = &ports.life {
                l.hold(self.period)?;
            }
            self.hold_sent = true;
        }
        Ok(true)
    }

    /// The wall-clock length of one control period (one odometry period).
    pub(crate) fn period_wall(&self) -> Duration {
        Duration::from_secs_f64(self.world.steps_per_odometry() as f64 * self.world.model().dt)
    }

    /// How the run stands; `signalled` says whether a stop request ended it.
    pub(crate) fn outcome(&self, signalled: bool) -> SimOutcome {
        SimOutcome {
            periods: self.period,
            collisions: self.world.collisions().len(),
            signalled,
        }
    }

    /// Applies the supervisor's events. A dead or lost agent's robot (also one the roster
    /// names so) brakes and is not waited for, and
    /// a command it sent for this period is void (the brake overrode it); a restarted one
    /// counts again from its first fresh command (it needs this period's odometry before it
    /// can send one). A `Resume` for the period held at ends the hold.
    pub(crate) fn on_lifecycle(&mut self, ports: &Ports) -> Result<LifecycleNews, SimProcessError> {
        let Some(l) = &ports.life else {
            return Ok(LifecycleNews {
                stop: false,
                any: false,
            });
        };
        // Empty unless an agent was restarted: no allocation in an ordinary round.
        let mut restarted = Vec::new();
        let mut any = false;
        let mut resumed = None;
        let (live, have, world) = (&mut self.live, &mut self.have, &mut self.world);
        let stop = l.drain_samples(|role, ev, sample| {
            any = true;
            if ev == LifecycleEvent::Resume {
                resumed = Some(sample.period());
                return;
            }
            let index = sample.index;
            let (Some(v), Some(h)) = (live.get_mut(index as usize), have.get_mut(index as usize))
            else {
                return;
            };
            // A restarted sim learns from the roster which agents are down or lost: it must
            // not wait for their robots.
            let down = match ev {
                LifecycleEvent::Roster => matches!(
                    RosterState::from_u8(sample.reason),
                    Some(RosterState::Down | RosterState::Lost)
                ),
                _ => matches!(ev, LifecycleEvent::Down | LifecycleEvent::Lost),
            };
            match (role, ev) {
                (Role::Agent, _) if down => {
                    *v = false;
                    *h = false;
                    world.brake(index);
                }
                (Role::Agent, LifecycleEvent::Restarted) => restarted.push(index),
                _ => {}
            }
        })?;
        if resumed.is_some() && resumed == self.holds.front().copied() {
            self.holds.pop_front();
            self.hold_sent = false;
        }
        self.resend_odometry(ports, &restarted)?;
        Ok(LifecycleNews {
            stop: stop.is_some(),
            any,
        })
    }

    /// A restarted agent needs an odometry reading before it can command its wheels, and the
    /// last one may have gone out before it subscribed: sends it again and waits for the agent
    /// from this period on. One that has already rejoined (its first fresh command came in
    /// before the event) needs nothing, and its command must not be forgotten.
    fn resend_odometry(&mut self, ports: &Ports, restarted: &[u32]) -> Result<(), SimProcessError> {
        let Some(last) = self.period.checked_sub(1) else {
            return Ok(());
        };
        // The robots of one process restart together and share one odometry sample: sent
        // once for those of them that have not rejoined.
        for (p, tx) in ports.odom.iter().enumerate() {
            let robots = ports.robots_of(p);
            let waiting = |i: &u32| {
                robots.contains(i) && !self.live.get(*i as usize).copied().unwrap_or(true)
            };
            if !restarted.iter().any(waiting) {
                continue;
            }
            self.send_odometry(tx, robots.clone(), last)?;
            for &i in restarted.iter().filter(|i| robots.contains(i)) {
                self.live[i as usize] = true;
            }
        }
        Ok(())
    }

    /// Sends the odometry of `robots` (one agent process's) for `period` on `tx`.
    fn send_odometry(
        &self,
        tx: &OdometrySender,
        robots: Range<u32>,
        period: u64,
    ) -> Result<(), SimProcessError> {
        let (first, n) = (robots.start, robots.len());
        let header = OdometryHeader {
            first,
            count: n as u32,
        };
        let w = &self.world;
        tx.send_from_fn(header, n, |k| {
            w.odometry(first + k as u32, period).unwrap_or_default()
        })?;
        Ok(())
    }

    /// Reads every wheel topic: liveness from the wake-up events, commands for the current
    /// period (or later) applied at the current sim time; stale ones are dropped. Returns
    /// whether anything (an event or a sample) came in.
    ///
    /// The events are taken before the samples (the drain order of
    /// [`Waiter`](hnav_runtime::transport::Waiter)), and acted on before them too, which is
    /// why this is not `drain_pending`: a robot whose publisher died and which still sent a
    /// fresh command counts as live from that command, not as down.
    pub(crate) fn drain(&mut self, ports: &Ports) -> Result<bool, SimProcessError> {
        let now = self.world.time_ns();
        let realtime = self.clock == ClockMode::Realtime;
        let mut any = false;
        for (p, rx) in ports.wheels.iter().enumerate() {
            let robots = ports.robots_of(p);
            let w = rx.take_wakeup()?;
            any |= w.data || w.peer_up || w.peer_left || w.peer_dead;
            if w.peer_dead || w.peer_left {
                for i in robots.clone() {
                    self.live[i as usize] = false;
                    self.have[i as usize] = false;
                    self.world.brake(i);
                }
            }
            let (world, have, live, period) =
                (&mut self.world, &mut self.have, &mut self.live, self.period);
            any |= rx.drain(|_, commands| {
                for c in commands {
                    let fresh = c.period >= period || realtime;
                    // Non-finite set-points are dropped: a bad agent cannot stop the sim;
                    // nor can it command a robot of another process.
                    if fresh
                        && robots.contains(&c.agent)
                        && world
                            .apply_command(c.agent, c.period, c.left_rad_s, c.right_rad_s, now)
                            .is_ok()
                    {
                        have[c.agent as usize] = true;
                        live[c.agent as usize] = true;
                    }
                }
            })? > 0;
        }
        Ok(any)
    }

    /// Whether every live robot's command for the current period is in.
    pub(crate) fn ready(&self) -> bool {
        self.live.iter().zip(&self.have).all(|(&l, &h)| !l || h)
    }

    /// The lockstep deadline passed: whoever is still missing is down and brakes.
    pub(crate) fn mark_missing_down(&mut self) {
        for (i, (live, have)) in self.live.iter_mut().zip(&self.have).enumerate() {
            if !have {
                *live = false;
                self.world.brake(i as u32);
            }
        }
    }

    /// Steps one control period, checkpoints it, and publishes odometry and truth for it.
    pub(crate) fn advance(&mut self, ports: &Ports) -> Result<(), SimProcessError> {
        for _ in 0..self.world.steps_per_odometry() {
            self.world.step();
        }
        if let Some(c) = &mut self.checkpoint {
            c.store(&self.world, self.period + 1)?;
        }
        self.publish(ports, self.period)?;
        self.period += 1;
        self.have.iter_mut().for_each(|h| *h = false);
        Ok(())
    }

    /// Publishes every robot's odometry and the truth of the world as it stands, as the
    /// reading of `period`.
    fn publish(&self, ports: &Ports, period: u64) -> Result<(), SimProcessError> {
        // Views first: an agent acting on its odometry has the view of the same period.
        if let Some(range) = self.view_range {
            for (p, tx) in ports.view.iter().enumerate() {
                let robots = ports.robots_of(p);
                let mut loan = tx.loan(robots.len())?;
                *loan.header_mut() = ViewsHeader {
                    first: robots.start,
                    count: robots.len() as u32,
                };
                loan.fill_with(View::default(), |views| {
                    for (i, v) in robots.zip(views) {
                        self.world.fill_view(i, period, range, v);
                    }
                    Ok::<(), SimProcessError>(())
                })?;
            }
        }
        for (p, tx) in ports.odom.iter().enumerate() {
            self.send_odometry(tx, ports.robots_of(p), period)?;
        }
        let world = &self.world;
        let n = world.robots();
        (ports.truth).send_from_fn(world.truth_header(period), n, |i| world.pose_at(i))?;
        if let Some(tx) = &ports.movers {
            let header = MoversHeader {
                sim_time_ns: world.time_ns(),
                period,
            };
            let n = world.movers_on_floor().min(tx.max_len());
            tx.send_from_fn(header, n, |k| world.mover_place(k))?;
        }
        Ok(())
    }

    /// A restarted sim: restores the world and the period counter from the checkpoint, if
    /// there is one, and publishes the last stepped period's odometry and truth again (its
    /// predecessor may have died between checkpointing and publishing them). Returns the
    /// period resumed at.
    pub(crate) fn resume(&mut self, ports: &Ports) -> Result<Option<u64>, SimProcessError> {
        let Some(c) = &self.checkpoint else {
            return Ok(None);
        };
        let Some(r) = c.load(&mut self.world)? else {
            return Ok(None);
        };
        self.period = r.period;
        if let Some(last) = r.period.checked_sub(1) {
            self.publish(ports, last)?;
        }
        Ok(Some(r.period))
    }
}
