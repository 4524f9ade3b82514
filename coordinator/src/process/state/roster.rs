//! Who the coordinator waits for ([`Roster`]): per agent, live or down, lost for good, and its
//! restarts as the supervisor counts them; the same whether heard or replayed from the log.

use hnav_runtime::consensus_log::AgentLife;
use hnav_runtime::msg::{LifecycleEvent, RosterState};

use crate::round::Arbiter;

/// Lifecycle events the log misses for one agent, in the order they are logged.
pub(super) type Missed = [Option<(LifecycleEvent, u32)>; 2];

/// The liveness of every agent of the run.
pub(super) struct Roster {
    /// Per agent: waited for in a round (not down, not lost).
    live: Vec<bool>,
    /// Per agent: gone for good (`Lost`); its robot stands for the rest of the run and its
    /// goal counts as not reached.
    lost: Vec<bool>,
    /// Per agent: its restarts so far, as the supervisor counts them.
    restarts: Vec<u32>,
}

impl Roster {
    /// `agents` agents, every one live.
    pub(super) fn new(agents: usize) -> Self {
        Roster {
            live: vec![true; agents],
            lost: vec![false; agents],
            restarts: vec![0; agents],
        }
    }

    /// What an agent's lifecycle event (heard or replayed) says of who is live: a `Down`
    /// agent is not waited for until it is back, a `Lost` one never again ([`AgentLife`]'s
    /// rule, which a snapshot's state follows too).
    pub(super) fn event(&mut self, index: u32, ev: LifecycleEvent, restarts: u32) {
        let i = index as usize;
        let (Some(live), Some(lost), Some(r)) = (
            self.live.get_mut(i),
            self.lost.get_mut(i),
            self.restarts.get_mut(i),
        ) else {
            return;
        };
        let mut life = AgentLife {
            live: *live,
            lost: *lost,
            restarts: *r,
        };
        life.event(ev, restarts);
        (*live, *lost, *r) = (life.live, life.lost, life.restarts);
    }

    /// Every agent as a snapshot's state says (a replica that starts from one).
    pub(super) fn restore(&mut self, agents: &[AgentLife]) {
        for (i, a) in agents.iter().enumerate().take(self.live.len()) {
            (self.live[i], self.lost[i], self.restarts[i]) = (a.live, a.lost, a.restarts);
        }
    }

    /// The events the log misses for agent `index` given the supervisor's roster entry
    /// (`state`, `restarts`): what happened while no coordinator listened.
    pub(super) fn missed(&self, index: u32, state: RosterState, restarts: u32) -> Missed {
        let i = index as usize;
        let mut missed: Missed = [None, None];
        let (Some(&live), Some(&lost), Some(&logged)) =
            (self.live.get(i), self.lost.get(i), self.restarts.get(i))
        else {
            return missed;
        };
        match state {
            // Up with restarts the log has not seen: it died and came back meanwhile.
            RosterState::Up if !lost && (!live || logged < restarts) => {
                if live {
                    missed[0] = Some((LifecycleEvent::Down, restarts.saturating_sub(1)));
                }
                missed[1] = Some((LifecycleEvent::Restarted, restarts));
            }
            RosterState::Down if live => missed[0] = Some((LifecycleEvent::Down, restarts)),
            RosterState::Lost if !lost => {
                if live {
                    missed[0] = Some((LifecycleEvent::Down, restarts));
                }
                missed[1] = Some((LifecycleEvent::Lost, restarts));
            }
            _ => {}
        }
        missed
    }

    /// A candidate of agent `i` came in: it is live, unless the supervisor gave it up (a
    /// sample it sent before it died).
    pub(super) fn heard_from(&mut self, i: usize) {
        self.live[i] = !self.lost[i];
    }

    /// Whether agent `i` is waited for in a round.
    pub(super) fn live(&self, i: usize) -> bool {
        self.live[i]
    }

    /// Whether agent `i` is gone for good.
    pub(super) fn lost(&self, i: usize) -> bool {
        self.lost[i]
    }

    /// Whether any agent is gone for good.
    pub(super) fn any_lost(&self) -> bool {
        self.lost.iter().any(|l| *l)
    }

    /// Agents not waited for now.
    pub(super) fn down(&self) -> usize {
        self.live.iter().filter(|l| !**l).count()
    }

    /// Agents at their goal, lost ones not counted (what the end record says).
    pub(super) fn at_goal(&self, arbiter: &Arbiter) -> u32 {
        (0..arbiter.agents())
            .filter(|&i| arbiter.agent_at_goal(i) && !self.lost[i])
            .count() as u32
    }
}
