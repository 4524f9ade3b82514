//! The run's processes, one slot per role and index: how each is started, its entry in the
//! run registry, and its restarts under its role's policy.

use std::cell::Cell;
use std::ffi::OsString;
use std::path::Path;
use std::time::Instant;

use super::error::RunError;
use crate::launch::ProcessArgs;
use crate::msg::{Lifecycle, LifecycleEvent, Role};
use crate::scenario::Scenario;
use crate::supervisor::child::{Child, ChildError, ChildSpec};
use crate::supervisor::registry::RunRecord;
use crate::supervisor::restart::{RestartDecision, RestartTracker};
use crate::supervisor::startup::SupervisorPorts;
use crate::transport::Transport;

/// One process of the run and what the supervisor knows of it.
struct Slot {
    spec: ChildSpec,
    child: Option<Child>,
    tracker: RestartTracker,
    restart_at: Option<Instant>,
    /// Restarted, `Restarted` not yet announced: that waits until the new process is up, so
    /// that peers reacting to it (the sim resends odometry) find its ports. A `Cell`, because
    /// the slots stay borrowed by the waiter's attachments on the children's exit descriptors
    /// while `Up`s are taken.
    announce: Cell<bool>,
}

/// Every process of the run: the sim, the coordinator and one agent per robot, in that order.
pub(super) struct Slots {
    slots: Vec<Slot>,
}

impl Slots {
    /// The slots of `scenario`'s processes, started from `bin_dir` with `args` (and agents
    /// with their `--index`), each one's output appended to `dir/logs/<node>.log`. Nothing
    /// is spawned yet.
    pub(super) fn new(args: &ProcessArgs, bin_dir: &Path, scenario: &Scenario, dir: &Path) -> Self {
        let mut slots = Vec::with_capacity(2 + scenario.agents.len());
        let mut add = |role: Role, index: u32, program: &str| {
            let rule = match role {
                Role::Sim => scenario.restart.sim,
                Role::Coordinator => scenario.restart.coordinator,
                Role::Agent => scenario.restart.agent,
            };
            let log = dir
                .join("logs")
                .join(format!("{}.log", role.node_name(index)));
            let mut spec = ChildSpec::new(role, index, bin_dir.join(program), log);
            let argv: Vec<OsString> = args.to_args();
            for a in argv {
                spec = spec.arg(a);
            }
            if role == Role::Agent {
                spec = spec.arg("--index").arg(index.to_string());
            }
            slots.push(Slot {
                spec,
                child: None,
                tracker: RestartTracker::new(rule),
                restart_at: None,
                announce: Cell::new(false),
            });
        };
        add(Role::Sim, 0, "hnav-sim");
        add(Role::Coordinator, 0, "hnav-coordinator");
        for i in 0..scenario.agents.len() as u32 {
            add(Role::Agent, i, "hnav-agent");
        }
        Self { slots }
    }

    /// Starts every process.
    pub(super) fn spawn_all(&mut self) -> Result<(), ChildError> {
        for s in &mut self.slots {
            s.child = Some(Child::spawn(&s.spec)?);
        }
        Ok(())
    }

    /// The processes that are running (or dead and not yet reaped).
    pub(super) fn children(&self) -> impl Iterator<Item = &Child> {
        self.slots.iter().filter_map(|s| s.child.as_ref())
    }

    /// The current incarnation of `role`/`index`, if it runs.
    pub(super) fn child(&self, role: Role, index: u32) -> Option<&Child> {
        self.slots
            .iter()
            .find(|s| s.spec.role == role && s.spec.index == index)
            .and_then(|s| s.child.as_ref())
    }

    /// The earliest pending restart.
    pub(super) fn next_restart(&self) -> Option<Instant> {
        self.slots.iter().filter_map(|s| s.restart_at).min()
    }

    /// Writes every running process's pid and restarts to the registry entry; a failed write
    /// only costs `hnav ps` its view, so it is a warning.
    pub(super) fn write_record(&self, record: &mut RunRecord) {
        for s in &self.slots {
            if let Some(c) = &s.child {
                record.set_process(s.spec.role, s.spec.index, c.pid(), s.tracker.restarts());
            }
        }
        if let Err(e) = record.write() {
            tracing::warn!("run registry entry not written: {e}");
        }
    }

    /// Reaps exited children, tells the others (`Down`), and restarts what is due.
    pub(super) fn reap_and_restart(
        &mut self,
        transport: &Transport,
        life: &SupervisorPorts,
    ) -> Result<(), RunError> {
        let mut died = false;
        for s in &mut self.slots {
            let Some(exit) = s.child.as_ref().and_then(|c| c.try_reap()) else {
                continue;
            };
            died = true;
            s.child = None;
            let (role, index) = (s.spec.role, s.spec.index);
            tracing::warn!(node = role.node_name(index), %exit, "process exited");
            life.publish(Lifecycle::down(role, index, s.tracker.restarts()))?;
            match s.tracker.on_exit(&exit) {
                RestartDecision::Restart { after } => s.restart_at = Some(Instant::now() + after),
                RestartDecision::GiveUp(why) => {
                    tracing::warn!(node = role.node_name(index), ?why, "not restarted")
                }
            }
        }
        if died {
            // Removing the dead nodes' resources wakes their peers with "peer dead".
            if let Err(e) = transport.cleanup_dead_nodes() {
                tracing::warn!("dead-node clean-up failed: {e}");
            }
        }
        let now = Instant::now();
        for s in &mut self.slots {
            if s.restart_at.is_some_and(|t| t <= now) {
                s.restart_at = None;
                let spec = s.spec.clone().arg("--resume");
                let child = Child::spawn(&spec)?;
                tracing::info!(
                    node = spec.role.node_name(spec.index),
                    pid = child.pid(),
                    "restarted"
                );
                s.child = Some(child);
                s.announce.set(true);
            }
        }
        Ok(())
    }

    /// Publishes `Restarted` for every restarted process that has announced itself up.
    pub(super) fn announce_restarts(&self, life: &SupervisorPorts) -> Result<(), RunError> {
        let ready = life.ready();
        let mut up = Vec::new();
        ready.drain_pending(|l| {
            // A start-up phase report is not yet the process being up.
            if l.event == LifecycleEvent::Up as u8 {
                up.push((l.role, l.index));
            }
        })?;
        for (role, index) in up {
            let slot = self
                .slots
                .iter()
                .find(|s| s.announce.get() && s.spec.role as u8 == role && s.spec.index == index);
            if let Some(s) = slot {
                s.announce.set(false);
                life.publish(Lifecycle::restarted(
                    s.spec.role,
                    s.spec.index,
                    s.tracker.restarts(),
                ))?;
            }
        }
        Ok(())
    }
}
