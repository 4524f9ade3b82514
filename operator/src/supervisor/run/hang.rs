//! Hang detection, the supervisor's half (the processes' half is [`hnav_runtime::health`]).
//!
//! Every process that is up has a deadline: its last beat (or the moment it came up, or the
//! supervisor's last pause, whichever is latest) plus its role's hang deadline
//! ([`Scenario::hang_deadline`]). The earliest of them bounds the watch's wait, so nothing is
//! polled: the supervisor wakes at that deadline, reads each process's latest beat (one depth-1
//! buffer per publisher on the `heartbeat` topic) and, if the process is still silent, declares
//! it hung: a `hung` event in `events.jsonl`, a warning, SIGKILL (actions the watch carries
//! out, see [`super::action`]). Its exit then takes the ordinary path (reaped, `Down`, restarted under its role's policy, or the run cannot go on).
//!
//! A process is watched from the moment it is up: a first start from `Start` (before it, the
//! start-up timeout bounds it). A restarted process is watched from its spawn: until its `Up`
//! its deadline is the start-up timeout (or its role's hang deadline, if longer), since it
//! may be loading a large map or reading a long log; from its `Up` on, its role's. Before,
//! a restart that hung before its `Up` was watched by nobody, and a lockstep run waited for
//! it for ever. Beats carry their own
//! `CLOCK_MONOTONIC` time, so a supervisor that was itself paused (Ctrl-Z then `fg`, or
//! SIGSTOP) judges its children by when they beat, not by when it read the beats. When its
//! children were paused with it, their beats are as old as the pause; so when the supervisor
//! comes back to a check much later than it expected to ([`PauseDetector`]), every process
//! gets a fresh deadline from that moment instead of being killed for the supervisor's own
//! absence. The pause may fall anywhere in the supervisor's loop, in its wait or between two
//! checks (reaping, restarting, printing): what counts is the time from one check to the next
//! against the time the supervisor meant to be away.

use std::time::{Duration, Instant};

use super::action::{Action, Incarnation, Shot, Why};
use super::slots::Slots;
use crate::supervisor::child::Signal;
use crate::supervisor::events::RunEvent;
use hnav_runtime::clock::monotonic_ns;
use hnav_runtime::msg::{Heartbeat, Role, MAX_REPLICAS};
use hnav_runtime::scenario::Scenario;
use hnav_runtime::topics;
use hnav_runtime::transport::{Receiver, Transport, TransportError};

/// The first agent's entry: after the sim and every possible coordinator (index 0 for a single
/// one, 1 to [`MAX_REPLICAS`] for replicas).
const AGENTS_FROM: usize = 2 + MAX_REPLICAS as usize;

/// What the watch knows of one incarnation of a process.
#[derive(Debug, Clone, Copy)]
struct Watched {
    pid: u32,
    /// When its silence is counted from, `CLOCK_MONOTONIC` ns: its last beat, when it came
    /// up, or the supervisor's last pause.
    since_ns: u64,
    /// Declared hung and SIGKILLed; its exit is on its way.
    declared: bool,
    /// It has announced its `Up` (or is a first start); a restart has not yet.
    up: bool,
}

/// The hang deadlines of a run's processes.
pub(super) struct HangWatch {
    beats: Receiver<Heartbeat>,
    /// Per role: sim, coordinator, agent.
    deadline: [Duration; 3],
    /// A restarted process's deadline until its `Up`: the start-up timeout.
    startup: Duration,
    /// One entry per process, in the slots' order: sim, coordinator, agent 0, 1, ...
    nodes: Vec<Option<Watched>>,
    /// Tells when the supervisor itself was away (paused or starved).
    pause: PauseDetector,
}

/// Tells when the supervisor was away far longer than it meant to be between two hang checks.
///
/// After each check the supervisor is expected back at once; a wait raises that to the
/// instant it was asked to end by. Coming back more than `slack` after the expected instant
/// means the supervisor was paused (SIGSTOP) or starved, wherever in its loop that happened.
/// Counting a slow restart as a pause only postpones hang deadlines, never kills anyone.
#[derive(Debug, Clone, Copy)]
struct PauseDetector {
    /// How much later than expected the supervisor may come back before it counts itself
    /// as paused: half the shortest hang deadline.
    slack: Duration,
    /// The instant the supervisor expects to be back at its next check by.
    back_by: Option<Instant>,
}

