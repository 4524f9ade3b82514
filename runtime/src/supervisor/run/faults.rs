//! The scenario's planned faults: a signal to one process once the coordinator reports the
//! fault's round committed.

use super::slots::Slots;
use crate::msg::Role;
use crate::scenario::{FaultSignal, FaultSpec, FaultTarget};
use crate::supervisor::child::Signal;

/// Which of the scenario's faults have fired.
pub(super) struct FaultSchedule<'s> {
    faults: &'s [FaultSpec],
    done: Vec<bool>,
}

impl<'s> FaultSchedule<'s> {
    /// None of `faults` fired yet.
    pub(super) fn new(faults: &'s [FaultSpec]) -> Self {
        Self {
            faults,
            done: vec![false; faults.len()],
        }
    }

    /// Sends the signals of the faults whose round has come, each once. A target that is
    /// not running (down, waiting for its restart) misses its fault.
    pub(super) fn fire(&mut self, slots: &Slots, round: u64) {
        for (f, d) in self.faults.iter().zip(self.done.iter_mut()) {
            if *d || round < f.at_round {
                continue;
            }
            *d = true;
            let (role, index) = match f.target {
                FaultTarget::Agent(i) => (Role::Agent, i as u32),
                FaultTarget::Coordinator => (Role::Coordinator, 0),
                FaultTarget::Sim => (Role::Sim, 0),
            };
            let signal = match f.signal {
                FaultSignal::Kill => Signal::SIGKILL,
                FaultSignal::Term => Signal::SIGTERM,
            };
            if let Some(c) = slots.child(role, index) {
                tracing::warn!(
                    node = role.node_name(index),
                    ?signal,
                    round,
                    "fault injected"
                );
                if let Err(e) = c.signal(signal) {
                    tracing::warn!("fault not injected: {e}");
                }
            }
        }
    }
}
