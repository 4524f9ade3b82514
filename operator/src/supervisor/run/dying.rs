//! Processes the supervisor itself SIGKILLed (a planned fault, a hung process), told `Down`
//! as soon as they can no longer act instead of once the kernel has torn them down.
//!
//! Why: a supervisor that learns of a death from the child's exit descriptor can say `Down`
//! only after the kernel's teardown (the address space and every shared memory mapping
//! unmapped), and in a chaos mix where three processes die at the same moment that took up
//! to 30 ms, three times the 10 ms aim (`docs/explanation/chaos.md`). What the process's
//! peers need to know is that it will not publish, write its log or drive its robot again.
//! For a SIGKILL the supervisor sent, that is certain as soon as every thread of the target
//! has entered the kernel's exit ([`proc_stat::exiting`]): the watch looks at each such
//! process every [`POLL`] until then (or until it is reaped), and tells `Down` at that point.
//! The reap later journals the exit and decides the restart as before, without telling
//! `Down` twice ([`Slots::told_down`]).
//!
//! A death the supervisor did not cause (a crash, `hnav kill` from another process, the OOM
//! killer) is told at the reap, as before: nothing says in advance that it is coming.

use std::time::{Duration, Instant};

use super::action::{Action, Incarnation};
use super::slots::Slots;
use crate::supervisor::proc_stat;

/// How often a killed process is looked at until it is exiting: a few reads of `/proc` per
/// poll, for the millisecond or so the kernel takes to stop every thread. iceoryx2's
/// `WaitSet` rounds a timeout up to the next millisecond (its epoll reactor), so in practice
/// a look comes every millisecond at most.
const POLL: Duration = Duration::from_micros(250);

/// The incarnations SIGKILLed by the supervisor and not yet told `Down`, in the order they
/// were killed.
#[derive(Debug, Default)]
pub(super) struct Dying {
    pending: Vec<Incarnation>,
}

impl Dying {
    /// The supervisor has just sent SIGKILL to `target`.
    pub(super) fn killed(&mut self, target: Incarnation) {
        if !self.pending.contains(&target) {
            self.pending.push(target);
        }
    }

    /// When to look again (none: no killed process waits to be told).
    pub(super) fn next_look(&self, now: Instant) -> Option<Instant> {
        (!self.pending.is_empty()).then(|| now + POLL)
    }

    /// `Down` for each killed process every thread of which is now exiting. One reaped
    /// meanwhile (or already told) is dropped: the reap told it.
    pub(super) fn check(&mut self, slots: &mut Slots) -> Vec<Action> {
        self.told(slots, proc_stat::exiting)
    }

    /// [`Self::check`] with `exiting` asked of each pid.
    fn told(&mut self, slots: &mut Slots, exiting: impl Fn(u32) -> bool) -> Vec<Action> {
        let mut todo = Vec::new();
        self.pending.retain(|&target| {
            if !slots.may_tell_down(target) {
                return false;
            }
            if !exiting(target.pid) {
                return true;
            }
            todo.extend(slots.told_down(target));
            false
        });
        todo
    }
}

#[cfg(test)]
mod tests {
    use std::os::unix::fs::PermissionsExt;
    use std::path::Path;

    use super::*;
    use hnav_runtime::launch::ProcessArgs;
    use hnav_runtime::msg::{Lifecycle, LifecycleEvent, Role, RosterState};
    use hnav_runtime::scenario::Scenario;

    /// The demo's slots, every process a shell that sleeps (`bin` holds them; a dropped
    /// slot's child is killed and reaped).
    fn sleeping_slots(tmp: &Path) -> Slots {
        let bin = tmp.join("bin");
        std::fs::create_dir_all(&bin).unwrap();
        for role in ["sim", "coordinator", "agent"] {
            let program = bin.join(format!("hnav-{role}"));
            std::fs::write(&program, "#!/bin/sh\nexec sleep 60\n").unwrap();
            std::fs::set_permissions(&program, std::fs::Permissions::from_mode(0o755)).unwrap();
        }
        let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/demo.toml");
        let args = ProcessArgs::new("dying", &demo);
        let scenario = Scenario::load(demo).unwrap();
        Slots::new(&args, &bin, &scenario, tmp, None, None, None)
    }

