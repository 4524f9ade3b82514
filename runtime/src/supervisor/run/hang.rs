//! Hang detection, the supervisor's half (the processes' half is [`crate::health`]).
//!
//! Every process that is up has a deadline: its last beat (or the moment it came up, or the
//! supervisor's last pause, whichever is latest) plus its role's hang deadline
//! ([`Scenario::hang_deadline`]). The earliest of them bounds the watch's wait, so nothing is
//! polled: the supervisor wakes at that deadline, reads each process's latest beat (one depth-1
//! buffer per publisher on the `heartbeat` topic) and, if the process is still silent, declares
//! it hung: a `hung` event in `events.jsonl`, a warning, SIGKILL. Its exit then takes the
//! ordinary path (reaped, `Down`, restarted under its role's policy, or the run cannot go on).
//!
//! A process is watched from the moment it is up: a first start from `Start` (before it, the
//! start-up timeout bounds it), a restart from its `Up`. Beats carry their own
//! `CLOCK_MONOTONIC` time, so a supervisor that was itself paused (Ctrl-Z then `fg`, or
//! SIGSTOP) judges its children by when they beat, not by when it read the beats. When its
//! children were paused with it, their beats are as old as the pause; so when the supervisor
//! wakes much later than it asked to ([`HangWatch::after_wait`]), every process gets a fresh
//! deadline from that moment instead of being killed for the supervisor's own absence.

use std::time::{Duration, Instant};

use super::slots::Slots;
use crate::clock::monotonic_ns;
use crate::msg::{Heartbeat, Role};
use crate::scenario::Scenario;
use crate::supervisor::child::Signal;
use crate::supervisor::events::RunEvent;
use crate::topics;
use crate::transport::{Receiver, Transport, TransportError};

/// What the watch knows of one incarnation of a process.
#[derive(Debug, Clone, Copy)]
struct Watched {
    pid: u32,
    /// When its silence is counted from, `CLOCK_MONOTONIC` ns: its last beat, when it came
    /// up, or the supervisor's last pause.
    since_ns: u64,
    /// Declared hung and SIGKILLed; its exit is on its way.
    declared: bool,
}

/// The hang deadlines of a run's processes.
pub(super) struct HangWatch {
    beats: Receiver<Heartbeat>,
    /// Per role: sim, coordinator, agent.
    deadline: [Duration; 3],
    /// One entry per process, in the slots' order: sim, coordinator, agent 0, 1, ...
    nodes: Vec<Option<Watched>>,
    /// How much later than asked a wait may return before the supervisor counts itself as
    /// paused: half the shortest hang deadline.
    pause: Duration,
    /// The instant the last wait was asked to end by.
    asked: Option<Instant>,
}

impl HangWatch {
    /// Opens the `heartbeat` topic for `scenario`'s processes; none is watched yet.
    pub(super) fn open(transport: &Transport, scenario: &Scenario) -> Result<Self, TransportError> {
        let n = scenario.agents.len();
        let deadline =
            [Role::Sim, Role::Coordinator, Role::Agent].map(|r| scenario.hang_deadline(r));
        let shortest = deadline
            .iter()
            .min()
            .copied()
            .unwrap_or(Duration::from_secs(1));
        Ok(Self {
            beats: transport.receiver(topics::HEARTBEAT, topics::heartbeat_qos(n))?,
            deadline,
            nodes: vec![None; 2 + n],
            pause: shortest / 2,
            asked: None,
        })
    }

    /// Follows the set of processes that are up: a new incarnation is watched from now, one
    /// that is gone is forgotten.
    pub(super) fn follow(&mut self, slots: &Slots) {
        let now = monotonic_ns();
        let mut up = vec![false; self.nodes.len()];
        for (role, index, pid) in slots.up() {
            let Some(k) = self.slot_of(role, index) else {
                continue;
            };
            up[k] = true;
            if self.nodes[k].is_none_or(|w| w.pid != pid) {
                self.nodes[k] = Some(Watched {
                    pid,
                    since_ns: now,
                    declared: false,
                });
            }
        }
        for (node, up) in self.nodes.iter_mut().zip(up) {
            if !up {
                *node = None;
            }
        }
    }

