//! The run's planned faults (the scenario's `[[faults]]`, then the command line's): a signal
//! to one process at the fault's time, and for a freeze the SIGCONT that ends it.
//!
//! In realtime a fault at a round fires once the coordinator reports that round committed,
//! and one in seconds once that much wall-clock time has passed since `Start`, while the run
//! goes on. In lockstep every fault is at a round (seconds become the round of that much
//! simulated time, [`FaultSpec::lockstep_round`]) and the run holds there instead: the sim,
//! with every live robot's command for the period of the round in, sends `Hold` and does not
//! step until the supervisor's `Resume`. The supervisor fires that round's faults, waits until
//! each target is done (a killed one reaped and either not restarted or restarted and up, a
//! frozen one stopped), then resumes, so every fault hits the same state at the same round
//! in every run.
//!
//! A freeze is SIGSTOP, then SIGCONT `for_s` later on the wall clock (in lockstep too: the
//! run does not step past the frozen process meanwhile, so when it is continued does not
//! change the log). The SIGCONT is a deadline of the supervisor's wait, and goes only to the
//! incarnation that was stopped: one that died meanwhile (hang detection kills a process
//! frozen for too long) or was replaced gets nothing.
//!
//! In a run across hosts every host's supervisor reads the same plan and carries out the
//! faults whose target it runs ([`HostPart::runs_target`]); the others it passes over. In
//! lockstep only the host that runs a round's targets resumes the sim's hold at it (the plan
//! is checked so that one host does: [`HostPart::check_faults`]).
//!
//! The schedule only decides: it reads the slots and returns the signals to send
//! ([`Action::Signal`]); the watch sends them and tells it where each fault's landed
//! ([`FaultSchedule::landed`]), which is what a hold waits for and what a freeze ends.

use std::time::{Duration, Instant};

use super::action::{Action, Incarnation, Landed, Shot, Why};
use super::host::HostPart;
use super::slots::Slots;
use crate::supervisor::child::Signal;
use hnav_runtime::msg::{Lifecycle, Role};
use hnav_runtime::scenario::{
    ClockMode, FaultAction, FaultSignal, FaultSpec, FaultTarget, FaultTime, Scenario,
};

/// The plan's faults, which have fired, the hold in progress and the freezes to end.
pub(super) struct FaultSchedule<'s> {
    faults: &'s [FaultSpec],
    /// When each fault is due.
    due: Vec<Due>,
    done: Vec<bool>,
    /// Whether this host runs each fault's target (always, on one host).
    mine: Vec<bool>,
    lockstep: bool,
    /// Realtime: the last round the coordinator reported committed.
    round: u64,
    /// The coordinator a fault aimed at "the coordinator" hits: the replica that last
    /// reported progress (the Raft leader), 0 for a single coordinator.
    leader: u32,
    held: Option<Held>,
    thaws: Vec<Thaw>,
}

/// When a fault is due.
#[derive(Clone, Copy)]
enum Due {
    /// Once this round is committed (lockstep: at the sim's hold before its period).
    Round(u64),
    /// Realtime: this long after `Start`.
    After(Duration),
}

/// Lockstep: the period the sim holds at and the process incarnations its faults hit.
struct Held {
    period: u64,
    /// Each process that has to settle before the run resumes.
    hit: Vec<Incarnation>,
}

/// A frozen process to continue.
struct Thaw {
    at: Instant,
    target: Incarnation,
    fault: usize,
}

impl<'s> FaultSchedule<'s> {
    /// None of `scenario`'s faults fired yet (seconds become rounds in lockstep); in a run
    /// across hosts (`host`), only those whose target this host runs are carried out here.
    pub(super) fn new(scenario: &'s Scenario, host: Option<&HostPart>) -> Self {
        let (faults, sim) = (&scenario.faults[..], &scenario.sim);
        let lockstep = sim.clock == ClockMode::Lockstep;
        let due = faults
            .iter()
            .map(|f| match f.at {
                _ if lockstep => Due::Round(f.lockstep_round(sim)),
                FaultTime::Round(r) => Due::Round(r),
                // Checked finite and >= 0 when the plan was read; one too far off for a
                // Duration never comes.
                FaultTime::Seconds(s) => {
                    Due::After(Duration::try_from_secs_f64(s).unwrap_or(Duration::MAX))
                }
            })
            .collect();
        let mine = faults
            .iter()
            .map(|f| host.is_none_or(|h| h.runs_target(&f.target)))
            .collect();
        Self {
            faults,
            due,
            done: vec![false; faults.len()],
            mine,
            lockstep,
            round: 0,
            leader: 0,
            held: None,
            thaws: Vec::new(),
        }
    }

    /// Realtime: the coordinator reports `round` committed.
    pub(super) fn on_round(&mut self, round: u64) {
        self.round = self.round.max(round);
    }

    /// The coordinator replica that reported progress last (0 for a single coordinator): the
    /// leader, which "the coordinator" means to a fault.
    pub(super) fn on_leader(&mut self, leader: u8) {
        self.leader = u32::from(leader);
    }

    /// Realtime: the signals of the faults that are due, `since_start` after `Start`, each
    /// once.
    pub(super) fn fire_due(&mut self, slots: &Slots, since_start: Duration) -> Vec<Action> {
        if self.lockstep {
            return Vec::new();
        }
        let mut todo = Vec::new();
        for i in 0..self.faults.len() {
            let due = match self.due[i] {
                Due::Round(r) => r <= self.round,
                Due::After(d) => d <= since_start,
            };
            if !self.done[i] && due {
                todo.extend(self.fire(i, slots, self.round, false));
            }
        }
        todo
    }

