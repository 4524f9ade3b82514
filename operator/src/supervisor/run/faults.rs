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

use std::time::{Duration, Instant};

use super::slots::Slots;
use crate::supervisor::child::Signal;
use crate::supervisor::events::RunEvent;
use hnav_runtime::msg::Role;
use hnav_runtime::scenario::{
    FaultAction, FaultSignal, FaultSpec, FaultTarget, FaultTime, SimParams,
};

/// The plan's faults, which have fired, the hold in progress and the freezes to end.
pub(super) struct FaultSchedule<'s> {
    faults: &'s [FaultSpec],
    /// When each fault is due.
    due: Vec<Due>,
    done: Vec<bool>,
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
    /// Role, index and pid of each process that has to settle before the run resumes.
    hit: Vec<(Role, u32, u32)>,
}

/// A frozen process to continue.
struct Thaw {
    at: Instant,
    role: Role,
    index: u32,
    pid: u32,
    fault: usize,
}

impl<'s> FaultSchedule<'s> {
    /// None of `faults` fired yet; `sim` turns their seconds into rounds in `lockstep`.
    pub(super) fn new(faults: &'s [FaultSpec], lockstep: bool, sim: &SimParams) -> Self {
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
        Self {
            faults,
            due,
            done: vec![false; faults.len()],
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

    /// Realtime: sends the signals of the faults that are due, `since_start` after `Start`,
    /// each once.
    pub(super) fn fire_due(&mut self, slots: &Slots, since_start: Duration) {
        if self.lockstep {
            return;
        }
        for i in 0..self.faults.len() {
            let due = match self.due[i] {
                Due::Round(r) => r <= self.round,
                Due::After(d) => d <= since_start,
            };
            if !self.done[i] && due {
                self.fire(i, slots, self.round, false);
            }
        }
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

    /// Sends SIGCONT to every frozen process whose freeze is over by `now`.
    pub(super) fn thaw_due(&mut self, slots: &Slots, now: Instant) {
        let (due, later): (Vec<Thaw>, Vec<Thaw>) = self.thaws.drain(..).partition(|t| t.at <= now);
        self.thaws = later;
        for t in due {
            self.thaw(&t, slots);
        }
    }

    /// Continues every process still frozen by the plan, so that the end of the run finds
    /// them able to stop politely.
    pub(super) fn thaw_all(&mut self, slots: &Slots) {
        for t in std::mem::take(&mut self.thaws) {
            self.thaw(&t, slots);
        }
    }

    fn thaw(&self, t: &Thaw, slots: &Slots) {
        let Some(c) = slots
            .child(t.role, t.index)
            .filter(|c| c.pid() == t.pid && c.exit().is_none())
        else {
            tracing::info!(
                node = t.role.node_name(t.index),
                pid = t.pid,
                "frozen process is gone; no SIGCONT"
            );
            return;
        };
        if let Err(e) = c.signal(Signal::SIGCONT) {
            tracing::warn!("freeze not ended: {e}");
            return;
        }
        tracing::warn!(node = t.role.node_name(t.index), "fault: continued");
        slots.events().record(RunEvent::Signalled {
            node: t.role.node_name(t.index),
            pid: t.pid,
            signal: Signal::SIGCONT.to_string(),
            fault: Some(t.fault),
            round: self.round,
        });
    }

    /// Lockstep: the sim holds before `period`; fires the faults of that round (each once: a
    /// restarted sim holding again at a round already done is resumed at once).
    pub(super) fn on_hold(&mut self, slots: &Slots, period: u64) {
        self.round = period;
        let mut hit = Vec::new();
        for i in 0..self.faults.len() {
            if !self.done[i] && matches!(self.due[i], Due::Round(r) if r == period) {
                hit.extend(self.fire(i, slots, period, true));
            }
        }
        self.held = Some(Held { period, hit });
    }

    /// Lockstep: the period to resume, once every process hit at the hold is done with.
    pub(super) fn resume_due(&mut self, slots: &Slots) -> Option<u64> {
        let held = self.held.as_ref()?;
        if !held
            .hit
            .iter()
            .all(|&(role, index, pid)| slots.settled(role, index, pid))
        {
            return None;
        }
        self.held.take().map(|h| h.period)
    }

    /// Sends fault `i`'s signal and marks it fired; returns whom a hold has to wait for (a
    /// killed process, or a frozen one that died instead of stopping). With `wait_stop`, a
    /// freeze returns once its target is stopped. A target that is not running (down,
    /// waiting for its restart) misses its fault.
    fn fire(
        &mut self,
        i: usize,
        slots: &Slots,
        round: u64,
        wait_stop: bool,
    ) -> Option<(Role, u32, u32)> {
        self.done[i] = true;
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
        let c = slots.child(role, index)?;
        tracing::warn!(
            node = role.node_name(index),
            %signal,
            round,
            "fault injected"
        );
        if let Err(e) = c.signal(signal) {
            tracing::warn!("fault not injected: {e}");
            return None;
        }
        slots.events().record(RunEvent::Signalled {
            node: role.node_name(index),
            pid: c.pid(),
            signal: signal.to_string(),
            fault: Some(i),
            round,
        });
        let hit = Some((role, index, c.pid()));
        let FaultAction::Freeze { for_s } = f.action else {
            return hit;
        };
        if wait_stop && !c.wait_stopped() {
            return hit;
        }
        // A freeze too long for the clock is one that is never ended.
        let end = for_s
            .and_then(|secs| Duration::try_from_secs_f64(secs).ok())
            .and_then(|d| Instant::now().checked_add(d));
        if let Some(at) = end {
            self.thaws.push(Thaw {
                at,
                role,
                index,
                pid: c.pid(),
                fault: i,
            });
        }
        None
    }
}
