//! The scenario's planned faults: a signal to one process at the fault's round.
//!
//! In realtime a fault fires once the coordinator reports its round committed, while the run
//! goes on. In lockstep the run holds there instead: the sim, with every live robot's command
//! for the period of the round in, sends `Hold` and does not step until the supervisor's
//! `Resume`. The supervisor fires that round's faults, waits until each target is done (reaped
//! and either not restarted or restarted and up), then resumes, so every fault hits the same
//! state at the same round in every run.

use super::slots::Slots;
use crate::msg::Role;
use crate::scenario::{FaultSignal, FaultSpec, FaultTarget};
use crate::supervisor::child::Signal;
use crate::supervisor::events::RunEvent;

/// Which of the scenario's faults have fired, and the hold in progress.
pub(super) struct FaultSchedule<'s> {
    faults: &'s [FaultSpec],
    done: Vec<bool>,
    held: Option<Held>,
}

/// Lockstep: the period the sim holds at and the process incarnations its faults hit.
struct Held {
    period: u64,
    /// Role, index and pid of each process signalled.
    hit: Vec<(Role, u32, u32)>,
}

impl<'s> FaultSchedule<'s> {
    /// None of `faults` fired yet.
    pub(super) fn new(faults: &'s [FaultSpec]) -> Self {
        Self {
            faults,
            done: vec![false; faults.len()],
            held: None,
        }
    }

    /// Realtime: sends the signals of the faults whose round has come by `round`, each once.
    pub(super) fn fire_due(&mut self, slots: &Slots, round: u64) {
        for i in 0..self.faults.len() {
            if !self.done[i] && self.faults[i].at_round <= round {
                self.fire(i, slots, round);
            }
        }
    }

    /// Lockstep: the sim holds before `period`; fires the faults of that round (each once: a
    /// restarted sim holding again at a round already done is resumed at once).
    pub(super) fn on_hold(&mut self, slots: &Slots, period: u64) {
        let mut hit = Vec::new();
        for i in 0..self.faults.len() {
            if !self.done[i] && self.faults[i].at_round == period {
                hit.extend(self.fire(i, slots, period));
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

    /// Sends fault `i`'s signal and marks it fired; returns whom it hit. A target that is not
    /// running (down, waiting for its restart) misses its fault.
    fn fire(&mut self, i: usize, slots: &Slots, round: u64) -> Option<(Role, u32, u32)> {
        self.done[i] = true;
        let f = &self.faults[i];
        let (role, index) = match f.target {
            FaultTarget::Agent(i) => (Role::Agent, i as u32),
            FaultTarget::Coordinator => (Role::Coordinator, 0),
            FaultTarget::Sim => (Role::Sim, 0),
        };
        let signal = match f.signal {
            FaultSignal::Kill => Signal::SIGKILL,
            FaultSignal::Term => Signal::SIGTERM,
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
        Some((role, index, c.pid()))
    }
}
