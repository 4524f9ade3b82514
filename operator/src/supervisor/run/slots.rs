//! The run's processes, one slot per role and index: how each is started, its entry in the
//! run registry, and its restarts under its role's policy.

use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::time::Instant;

use super::error::RunError;
use super::host::{processes_of, HostPart};
use crate::supervisor::child::{Child, ChildError, ChildSpec, ExitInfo};
use crate::supervisor::events::{RunEvent, RunEvents};
use crate::supervisor::registry::RunRecord;
use crate::supervisor::restart::{GiveUpReason, RestartDecision, RestartTracker};
use crate::supervisor::startup::SupervisorPorts;
use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::msg::{Lifecycle, LifecycleEvent, Role, RosterState};
use hnav_runtime::scenario::{GiveUpAction, RestartPolicy, RestartRule, Scenario};
use hnav_runtime::transport::{Bell, Transport, BELL_ENV};

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
    /// Gone for good (not restarted): why, in words.
    lost: Option<String>,
}

/// Every process of the run: the sim, the coordinator (or its replicas, index = Raft id) and
/// one agent per robot, in that order.
pub(super) struct Slots {
    slots: Vec<Slot>,
    /// The run directory, named when a process stops on a full disk.
    dir: PathBuf,
    /// `DIR/events.jsonl`: exits, respawns, `Up`s and the faults' signals.
    events: RunEvents,
    /// What an agent gone for good does to the run.
    on_give_up: GiveUpAction,
    /// In a run across hosts, this host's part.
    host: Option<HostPart>,
}

impl Slots {
    /// The slots of `scenario`'s processes, started from `bin_dir` with `args` (and agents
    /// with their `--index`), each one's output appended to `dir/logs/<node>.log`; the
    /// coordinator and the agents are handed the commit `bell`, if any. In a run across hosts
    /// (`host`), only this host's processes, and its bridge first. Nothing is spawned yet.
    pub(super) fn new(
        args: &ProcessArgs,
        bin_dir: &Path,
        scenario: &Scenario,
        dir: &Path,
        bell: Option<&Bell>,
        host: Option<&HostPart>,
    ) -> Self {
        let mut slots = Vec::with_capacity(3 + scenario.agents.len());
        let runs_here = |role, index| host.is_none_or(|h| h.this().runs(role, index));
        let mut add = |role: Role, index: u32| {
            let rule = match role {
                Role::Sim => scenario.restart.sim,
                Role::Coordinator => scenario.restart.coordinator,
                Role::Agent => scenario.restart.agent,
                // A host without its bridge is cut off: restart it whatever the processes'
                // rules say.
                Role::Bridge => RestartRule::with_policy(RestartPolicy::OnFailure),
            };
            let log = dir
                .join("logs")
                .join(format!("{}.log", role.node_name(index)));
            let program = bin_dir.join(format!("hnav-{}", role.name()));
            let mut spec = ChildSpec::new(role, index, program, log);
            if let (Role::Bridge, Some(h)) = (role, host) {
                spec = h.bridge_args(spec, &args.run, scenario);
            } else {
                for a in args.to_args() {
                    spec = spec.arg(a);
                }
            }
            if role == Role::Agent {
                spec = spec.arg("--index").arg(index.to_string());
            }
            if role == Role::Coordinator && index > 0 {
                spec = spec.arg("--replica").arg(index.to_string());
            }
            if let Some(bell) = bell.filter(|_| matches!(role, Role::Coordinator | Role::Agent)) {
                spec = spec.env(BELL_ENV, bell.env_value());
            }
            slots.push(Slot {
                spec,
                child: None,
                tracker: RestartTracker::new(rule),
                restart_at: None,
                announce: Cell::new(false),
                lost: None,
            });
        };
        let bridge = host.map(|h| (Role::Bridge, h.index() as u32));
        let local = processes_of(scenario).filter(|&(role, index)| runs_here(role, index));
        for (role, index) in bridge.into_iter().chain(local) {
            add(role, index);
        }
        Self {
            slots,
            dir: dir.to_path_buf(),
            events: RunEvents::create(dir),
            on_give_up: scenario.restart.on_give_up,
            host: host.cloned(),
        }
    }

    /// In a run across hosts, this host's part.
    pub(super) fn host(&self) -> Option<&HostPart> {
        self.host.as_ref()
    }

    /// The run's event journal.
    pub(super) fn events(&self) -> &RunEvents {
        &self.events
    }

    /// Starts every process of `role` (every process: `None`) not started yet.
    pub(super) fn spawn_all(&mut self, role: Option<Role>) -> Result<(), ChildError> {
        for s in &mut self.slots {
            if s.child.is_none() && role.is_none_or(|r| r == s.spec.role) {
                s.child = Some(Child::spawn(&s.spec)?);
            }
        }
        Ok(())
    }

    /// The processes that are running (or dead and not yet reaped).
    pub(super) fn children(&self) -> impl Iterator<Item = &Child> {
        self.slots.iter().filter_map(|s| s.child.as_ref())
    }

