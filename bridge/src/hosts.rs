//! The other hosts of a run, as a bridge hears them: each bridge declares a Zenoh liveliness
//! token `hnav/<run>/_bridge/<host>` and follows everyone else's.
//!
//! - Once every other host's token is seen, the bridge announces itself `Up` (role
//!   [`Role::Bridge`]) on its host's `ready`: its supervisor starts the host's processes only
//!   then, so that no process announces itself before the far side can hear it.
//! - A token that goes away is a host cut off (its bridge ended, or the link's lease of
//!   [`session::LEASE_MS`](crate::session::LEASE_MS) ran out): the bridge publishes `Down`
//!   for that host's agents on its own host's `lifecycle`, as the supervisor does for an
//!   agent that died. The coordinator stops waiting for them, the sim brakes their robots.
//!   When the token comes back the bridge publishes `Restarted` for them (restart count
//!   unchanged: the process never stopped), and they are waited for again from the round
//!   they rejoin in. Both go only into this host's iceoryx2: every host judges its own links.

use hnav_runtime::msg::{Lifecycle, Role};

/// Another host of the run and the agents it runs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PeerHost {
    /// Its name in the placement.
    pub name: String,
    /// The agents it runs.
    pub agents: Vec<u32>,
}

/// This host's view of the others.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Peers {
    /// This host's name.
    pub me: String,
    /// This host's place in the placement (the bridge's index in its `Up`).
    pub index: u32,
    /// Every other host.
    pub others: Vec<PeerHost>,
}

/// The liveliness key of host `name`'s bridge in run `run`.
pub(crate) fn token_key(run: &str, name: &str) -> String {
    format!("hnav/{run}/_bridge/{name}")
}

/// The key every bridge of run `run` follows.
pub(crate) fn all_tokens(run: &str) -> String {
    format!("hnav/{run}/_bridge/*")
}

/// What is known of each other host, and what it takes to say so.
pub(crate) struct HostsView {
    peers: Peers,
    /// Per other host: heard at least once, and cut off now.
    heard: Vec<bool>,
    cut: Vec<bool>,
    announced: bool,
}

impl HostsView {
    pub(crate) fn new(peers: Peers) -> Self {
        let n = peers.others.len();
        Self {
            peers,
            heard: vec![false; n],
            cut: vec![false; n],
            announced: false,
        }
    }

    /// Takes in that host `name`'s token appeared (`alive`) or went away; returns the
    /// lifecycle events to publish on this host's `lifecycle`.
    pub(crate) fn on_token(&mut self, name: &str, alive: bool) -> Vec<Lifecycle> {
        let Some(i) = self.peers.others.iter().position(|p| p.name == name) else {
            return Vec::new();
        };
        let agents = &self.peers.others[i].agents;
        match (alive, self.cut[i]) {
            (true, true) => {
                self.cut[i] = false;
                tracing::warn!(host = name, "host reachable again: its robots rejoin");
                agents
                    .iter()
                    .map(|&a| Lifecycle::restarted(Role::Agent, a, 0))
                    .collect()
            }
            (true, false) => {
                self.heard[i] = true;
                Vec::new()
            }
            (false, false) if self.heard[i] => {
                self.cut[i] = true;
                tracing::warn!(host = name, "host cut off: its robots stand");
                agents
                    .iter()
                    .map(|&a| Lifecycle::down(Role::Agent, a, 0))
                    .collect()
            }
            (false, _) => Vec::new(),
        }
    }

    /// This bridge's `Up`, once every other host has been heard; only once.
    pub(crate) fn take_up(&mut self) -> Option<Lifecycle> {
        if self.announced || !self.heard.iter().all(|&h| h) {
            return None;
        }
        self.announced = true;
        Some(Lifecycle::up(Role::Bridge, self.peers.index))
    }

    /// Whether this bridge has announced itself up.
    pub(crate) fn is_up(&self) -> bool {
        self.announced
    }

    /// The other hosts not heard yet, by name (for the log while waiting).
    pub(crate) fn unheard(&self) -> Vec<&str> {
        (self.peers.others.iter().zip(&self.heard))
            .filter(|(_, &h)| !h)
            .map(|(p, _)| p.name.as_str())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use hnav_runtime::msg::LifecycleEvent;

    use super::*;

    fn view() -> HostsView {
        HostsView::new(Peers {
            me: "base".into(),
            index: 0,
            others: vec![
                PeerHost {
                    name: "a".into(),
                    agents: vec![0, 1],
                },
                PeerHost {
                    name: "b".into(),
                    agents: vec![2],
                },
            ],
        })
    }

    #[test]
    fn up_once_every_host_is_heard_then_down_and_back_for_a_cut_host() {
        let mut v = view();
        assert!(v.on_token("a", true).is_empty());
        assert_eq!(v.take_up(), None);
        assert_eq!(v.unheard(), ["b"]);
        assert!(v.on_token("b", true).is_empty());
        let up = v.take_up().expect("every host heard");
        assert_eq!(
            (up.role, up.index, up.event),
            (Role::Bridge as u8, 0, LifecycleEvent::Up as u8)
        );
        assert_eq!(v.take_up(), None, "only once");
        let down = v.on_token("a", false);
        let got: Vec<_> = down.iter().map(|l| (l.index, l.event)).collect();
        assert_eq!(
            got,
            [
                (0, LifecycleEvent::Down as u8),
                (1, LifecycleEvent::Down as u8)
            ]
        );
        assert!(v.on_token("a", false).is_empty(), "a cut host is cut once");
        let back = v.on_token("a", true);
        let got: Vec<_> = back.iter().map(|l| (l.index, l.event)).collect();
        assert_eq!(
            got,
            [
                (0, LifecycleEvent::Restarted as u8),
                (1, LifecycleEvent::Restarted as u8)
            ]
        );
        assert!(v.on_token("nobody", false).is_empty());
    }

    #[test]
    fn a_host_never_heard_is_not_cut() {
        let mut v = view();
        assert!(v.on_token("b", false).is_empty());
    }
}