impl PauseDetector {
    fn new(slack: Duration) -> Self {
        Self {
            slack,
            back_by: None,
        }
    }

    /// A check happens at `now`: whether the supervisor was away (by more than the slack)
    /// since it last expected to be back. The next check is expected at once from `now`.
    fn check_at(&mut self, now: Instant) -> Option<Duration> {
        let late = self
            .back_by
            .map(|b| now.saturating_duration_since(b))
            .filter(|late| *late > self.slack);
        self.back_by = Some(now);
        late
    }

    /// The supervisor is about to wait until `until`: it is expected back by then.
    fn wait_until(&mut self, until: Instant) {
        self.back_by = Some(self.back_by.map_or(until, |b| b.max(until)));
    }
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
            startup: scenario.startup_timeout(),
            nodes: vec![None; AGENTS_FROM + n],
            pause: PauseDetector::new(shortest / 2),
        })
    }

    /// Follows the set of processes that are up or restarting: a new incarnation is watched
    /// from now, a restart that came up is watched afresh from now under its role's
    /// deadline, one that is gone is forgotten.
    pub(super) fn follow(&mut self, slots: &Slots) {
        let now = monotonic_ns();
        let mut seen = vec![false; self.nodes.len()];
        let up = slots.up().map(|p| (p, true));
        let starting = slots.starting().map(|p| (p, false));
        for ((role, index, pid), is_up) in up.chain(starting) {
            let Some(k) = self.slot_of(role, index) else {
                continue;
            };
            seen[k] = true;
            let node = &mut self.nodes[k];
            match node {
                Some(w) if w.pid == pid && w.up == is_up => {}
                Some(w) if w.pid == pid => {
                    w.up = true;
                    w.since_ns = w.since_ns.max(now);
                }
                _ => {
                    *node = Some(Watched {
                        pid,
                        since_ns: now,
                        declared: false,
                        up: is_up,
                    })
                }
            }
        }
        for (node, seen) in self.nodes.iter_mut().zip(seen) {
            if !seen {
                *node = None;
            }
        }
    }

    /// Reads the latest beats and declares every process silent past its deadline hung:
    /// returns the journal line and SIGKILL of each (`round` is the last committed round, for
    /// the journal) and the next deadline, if any process is still watched.
    pub(super) fn check(
        &mut self,
        round: u64,
    ) -> Result<(Vec<Action>, Option<Instant>), TransportError> {
        self.take_beats()?;
        let now = Instant::now();
        if let Some(late) = self.pause.check_at(now) {
            self.restart_deadlines(late);
        }
        let now_ns = monotonic_ns();
        let mut next: Option<Instant> = None;
        let mut todo = Vec::new();
        for k in 0..self.nodes.len() {
            let Some(w) = self.nodes[k].filter(|w| !w.declared) else {
                continue;
            };
            let (role, index) = Self::node_of(k);
            let hang = match self.deadline[Self::role_slot(role)] {
                d if w.up => d,
                d => d.max(self.startup),
            };
            let silent = Duration::from_nanos(now_ns.saturating_sub(w.since_ns));
            if silent <= hang {
                let due = now + hang.saturating_sub(silent);
                next = Some(next.map_or(due, |n| n.min(due)));
                continue;
            }
            let target = Incarnation {
                role,
                index,
                pid: w.pid,
            };
            todo.extend(declare(target, silent, hang, round));
            if let Some(w) = &mut self.nodes[k] {
                w.declared = true;
            }
        }
        Ok((todo, next))
    }

    /// Notes the instant the coming wait is asked to end by: the supervisor is expected back
    /// at its next check by then.
    pub(super) fn before_wait(&mut self, until: Instant) {
        self.pause.wait_until(until);
    }

    /// The supervisor was away `late` longer than it meant to be: every process's silence is
    /// counted afresh from now.
    fn restart_deadlines(&mut self, late: Duration) {
        tracing::warn!(
            paused_s = late.as_secs_f64(),
            "the supervisor was paused (or starved); every process gets a fresh hang deadline"
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

    fn slot_of(&self, role: Role, index: u32) -> Option<usize> {
        Self::slot_index(self.nodes.len(), role, index)
    }

    /// The entry of `role`/`index` among `len` entries: the sim, a single coordinator (index
    /// 0) or replicas 1 to [`MAX_REPLICAS`], then the agents.
    fn slot_index(len: usize, role: Role, index: u32) -> Option<usize> {
        let k = match role {
            Role::Sim => 0,
            Role::Coordinator if index <= MAX_REPLICAS => 1 + index as usize,
            Role::Coordinator | Role::Bridge => return None,
            Role::Agent => AGENTS_FROM + index as usize,
        };
        (k < len).then_some(k)
    }

    /// The process of entry `k`.
    fn node_of(k: usize) -> (Role, u32) {
        match k {
            0 => (Role::Sim, 0),
            k if k < AGENTS_FROM => (Role::Coordinator, (k - 1) as u32),
            _ => (Role::Agent, (k - AGENTS_FROM) as u32),
        }
    }

    /// The index of `role` in [`HangWatch::deadline`].
    fn role_slot(role: Role) -> usize {
        match role {
            Role::Sim => 0,
            Role::Coordinator => 1,
            // A bridge has no entry (`slot_index`), so it is never asked for.
            Role::Agent | Role::Bridge => 2,
        }
    }
}

/// Declares `target` hung after `silent` of silence (its deadline: `hang`): a journal line,
/// then SIGKILL.
fn declare(target: Incarnation, silent: Duration, hang: Duration, round: u64) -> [Action; 2] {
    let node = target.role.node_name(target.index);
    let silent_ms = silent.as_millis() as u64;
    tracing::warn!(
        node,
        pid = target.pid,
        silent_ms,
        deadline_ms = hang.as_millis() as u64,
        "process hung: no heartbeat within its deadline; killing it"
    );
    let hung = RunEvent::Hung {
        node,
        pid: target.pid,
        silent_ms,
    };
    let kill = Shot {
        target,
        signal: Signal::SIGKILL,
        why: Why::Hung,
        round,
        wait_stop: false,
    };
    [Action::Journal(hung), Action::Signal(kill)]
}

#[cfg(test)]
mod tests {
    use super::*;

    const SLACK: Duration = Duration::from_millis(500);

    #[test]
    fn a_wait_that_ends_late_is_a_pause() {
        let mut p = PauseDetector::new(SLACK);
        let t0 = Instant::now();
        assert_eq!(p.check_at(t0), None);
        p.wait_until(t0 + Duration::from_millis(100));
        assert_eq!(p.check_at(t0 + Duration::from_millis(120)), None);
        p.wait_until(t0 + Duration::from_millis(220));
        let late = p.check_at(t0 + Duration::from_millis(2220));
        assert_eq!(late, Some(Duration::from_secs(2)));
    }

    /// The CI failure of `hang.rs::a_whole_run_paused_past_the_deadline_kills_nobody`: the
    /// supervisor was stopped after a wait had ended, between two checks, and came back to a
    /// check with no late wait to tell it; it killed every child for its own absence.
    #[test]
    fn a_pause_between_two_checks_outside_any_wait_is_a_pause() {
        let mut p = PauseDetector::new(SLACK);
        let t0 = Instant::now();
        p.check_at(t0);
        p.wait_until(t0 + Duration::from_millis(100));
        // The wait ends early (a child's event), then the supervisor is stopped for 2 s
        // while it reaps and restarts, before it checks again.
        let late = p.check_at(t0 + Duration::from_millis(2050));
        assert_eq!(late, Some(Duration::from_millis(1950)));
        // Without a wait in between, too.
        let t1 = t0 + Duration::from_millis(2050);
        assert_eq!(
            p.check_at(t1 + Duration::from_secs(3)),
            Some(Duration::from_secs(3))
        );
    }

    #[test]
    fn an_early_wake_or_a_short_delay_is_not_a_pause() {
        let mut p = PauseDetector::new(SLACK);
        let t0 = Instant::now();
        p.check_at(t0);
        p.wait_until(t0 + Duration::from_secs(1));
        assert_eq!(p.check_at(t0 + Duration::from_millis(10)), None);
        assert_eq!(p.check_at(t0 + Duration::from_millis(500)), None);
    }
}