    /// Reads the latest beats, declares every process silent past its deadline hung
    /// (SIGKILL; `round` is the last committed round, for the journal) and returns the next
    /// deadline, if any process is watched.
    pub(super) fn check(
        &mut self,
        slots: &Slots,
        round: u64,
    ) -> Result<Option<Instant>, TransportError> {
        self.take_beats()?;
        let now_ns = monotonic_ns();
        let now = Instant::now();
        let mut next: Option<Instant> = None;
        for k in 0..self.nodes.len() {
            let Some(w) = self.nodes[k].filter(|w| !w.declared) else {
                continue;
            };
            let (role, index) = Self::node_of(k);
            let hang = self.deadline[Self::role_slot(role)];
            let silent = Duration::from_nanos(now_ns.saturating_sub(w.since_ns));
            if silent <= hang {
                let due = now + hang.saturating_sub(silent);
                next = Some(next.map_or(due, |n| n.min(due)));
                continue;
            }
            self.declare(slots, role, index, w.pid, silent, hang, round);
            if let Some(w) = &mut self.nodes[k] {
                w.declared = true;
            }
        }
        Ok(next)
    }

    /// Notes the instant the coming wait is asked to end by.
    pub(super) fn before_wait(&mut self, until: Instant) {
        self.asked = Some(until);
    }

    /// After a wait: if it ended much later than asked, the supervisor itself was paused (or
    /// starved), and every process's silence is counted afresh from now.
    pub(super) fn after_wait(&mut self) {
        let Some(asked) = self.asked.take() else {
            return;
        };
        let late = Instant::now().saturating_duration_since(asked);
        if late <= self.pause {
            return;
        }
        tracing::warn!(
            paused_s = late.as_secs_f64(),
            "the supervisor was paused; every process gets a fresh hang deadline"
        );
        let now = monotonic_ns();
        for w in self.nodes.iter_mut().flatten() {
            w.since_ns = w.since_ns.max(now);
        }
    }

    /// Folds every pending beat of a watched incarnation into its `since_ns`.
    fn take_beats(&mut self) -> Result<(), TransportError> {
        let nodes = &mut self.nodes;
        self.beats.drain(|b| {
            let Some(role) = Role::from_u8(b.role) else {
                return;
            };
            let Some(k) = Self::slot_index(nodes.len(), role, b.index) else {
                return;
            };
            if let Some(w) = nodes[k].as_mut().filter(|w| w.pid == b.pid) {
                w.since_ns = w.since_ns.max(b.t_ns);
            }
        })?;
        Ok(())
    }

    /// Declares `role`/`index` (process `pid`) hung after `silent` of silence and kills it.
    #[allow(clippy::too_many_arguments)]
    fn declare(
        &self,
        slots: &Slots,
        role: Role,
        index: u32,
        pid: u32,
        silent: Duration,
        hang: Duration,
        round: u64,
    ) {
        let node = role.node_name(index);
        let silent_ms = silent.as_millis() as u64;
        tracing::warn!(
            node,
            pid,
            silent_ms,
            deadline_ms = hang.as_millis() as u64,
            "process hung: no heartbeat within its deadline; killing it"
        );
        slots.events().record(RunEvent::Hung {
            node: node.clone(),
            pid,
            silent_ms,
        });
        let Some(child) = slots.child(role, index).filter(|c| c.pid() == pid) else {
            return;
        };
        if let Err(e) = child.signal(Signal::SIGKILL) {
            tracing::warn!(node, "hung process not killed: {e}");
            return;
        }
        slots.events().record(RunEvent::Signalled {
            node,
            pid,
            signal: Signal::SIGKILL.to_string(),
            fault: None,
            round,
        });
    }

    fn slot_of(&self, role: Role, index: u32) -> Option<usize> {
        Self::slot_index(self.nodes.len(), role, index)
    }

    /// The entry of `role`/`index` among `len` entries.
    fn slot_index(len: usize, role: Role, index: u32) -> Option<usize> {
        let k = match role {
            Role::Sim => 0,
            Role::Coordinator => 1,
            Role::Agent => 2 + index as usize,
        };
        (k < len).then_some(k)
    }

    /// The process of entry `k`.
    fn node_of(k: usize) -> (Role, u32) {
        match k {
            0 => (Role::Sim, 0),
            1 => (Role::Coordinator, 0),
            _ => (Role::Agent, (k - 2) as u32),
        }
    }

    /// The index of `role` in [`HangWatch::deadline`].
    fn role_slot(role: Role) -> usize {
        match role {
            Role::Sim => 0,
            Role::Coordinator => 1,
            Role::Agent => 2,
        }
    }
}
