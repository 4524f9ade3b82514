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
                if role == Role::Coordinator && ev == LifecycleEvent::Restarted && l.index == 0 {
                    self.roster_due = false;
                }
                if role == Role::Agent {
                    if self.roster_due {
                        return Ok(());
                    }
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

    /// This single coordinator was restarted (`--resume`): until the supervisor's
    /// `Restarted` for it, an agent's event is not logged. The first sample it hears is the
    /// lifecycle topic's history, the last event published before it subscribed: one its
    /// predecessor may have logged already, or the `Lost` of an agent whose `Down` (published
    /// just before) it never sees. The roster that follows its `Restarted` gives each agent's
    /// state then, and [`State::reconcile`] logs exactly what the log misses, in order.
    pub(in crate::process) fn await_roster(&mut self) {
        self.roster_due = true;
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

    /// This replica comes to lead: what it heard while following and no leader logged is
    /// logged now. The other processes' events first, in the order heard (the leader it
    /// replaces died unlogged: its `Down` reached only the followers), then each agent's
    /// state, reconciled with the log.
    pub(super) fn log_overheard(&mut self) -> Result<(), CoordinatorError> {
        for (role, index, ev, restarts) in self.heard.take_others() {
            self.log_event(role, index, ev, restarts)?;
        }
        for (i, state, restarts) in self.heard.take() {
            self.reconcile(i, state, restarts)?;
        }
        Ok(())
    }

    /// A following replica takes in the supervisor's events: liveness is remembered for when
    /// it comes to lead (the leader logs it meanwhile); returns how the run ends on a `Stop`.
    pub(in crate::process) fn overhear(
        &mut self,
        life: &LifecyclePorts,
    ) -> Result<Option<EndReason>, CoordinatorError> {
        let stop = self.heard.hear(life)?.map(stopped);
        if let Some(raft) = self.log.raft() {
            for dead in self.heard.take_replicas_down() {
                raft.replica_down(u64::from(dead));
            }
        }
        Ok(stop)
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use hnav_runtime::consensus_log::{read_log, Record};
    use hnav_runtime::msg::{Lifecycle, LifecycleEvent, Role, RosterState};
    use hnav_runtime::scenario::Scenario;

    use super::State;

    const TWO: &str = r#"
        name = "t"
        [map]
        rows = ["........", "........", "........"]
        [[agents]]
        start = [0, 1]
        goal = [7, 1]
        [[agents]]
        start = [2, 1]
        goal = [2, 0]
    "#;

    fn scenario() -> Scenario {
        Scenario::from_str(TWO, "test.toml", Path::new(".")).unwrap()
    }

    /// A coordinator restarted by the supervisor over the log its predecessor left in `dir`.
    fn restarted(s: &Scenario, dir: &Path) -> State {
        let mut state = State::open(s, dir).unwrap();
        state.await_roster();
        state
    }

    /// The agents' lifecycle records of the log in `dir`: (index, event, restarts).
    fn agent_records(state: &mut State, dir: &Path) -> Vec<(u32, LifecycleEvent, u32)> {
        state.sync().unwrap();
        let contents = read_log(dir.join("log")).unwrap();
        contents
            .records
            .iter()
            .filter_map(|r| match r {
                Record::Lifecycle(l) if l.role == Role::Agent as u8 => Some((
                    l.index,
                    LifecycleEvent::from_u8(l.event).unwrap(),
                    l.restarts,
                )),
                _ => None,
            })
            .collect()
    }

    /// What a restarted coordinator drains from the lifecycle topic: first the topic's
    /// history (the last event the supervisor published before it subscribed), then its own
    /// `Restarted` and the roster.
    fn drain(state: &mut State, history: Lifecycle, roster: [Lifecycle; 2]) {
        let own = Lifecycle::restarted(Role::Coordinator, 0, 1);
        for l in [history, own].iter().chain(&roster) {
            state.on_lifecycle(l).unwrap();
        }
    }

    /// Agent 1 and the coordinator die together and the supervisor reaps the coordinator
    /// first: it publishes the coordinator's `Down`, then agent 1's `Down` and `Lost`, so the
    /// restarted coordinator's history is agent 1's `Lost` alone.
    #[test]
    fn a_lost_agent_whose_down_a_restarted_coordinator_missed_is_logged_down_then_lost() {
        let s = scenario();
        let tmp = tempfile::tempdir().unwrap();
        drop(State::open(&s, tmp.path()).unwrap());
        let mut state = restarted(&s, tmp.path());
        drain(
            &mut state,
            Lifecycle::lost(Role::Agent, 1, 0),
            [
                Lifecycle::roster(0, RosterState::Up, 0),
                Lifecycle::roster(1, RosterState::Lost, 0),
            ],
        );
        assert_eq!(
            agent_records(&mut state, tmp.path()),
            vec![(1, LifecycleEvent::Down, 0), (1, LifecycleEvent::Lost, 0)]
        );
    }

    /// The predecessor logged agent 0's `Restarted` and died before the supervisor published
    /// anything else: the topic's history replays that `Restarted`, which must not be logged
    /// twice.
    #[test]
    fn an_agent_event_the_predecessor_logged_is_not_logged_again_from_the_topic_history() {
        let s = scenario();
        let tmp = tempfile::tempdir().unwrap();
        let mut first = State::open(&s, tmp.path()).unwrap();
        for l in [
            Lifecycle::down(Role::Agent, 0, 0),
            Lifecycle::restarted(Role::Agent, 0, 1),
        ] {
            first.on_lifecycle(&l).unwrap();
        }
        drop(first);
        let mut state = restarted(&s, tmp.path());
        drain(
            &mut state,
            Lifecycle::restarted(Role::Agent, 0, 1),
            [
                Lifecycle::roster(0, RosterState::Up, 1),
                Lifecycle::roster(1, RosterState::Up, 0),
            ],
        );
        assert_eq!(
            agent_records(&mut state, tmp.path()),
            vec![
                (0, LifecycleEvent::Down, 0),
                (0, LifecycleEvent::Restarted, 1)
            ]
        );
    }
}
