//! What the supervisor tells the coordinator: agents down, restarted, lost, its roster once a
//! coordinator is up, and the run's stop. A deciding coordinator logs liveness at the current
//! round; a following replica only remembers it for when it comes to lead.

use hnav_runtime::consensus_log::{EndReason, LifecycleRecord, Record};
use hnav_runtime::launch::LifecyclePorts;
use hnav_runtime::msg::{Lifecycle, LifecycleEvent, Role, RosterState, StopReason};

use super::State;
use crate::process::error::CoordinatorError;
use crate::process::ports::Ports;

/// How the run ends on the supervisor's `Stop`.
fn stopped(reason: StopReason) -> EndReason {
    match reason {
        StopReason::TimeLimit => EndReason::TimeLimit,
        StopReason::Requested => EndReason::Stopped,
    }
}

impl State {
    /// Takes in every pending supervisor event; returns how the run ends if one was `Stop`.
    pub(in crate::process) fn hear_supervisor(
        &mut self,
        p: &Ports,
        life: &LifecyclePorts,
    ) -> Result<Option<EndReason>, CoordinatorError> {
        // Taken out so that applying the events may borrow the state; an error ends the
        // process, so losing the buffer then costs nothing.
        let mut events = std::mem::take(&mut self.events);
        events.clear();
        let stop = life.drain_samples(|_, _, l| events.push(*l))?;
        let ended = self.ended();
        for l in &events {
            self.on_lifecycle(l)?;
        }
        self.events = events;
        // A robot lost while every other one is settled ends the run here, between rounds.
        self.end_if_over()?;
        if self.ended() && !ended {
            self.publish_progress(p)?;
        }
        Ok(stop.map(stopped))
    }

    /// A supervisor event: liveness of agents, logged for the record with the restart count
    /// the supervisor gives; a roster entry is reconciled with what the log holds.
    fn on_lifecycle(&mut self, l: &Lifecycle) -> Result<(), CoordinatorError> {
        let (Some(role), Some(ev)) = (Role::from_u8(l.role), LifecycleEvent::from_u8(l.event))
        else {
            return Ok(());
        };
        match ev {
            LifecycleEvent::Down | LifecycleEvent::Restarted | LifecycleEvent::Lost => {
                if role == Role::Agent {
                    self.roster.event(l.index, ev, l.restarts);
                }
                self.log_event(role, l.index, ev, l.restarts)
            }
            LifecycleEvent::Roster if role == Role::Agent => match RosterState::from_u8(l.reason) {
                Some(state) => self.reconcile(l.index, state, l.restarts),
                None => Ok(()),
            },
            _ => Ok(()),
        }
    }

    /// A roster entry (sent after this coordinator came up): the records the log misses
    /// because the agent died, came back or was given up while no coordinator listened are
    /// logged now, at the current round, and the agent is waited for or not accordingly.
    pub(super) fn reconcile(
        &mut self,
        index: u32,
        state: RosterState,
        restarts: u32,
    ) -> Result<(), CoordinatorError> {
        for (ev, count) in self
            .roster
            .missed(index, state, restarts)
            .into_iter()
            .flatten()
        {
            self.roster.event(index, ev, count);
            self.log_event(Role::Agent, index, ev, count)?;
        }
        Ok(())
    }

    /// Logs a lifecycle event at the current round, unless the run has ended.
    fn log_event(
        &mut self,
        role: Role,
        index: u32,
        ev: LifecycleEvent,
        restarts: u32,
    ) -> Result<(), CoordinatorError> {
        if self.ended() {
            return Ok(());
        }
        let event = match ev {
            LifecycleEvent::Restarted => Lifecycle::restarted(role, index, restarts),
            LifecycleEvent::Lost => Lifecycle::lost(role, index, restarts),
            _ => Lifecycle::down(role, index, restarts),
        };
        self.log
            .append(&Record::Lifecycle(LifecycleRecord::new(self.round, &event)))?;
        Ok(())
    }

    /// A following replica takes in the supervisor's events: liveness is remembered for when
    /// it comes to lead (the leader logs it meanwhile); returns how the run ends on a `Stop`.
    pub(in crate::process) fn overhear(
        &mut self,
        life: &LifecyclePorts,
    ) -> Result<Option<EndReason>, CoordinatorError> {
        Ok(self.heard.hear(life)?.map(stopped))
    }
}