    /// The lifecycle messages among `todo`.
    fn told(todo: &[Action]) -> Vec<Lifecycle> {
        (todo.iter())
            .filter_map(|a| match a {
                Action::Publish(l) => Some(*l),
                _ => None,
            })
            .collect()
    }

    /// The roster the slots give a coordinator restarted and up.
    fn coordinator_restarted(slots: &mut Slots) -> Vec<Lifecycle> {
        slots.respawn(Role::Coordinator, 0).unwrap();
        let todo = slots.on_up(&[(Role::Coordinator as u8, 0)]);
        (told(&todo).into_iter())
            .filter(|l| is(l, LifecycleEvent::Roster))
            .collect()
    }

    fn is(l: &Lifecycle, event: LifecycleEvent) -> bool {
        l.event == event as u8
    }

    #[test]
    fn a_killed_process_is_told_down_once_when_exiting_and_not_again_at_its_reap() {
        let tmp = tempfile::tempdir().unwrap();
        let mut slots = sleeping_slots(tmp.path());
        slots.spawn_all(None).unwrap();
        let child = slots.child(Role::Agent, 2).unwrap();
        let target = Incarnation {
            role: Role::Agent,
            index: 2,
            pid: child.pid(),
        };
        child
            .signal(crate::supervisor::child::Signal::SIGKILL)
            .unwrap();
        let mut dying = Dying::default();
        dying.killed(target);
        dying.killed(target);

        // Not exiting yet: nothing told, looked at again soon.
        assert!(dying.told(&mut slots, |_| false).is_empty());
        let now = Instant::now();
        assert_eq!(dying.next_look(now), Some(now + POLL));

        // Exiting: one `Down`, and the roster says so before the reap.
        let todo = dying.told(&mut slots, |_| true);
        let down = told(&todo);
        assert_eq!(down.len(), 1, "{down:?}");
        assert!(is(&down[0], LifecycleEvent::Down) && down[0].index == 2);
        assert_eq!(dying.next_look(now), None);

        // The reap journals the exit and schedules the restart, without a second `Down`.
        let deadline = Instant::now() + Duration::from_secs(10);
        let reaped = loop {
            let reaped = slots.reap_and_restart();
            if reaped.todo.iter().any(|a| matches!(a, Action::Journal(_))) {
                break reaped;
            }
            assert!(
                Instant::now() < deadline,
                "the killed agent not reaped in 10 s"
            );
            std::thread::sleep(Duration::from_millis(5));
        };
        let again = told(&reaped.todo);
        assert!(
            !again.iter().any(|l| is(l, LifecycleEvent::Down)),
            "Down told twice: {again:?}"
        );

        // Another kill of the next incarnation is told again; the roster meanwhile says down.
        let restarted = slots.respawn(Role::Agent, 2).unwrap();
        assert!(restarted.is_some());
        let roster = coordinator_restarted(&mut slots);
        let agent2 = roster.iter().find(|l| l.index == 2).unwrap();
        assert_eq!(
            agent2.reason,
            RosterState::Down as u8,
            "restarting, not up yet"
        );
        let pid = slots.child(Role::Agent, 2).unwrap().pid();
        assert_ne!(pid, target.pid);
        let next = Incarnation { pid, ..target };
        assert!(slots.may_tell_down(next));
        assert!(!slots.may_tell_down(target), "the reaped incarnation");
    }

    #[test]
    fn a_process_told_down_is_down_in_the_roster_until_reaped() {
        let tmp = tempfile::tempdir().unwrap();
        let mut slots = sleeping_slots(tmp.path());
        slots.spawn_all(None).unwrap();
        let pid = slots.child(Role::Agent, 4).unwrap().pid();
        let target = Incarnation {
            role: Role::Agent,
            index: 4,
            pid,
        };
        // Told down as if exiting (the process itself runs on: the roster is all we look at).
        assert_eq!(slots.told_down(target).len(), 1);
        assert!(slots.told_down(target).is_empty(), "told once");
        let roster = coordinator_restarted(&mut slots);
        let states: Vec<_> = roster.iter().map(|l| (l.index, l.reason)).collect();
        let up = RosterState::Up as u8;
        let down = RosterState::Down as u8;
        assert_eq!(
            states,
            [(0, up), (1, up), (2, up), (3, up), (4, down), (5, up)]
        );
    }
}
