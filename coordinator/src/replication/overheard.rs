//! What a following replica hears of the supervisor ([`Overheard`]): the leader logs the
//! agents' liveness meanwhile, but a replica that comes to lead must know who is live, and
//! what the leader it replaces may not have logged.

use hnav_runtime::launch::LifecyclePorts;
use hnav_runtime::msg::{LifecycleEvent, Role, RosterState, StopReason};
use hnav_runtime::transport::TransportError;

/// Per agent, the last liveness the supervisor told a following replica (roster state and
/// restarts), reconciled with the log when the replica comes to lead.
pub struct Overheard {
    heard: Vec<Option<(RosterState, u32)>>,
}

impl Overheard {
    /// Nothing heard yet of `agents` agents.
    pub fn new(agents: usize) -> Self {
        Overheard {
            heard: vec![None; agents],
        }
    }

    /// Takes in the supervisor's pending events; returns why the run stops on a `Stop`.
    pub fn hear(&mut self, life: &LifecyclePorts) -> Result<Option<StopReason>, TransportError> {
        let heard = &mut self.heard;
        life.drain_samples(|_, _, l| {
            let (Some(Role::Agent), Some(ev)) =
                (Role::from_u8(l.role), LifecycleEvent::from_u8(l.event))
            else {
                return;
            };
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

    /// What was heard, once (the replica comes to lead): `(agent, state, restarts)` for every
    /// agent the supervisor spoke of.
    pub fn take(&mut self) -> impl Iterator<Item = (u32, RosterState, u32)> {
        std::mem::take(&mut self.heard)
            .into_iter()
            .enumerate()
            .filter_map(|(i, h)| h.map(|(state, restarts)| (i as u32, state, restarts)))
    }
}