    /// Role, index and pid of every process that is up: running, and announced up again if
    /// it was restarted (what the hang watch holds deadlines for).
    pub(super) fn up(&self) -> impl Iterator<Item = (Role, u32, u32)> + '_ {
        self.slots
            .iter()
            .filter(|s| !s.announce.get())
            .filter_map(|s| Some((s.spec.role, s.spec.index, s.child.as_ref()?.pid())))
    }

    /// The current incarnation of `role`/`index`, if it runs.
    pub(super) fn child(&self, role: Role, index: u32) -> Option<&Child> {
        self.slots
            .iter()
            .find(|s| s.spec.role == role && s.spec.index == index)
            .and_then(|s| s.child.as_ref())
    }

    /// Whether the incarnation `pid` of `role`/`index` is over for good or replaced: it was
    /// reaped, and it is either not restarted or its successor is up and announced.
    pub(super) fn settled(&self, role: Role, index: u32, pid: u32) -> bool {
        self.slots
            .iter()
            .find(|s| s.spec.role == role && s.spec.index == index)
            .is_none_or(|s| match &s.child {
                Some(c) => c.pid() != pid && !s.announce.get(),
                None => s.restart_at.is_none(),
            })
    }

    /// Whether an agent runs or is due to be restarted.
    fn any_agent_left(&self) -> bool {
        self.slots
            .iter()
            .any(|s| s.spec.role == Role::Agent && (s.child.is_some() || s.restart_at.is_some()))
    }

    /// The agents gone for good and why, by index.
    pub(super) fn lost_agents(&self) -> Vec<(u32, String)> {
        self.slots
            .iter()
            .filter(|s| s.spec.role == Role::Agent)
            .filter_map(|s| s.lost.clone().map(|why| (s.spec.index, why)))
            .collect()
    }

    /// Tells every process what state each agent is in now (`Roster`), for a sim or a
    /// coordinator that was down and missed their events.
    fn publish_roster(&self, life: &SupervisorPorts) -> Result<(), RunError> {
        for s in self.slots.iter().filter(|s| s.spec.role == Role::Agent) {
            let restarts = s.tracker.restarts();
            let (state, restarts) = match (&s.child, s.lost.is_some()) {
                (_, true) => (RosterState::Lost, restarts),
                (Some(_), false) if !s.announce.get() => (RosterState::Up, restarts),
                // Dead, waiting for its restart, or restarted and not up yet: the restart
                // already counted is still to be announced.
                _ => (RosterState::Down, restarts.saturating_sub(1)),
            };
            life.publish(Lifecycle::roster(s.spec.index, state, restarts))?;
        }
        Ok(())
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
        // In a run across hosts, the other hosts' processes too: `hnav ps` shows the run.
        if let Some(h) = &self.host {
            for (role, index, host) in h.remote() {
                record.set_remote(role, index, host);
            }
        }
        if let Err(e) = record.write() {
            tracing::warn!("run registry entry not written: {e}");
        }
    }

    /// Reaps exited children, tells the others (`Down`), and restarts what is due. Returns
    /// why the run cannot go on, if it cannot: the sim or the coordinator is down and not
    /// restarted, coordinator replicas are lost until no majority is left, or no agent is
    /// left. A child that stopped on a full disk ends the run instead: [`RunError::NoSpace`].
    pub(super) fn reap_and_restart(
        &mut self,
        transport: &Transport,
        life: &SupervisorPorts,
    ) -> Result<Option<String>, RunError> {
        let mut died = false;
        // The sim or the coordinator gone for good ends the run; a replica only once no
        // majority is left (Raft's cluster goes on without a minority); an agent only if it
        // was the last one.
        let (mut core_gone, mut replica_gone, mut agent_gone) = (None, None, None);
        for s in &mut self.slots {
            let Some(exit) = s.child.as_ref().and_then(|c| c.try_reap()) else {
                continue;
            };
            died = true;
            let pid = s.child.take().map_or(0, |c| c.pid());
            let (role, index) = (s.spec.role, s.spec.index);
            tracing::warn!(node = role.node_name(index), %exit, "process exited");
            self.events.record(RunEvent::Exited {
                node: role.node_name(index),
                pid,
                how: exit.to_string(),
            });
            life.publish(Lifecycle::down(role, index, s.tracker.restarts()))?;
            match s.tracker.on_exit(&exit) {
                RestartDecision::Restart { after } => s.restart_at = Some(Instant::now() + after),
                RestartDecision::GiveUp(GiveUpReason::NoSpace) => {
                    return Err(RunError::NoSpace {
                        node: role.node_name(index),
                        writes: role_writes(role, index, &self.dir),
                    })
                }
                RestartDecision::GiveUp(why) => {
                    tracing::warn!(node = role.node_name(index), %why, "not restarted");
                    life.publish(Lifecycle::lost(role, index, s.tracker.restarts()))?;
                    let ended = not_restarted(role, index, &exit, why);
                    let replica = role == Role::Coordinator && index > 0;
                    let gone = if replica {
                        format!("{ended}: the cluster goes on while a majority of it is left")
                    } else {
                        format!("{ended}: the run cannot go on")
                    };
                    self.events.record(RunEvent::GaveUp {
                        node: role.node_name(index),
                        why: gone.clone(),
                    });
                    match role {
                        Role::Agent if self.on_give_up == GiveUpAction::Stop => {
                            core_gone = Some(format!(
                                "{ended}, and [restart] on_give_up = \"stop\" ends the run"
                            ));
                        }
                        Role::Agent => agent_gone = Some(gone),
                        Role::Coordinator if replica => replica_gone = Some(ended.clone()),
                        Role::Sim | Role::Coordinator | Role::Bridge => core_gone = Some(gone),
                    }
                    s.lost = Some(ended);
                }
            }
        }
        if died {
            // Removing the dead nodes' resources wakes their peers with "peer dead".
            if let Err(e) = transport.cleanup_dead_nodes() {
                tracing::warn!("dead-node clean-up failed: {e}");
            }
        }
        if core_gone.is_some() {
            return Ok(core_gone);
        }
        if let Some(gone) = replica_gone.filter(|_| !self.replica_majority_left()) {
            return Ok(Some(format!(
                "no majority of the coordinator replicas is left; the last lost: {gone}"
            )));
        }
        if let Some(gone) = agent_gone.filter(|_| !self.any_agent_left()) {
            return Ok(Some(format!("no agent is left; the last: {gone}")));
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
                self.events.record(RunEvent::Spawned {
                    node: spec.role.node_name(spec.index),
                    pid: child.pid(),
                    restarts: s.tracker.restarts(),
                });
                s.child = Some(child);
                s.announce.set(true);
            }
        }
        Ok(None)
    }

    /// Whether more than half of the coordinator replicas are not lost for good (running, or
    /// to be restarted): Raft can still commit. True for a single coordinator.
    fn replica_majority_left(&self) -> bool {
        let replicas = self
            .slots
            .iter()
            .filter(|s| s.spec.role == Role::Coordinator && s.spec.index > 0);
        let (total, left) = replicas.fold((0, 0), |(t, l), s| {
            (t + 1, l + usize::from(s.lost.is_none()))
        });
        total == 0 || 2 * left > total
    }

    /// Publishes `Restarted` for every restarted process that has announced itself up;
    /// returns the periods of the sim's `Hold`s among what came in on `ready`.
    pub(super) fn announce_restarts(&self, life: &SupervisorPorts) -> Result<Vec<u64>, RunError> {
        let ready = life.ready();
        let mut up = Vec::new();
        let mut holds = Vec::new();
        ready.drain_pending(|l| match LifecycleEvent::from_u8(l.event) {
            Some(LifecycleEvent::Up) => up.push((l.role, l.index)),
            Some(LifecycleEvent::Hold) => holds.push(l.period()),
            // A start-up phase report is not yet the process being up.
            _ => {}
        })?;
        for (role, index) in up {
            let slot = self
                .slots
                .iter()
                .find(|s| s.announce.get() && s.spec.role as u8 == role && s.spec.index == index);
            if let Some(s) = slot {
                s.announce.set(false);
                self.events.record(RunEvent::Up {
                    node: s.spec.role.node_name(s.spec.index),
                    pid: s.child.as_ref().map_or(0, |c| c.pid()),
                });
                life.publish(Lifecycle::restarted(
                    s.spec.role,
                    s.spec.index,
                    s.tracker.restarts(),
                ))?;
                if s.spec.role != Role::Agent {
                    self.publish_roster(life)?;
                }
            }
        }
        Ok(holds)
    }
}