    /// The next time something is due: a realtime fault in seconds (`start` = when `Start`
    /// was published) or the end of a freeze.
    pub(super) fn next_deadline(&self, start: Instant) -> Option<Instant> {
        let timed = self
            .due
            .iter()
            .zip(&self.done)
            .filter_map(|(due, done)| match due {
                Due::After(d) if !done && !self.lockstep => start.checked_add(*d),
                _ => None,
            });
        timed.chain(self.thaws.iter().map(|t| t.at)).min()
    }

    /// The SIGCONT of every frozen process whose freeze is over by `now`.
    pub(super) fn thaw_due(&mut self, now: Instant) -> Vec<Action> {
        let (due, later): (Vec<Thaw>, Vec<Thaw>) = self.thaws.drain(..).partition(|t| t.at <= now);
        self.thaws = later;
        due.iter().map(|t| self.thaw(t)).collect()
    }

    /// The SIGCONT of every process still frozen by the plan, so that the end of the run
    /// finds them able to stop politely.
    pub(super) fn thaw_all(&mut self) -> Vec<Action> {
        let all = std::mem::take(&mut self.thaws);
        all.iter().map(|t| self.thaw(t)).collect()
    }

    fn thaw(&self, t: &Thaw) -> Action {
        Action::Signal(Shot {
            target: t.target,
            signal: Signal::SIGCONT,
            why: Why::Thaw(t.fault),
            round: self.round,
            wait_stop: false,
        })
    }

    /// Lockstep: the sim holds before `period`; the signals of the faults of that round
    /// (each once: a restarted sim holding again at a round already done is resumed at once).
    /// In a run across hosts, only the host that runs the round's targets holds (and so
    /// resumes): another host's `Resume` would end the hold before the faults landed.
    pub(super) fn on_hold(&mut self, slots: &Slots, period: u64) -> Vec<Action> {
        self.round = period;
        let at_hold = |i: usize| matches!(self.due[i], Due::Round(r) if r == period);
        if !(0..self.faults.len()).any(|i| at_hold(i) && self.mine[i]) {
            for i in (0..self.faults.len()).filter(|&i| at_hold(i)) {
                self.done[i] = true;
            }
            return Vec::new();
        }
        self.held = Some(Held {
            period,
            hit: Vec::new(),
        });
        let mut todo = Vec::new();
        for i in 0..self.faults.len() {
            if !self.done[i] && matches!(self.due[i], Due::Round(r) if r == period) {
                todo.extend(self.fire(i, slots, period, true));
            }
        }
        todo
    }

    /// Lockstep: the `Resume` of the hold, once every process hit at it is done with.
    pub(super) fn resume_due(&mut self, slots: &Slots) -> Option<Action> {
        let held = self.held.as_ref()?;
        if !held
            .hit
            .iter()
            .all(|t| slots.settled(t.role, t.index, t.pid))
        {
            return None;
        }
        let period = self.held.take()?.period;
        Some(Action::Publish(Lifecycle::resume(period)))
    }

    /// Marks fault `i` fired and returns its signal to the process it targets now (none if
    /// that is not running: down, waiting for its restart, it misses its fault). With
    /// `wait_stop`, a freeze is waited for until its target is stopped.
    fn fire(&mut self, i: usize, slots: &Slots, round: u64, wait_stop: bool) -> Option<Action> {
        self.done[i] = true;
        if !self.mine[i] {
            return None;
        }
        let f = &self.faults[i];
        let (role, index) = match f.target {
            FaultTarget::Agent(i) => (Role::Agent, i as u32),
            FaultTarget::Coordinator => (Role::Coordinator, self.leader),
            FaultTarget::Replica(id) => (Role::Coordinator, id),
            FaultTarget::Sim => (Role::Sim, 0),
        };
        let signal = match f.action {
            FaultAction::Kill(FaultSignal::Kill) => Signal::SIGKILL,
            FaultAction::Kill(FaultSignal::Term) => Signal::SIGTERM,
            FaultAction::Freeze { .. } => Signal::SIGSTOP,
        };
        // `agent:N` names a robot: the signal goes to the process that hosts it, named by
        // its first robot.
        let child = slots.child(role, index)?;
        let (index, pid) = (child.spec().index, child.pid());
        tracing::warn!(
            node = role.node_name(index),
            %signal,
            round,
            "fault injected"
        );
        Some(Action::Signal(Shot {
            target: Incarnation { role, index, pid },
            signal,
            why: Why::Fault(i),
            round,
            wait_stop: wait_stop && matches!(f.action, FaultAction::Freeze { .. }),
        }))
    }

    /// Fault `i`'s signal to `target` `landed`: a hold waits for a killed process (or a frozen
    /// one that died instead of stopping) to settle; a stopped one is continued `for_s` later.
    pub(super) fn landed(&mut self, i: usize, target: Incarnation, landed: Landed) {
        match (self.faults[i].action, landed) {
            (_, Landed::Missed) => {}
            (FaultAction::Freeze { for_s }, Landed::Sent) => self.thaw_later(i, target, for_s),
            _ => {
                if let Some(held) = &mut self.held {
                    held.hit.push(target);
                }
            }
        }
    }

    /// Fault `i` froze `target`: it is continued `for_s` from now (never without `for_s`).
    fn thaw_later(&mut self, i: usize, target: Incarnation, for_s: Option<f64>) {
        // A freeze too long for the clock is one that is never ended.
        let end = for_s
            .and_then(|secs| Duration::try_from_secs_f64(secs).ok())
            .and_then(|d| Instant::now().checked_add(d));
        if let Some(at) = end {
            self.thaws.push(Thaw {
                at,
                target,
                fault: i,
            });
        }
    }
}
