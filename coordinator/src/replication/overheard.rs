//! What a following replica hears of the supervisor ([`Overheard`]): the leader logs every
//! process's liveness meanwhile, but a replica that comes to lead must know who is live, and
//! what the leader it replaces did not log: above all that leader's own `Down`, which only
//! the followers hear (it is dead, and no one leads until they elect one).

use hnav_runtime::launch::LifecyclePorts;
use hnav_runtime::msg::{LifecycleEvent, Role, RosterState, StopReason};
use hnav_runtime::transport::TransportError;

/// A lifecycle event of a process other than an agent (the sim, a replica, a bridge):
/// `(role, index, event, restarts)`.
pub type OtherEvent = (Role, u32, LifecycleEvent, u32);

/// Where `event` with `restarts` falls in one process's life: `Restarted(k)` (its k-th
/// start) before `Down(k)` before `Restarted(k + 1)` or `Lost(k)`. Each event happens once
/// per process, so "logged up to here" says which heard events the log already holds.
fn ordinal(event: LifecycleEvent, restarts: u32) -> Option<u64> {
    let k = 2 * u64::from(restarts);
    match event {
        LifecycleEvent::Restarted => Some(k),
        LifecycleEvent::Down => Some(k + 1),
        LifecycleEvent::Lost => Some(k + 2),
        _ => None,
    }
}

/// Per agent, the last liveness the supervisor told a following replica (roster state and
/// restarts), reconciled with the log when the replica comes to lead; for every other
/// process, the events themselves, in the order heard, and how far the log holds its life.
pub struct Overheard {
    heard: Vec<Option<(RosterState, u32)>>,
    /// Events of processes other than agents, in the order heard. Few: a process's death
    /// or restart, bounded by the restart rules.
    others: Vec<OtherEvent>,
    /// Per process other than an agent: the ordinal of the last event the log holds.
    logged: Vec<(Role, u32, u64)>,
    /// Replicas heard `Down` since the last [`Overheard::take_replicas_down`]: if one led,
    /// this replica may stand for election at once.
    replicas_down: Vec<u32>,
}

impl Overheard {
    /// Nothing heard yet of `agents` agents.
    pub fn new(agents: usize) -> Self {
        Overheard {
            heard: vec![None; agents],
            others: Vec::new(),
            logged: Vec::new(),
            replicas_down: Vec::new(),
        }
    }

    /// Takes in the supervisor's pending events; returns why the run stops on a `Stop`.
    pub fn hear(&mut self, life: &LifecyclePorts) -> Result<Option<StopReason>, TransportError> {
        let (heard, others, down) = (&mut self.heard, &mut self.others, &mut self.replicas_down);
        life.drain_samples(|_, _, l| {
            let (Some(role), Some(ev)) = (Role::from_u8(l.role), LifecycleEvent::from_u8(l.event))
            else {
                return;
            };
            if role != Role::Agent {
                if (role, ev) == (Role::Coordinator, LifecycleEvent::Down) {
                    down.push(l.index);
                }
                let event = (role, l.index, ev, l.restarts);
                if ordinal(ev, l.restarts).is_some() && !others.contains(&event) {
                    others.push(event);
                }
                return;
            }
            let state = match ev {
                LifecycleEvent::Down => RosterState::Down,
                LifecycleEvent::Restarted => RosterState::Up,
                LifecycleEvent::Lost => RosterState::Lost,
                LifecycleEvent::Roster => match RosterState::from_u8(l.reason) {
                    Some(s) => s,
                    None => return,
                },
                _ => return,
            };
            if let Some(h) = heard.get_mut(l.index as usize) {
                *h = Some((state, l.restarts));
            }
        })
    }

    /// The replicas heard going down since the last call.
    pub fn take_replicas_down(&mut self) -> std::vec::Drain<'_, u32> {
        self.replicas_down.drain(..)
    }

    /// The log holds `event` of a process other than an agent (a committed record applied,
    /// or one this replica logs).
    pub fn logged(&mut self, role: Role, index: u32, event: LifecycleEvent, restarts: u32) {
        let Some(n) = ordinal(event, restarts) else {
            return;
        };
        match self
            .logged
            .iter_mut()
            .find(|(r, i, _)| (*r, *i) == (role, index))
        {
            Some(l) => l.2 = l.2.max(n),
            None => self.logged.push((role, index, n)),
        }
    }

    /// What was heard of agents, once (the replica comes to lead): `(agent, state,
    /// restarts)` for every agent the supervisor spoke of.
    pub fn take(&mut self) -> impl Iterator<Item = (u32, RosterState, u32)> {
        std::mem::take(&mut self.heard)
            .into_iter()
            .enumerate()
            .filter_map(|(i, h)| h.map(|(state, restarts)| (i as u32, state, restarts)))
    }

    /// The events of other processes the log does not hold, once (the replica comes to
    /// lead), in the order heard.
    pub fn take_others(&mut self) -> Vec<OtherEvent> {
        let mut missed = std::mem::take(&mut self.others);
        missed.retain(|&(role, index, ev, restarts)| {
            let logged = self
                .logged
                .iter()
                .find(|(r, i, _)| (*r, *i) == (role, index))
                .map(|l| l.2);
            ordinal(ev, restarts).is_some_and(|n| logged.is_none_or(|l| n > l))
        });
        missed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_log_holds_a_processs_life_up_to_its_last_logged_event() {
        let mut o = Overheard::new(0);
        let c = Role::Coordinator;
        o.others = vec![
            (c, 2, LifecycleEvent::Down, 0),
            (c, 2, LifecycleEvent::Restarted, 1),
            (Role::Sim, 0, LifecycleEvent::Down, 3),
        ];
        // The leader logged replica 2's down before it went, and the sim's restart before.
        o.logged(c, 2, LifecycleEvent::Down, 0);
        o.logged(Role::Sim, 0, LifecycleEvent::Restarted, 3);
        assert_eq!(
            o.take_others(),
            [
                (c, 2, LifecycleEvent::Restarted, 1),
                (Role::Sim, 0, LifecycleEvent::Down, 3)
            ]
        );
        assert!(o.take_others().is_empty(), "taken once");
    }

    #[test]
    fn lost_comes_after_its_down_and_restarted_after_the_down_before_it() {
        let seq = [
            (LifecycleEvent::Restarted, 0),
            (LifecycleEvent::Down, 0),
            (LifecycleEvent::Restarted, 1),
            (LifecycleEvent::Down, 1),
            (LifecycleEvent::Lost, 1),
        ];
        let ords: Vec<_> = seq.iter().map(|&(e, k)| ordinal(e, k).unwrap()).collect();
        assert!(ords.windows(2).all(|w| w[0] < w[1]), "{ords:?}");
    }
}