/// That `role`/`index` ended with `exit` and is not restarted for `why`, in words.
fn not_restarted(role: Role, index: u32, exit: &ExitInfo, why: GiveUpReason) -> String {
    let who = match role {
        Role::Agent => format!("hnav-agent {index}"),
        other => format!("hnav-{}", other.name()),
    };
    format!("{who} ended ({exit}) and is not restarted ({why})")
}

/// What a process of `role` writes in the run directory `dir`, for the message of a run that
/// ended on a full disk.
fn role_writes(role: Role, index: u32, dir: &Path) -> String {
    let log = dir
        .join("logs")
        .join(format!("{}.log", role.node_name(index)));
    match role {
        Role::Coordinator if index > 0 => format!(
            "its replica's consensus log in {}",
            dir.join("log").join(index.to_string()).display()
        ),
        Role::Coordinator => format!("the consensus log in {}", dir.join("log").display()),
        Role::Agent => format!(
            "its checkpoint {} or its log {}",
            dir.join("agents").join(format!("{index}.ckpt")).display(),
            log.display()
        ),
        Role::Sim => format!(
            "its checkpoint {} or its log {}",
            dir.join("sim.ckpt.{0,1}").display(),
            log.display()
        ),
        Role::Bridge => format!("its log {}", log.display()),
    }
}
