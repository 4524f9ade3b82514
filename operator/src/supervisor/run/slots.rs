//! The run's processes, one slot per role and index: how each is started, its entry in the
//! run registry, and its restarts under its role's policy.
//!
//! The slots hold the state; what is to be done about an exit or an `Up` (journal lines,
//! lifecycle messages, respawns) they return as [`Action`]s for the watch to carry out.

use std::path::{Path, PathBuf};
use std::time::Instant;

mod gone;

use gone::{not_restarted, role_writes, Gone};

use super::action::{Action, Incarnation};
use super::error::RunError;
use super::host::{processes_of, HostPart};
use super::ros2::Ros2Options;
use crate::supervisor::child::{Child, ChildError, ChildSpec, ExitInfo};
use crate::supervisor::events::RunEvent;
use crate::supervisor::exit_fd::ExitFd;
use crate::supervisor::registry::RunRecord;
use crate::supervisor::restart::{GiveUpReason, RestartDecision, RestartTracker};
use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::msg::{Lifecycle, Role, RosterState};
use hnav_runtime::scenario::{GiveUpAction, RestartPolicy, RestartRule, Scenario};
use hnav_runtime::transport::{Bell, BELL_ENV, DOMAIN_ENV};

/// One process of the run and what the supervisor knows of it.
struct Slot {
    spec: ChildSpec,
    /// The robots an agent process hosts, from `spec.index` on (`[run] agents_per_process`);
    /// 1 for every other process.
    robots: u32,
    child: Option<Child>,
    tracker: RestartTracker,
    restart_at: Option<Instant>,
    /// Restarted, `Restarted` not yet announced: that waits until the new process is up, so
    /// that peers reacting to it (the sim resends odometry) find its ports.
    announce: bool,
    /// Gone for good (not restarted): why, in words.
    lost: Option<String>,
    /// The pid of the incarnation already told `Down` before its reap (see `dying`).
    down_told: Option<u32>,
}

impl Slot {
    /// Whether this slot is `role`/`index`: for an agent process, whether it hosts robot
    /// `index`.
    fn is(&self, role: Role, index: u32) -> bool {
        self.spec.role == role && (self.spec.index..self.spec.index + self.robots).contains(&index)
    }

    /// The robots of this slot, each as its lifecycle events name it (the slot's own index
    /// for a process that is not an agent).
    fn indices(&self) -> std::ops::Range<u32> {
        self.spec.index..self.spec.index + self.robots
    }

    /// `event` (`Lifecycle::down`, `lost` or `restarted`) of each robot of this slot.
    fn tell(&self, event: fn(Role, u32, u32) -> Lifecycle) -> impl Iterator<Item = Action> + '_ {
        let (role, restarts) = (self.spec.role, self.tracker.restarts());
        self.indices()
            .map(move |i| Action::Publish(event(role, i, restarts)))
    }

    /// Whether `target` is this slot's running, unreaped incarnation, not yet told `Down`.
    fn may_tell_down(&self, target: Incarnation) -> bool {
        self.is(target.role, target.index)
            && self.down_told != Some(target.pid)
            && (self.child.as_ref()).is_some_and(|c| c.pid() == target.pid && c.exit().is_none())
    }
}

/// Every process of the run: the sim, the coordinator (or its replicas, index = Raft id) and
/// the agent processes (one per robot, or one per `[run] agents_per_process` robots, each
/// named by its first), in that order.
pub(super) struct Slots {
    slots: Vec<Slot>,
    /// The run directory, named when a process stops on a full disk.
    dir: PathBuf,
    /// What an agent gone for good does to the run.
    on_give_up: GiveUpAction,
    /// In a run across hosts, this host's part.
    host: Option<HostPart>,
}

impl Slots {
    /// The slots of `scenario`'s processes, started from `bin_dir` with `args` (and agents
    /// with their `--index`), each one's output appended to `dir/logs/<node>.log`; the
    /// coordinator and the agents are handed the commit `bell`, if any. In a run across hosts
    /// (`host`), only this host's processes, and its bridge first. Each is told the run's
    /// iceoryx2 `domain`, if it has one. Nothing is spawned yet.
    pub(super) fn new(
        args: &ProcessArgs,
        bin_dir: &Path,
        scenario: &Scenario,
        dir: &Path,
        bell: Option<&Bell>,
        host: Option<&HostPart>,
        domain: Option<&str>,
    ) -> Self {
        let mut slots = Vec::with_capacity(3 + scenario.agents.len());
        let runs_here = |role, index| host.is_none_or(|h| h.this().runs(role, index));
        let mut add = |role: Role, index: u32, robots: u32| {
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
            if robots > 1 {
                spec = spec.arg("--count").arg(robots.to_string());
            }
            if role == Role::Coordinator && index > 0 {
                spec = spec.arg("--replica").arg(index.to_string());
            }
            if let Some(bell) = bell.filter(|_| matches!(role, Role::Coordinator | Role::Agent)) {
                spec = spec.env(BELL_ENV, bell.env_value());
            }
            if let Some(domain) = domain {
                spec = spec.env(DOMAIN_ENV, domain);
            }
            slots.push(Slot {
                spec,
                robots,
                child: None,
                tracker: RestartTracker::new(rule),
                restart_at: None,
                announce: false,
                lost: None,
                down_told: None,
            });
        };
        let bridge = host.map(|h| (Role::Bridge, h.index() as u32, 1));
        let local = processes_of(scenario).filter(|&(role, index, _)| runs_here(role, index));
        for (role, index, robots) in bridge.into_iter().chain(local) {
            add(role, index, robots);
        }
        Self {
            slots,
            dir: dir.to_path_buf(),
            on_give_up: scenario.restart.on_give_up,
            host: host.cloned(),
        }
    }

    /// Robots outside HNAV (`[sim] kind = "ros2"`): the sim's slot runs
    /// `bin_dir/hnav-ros2 --robots` instead of `hnav-sim`, joining the ROS 2 graph as `ros2`
    /// says; as the sim it keeps its role, log, restarts and faults.
    pub(super) fn with_outside_robots(mut self, bin_dir: &Path, ros2: &Ros2Options) -> Self {
        for slot in self.slots.iter_mut().filter(|s| s.spec.role == Role::Sim) {
            slot.spec.program = bin_dir.join("hnav-ros2");
            slot.spec.args.push("--robots".into());
            slot.spec
                .args
                .extend(ros2.args().into_iter().map(Into::into));
        }
        self
    }

    /// In a run across hosts, this host's part.
    pub(super) fn host(&self) -> Option<&HostPart> {
        self.host.as_ref()
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

    /// A descriptor of each child's exit of its own, for a waiter that stays attached while
    /// the slots change.
    pub(super) fn exit_fds(&self) -> std::io::Result<Vec<ExitFd>> {
        self.children().map(|c| c.exit_fd().try_clone()).collect()
    }

    /// Role, index and pid of every process that is up: running, and announced up again if
    /// it was restarted (what the hang watch holds deadlines for).
    pub(super) fn up(&self) -> impl Iterator<Item = (Role, u32, u32)> + '_ {
        self.slots
            .iter()
            .filter(|s| !s.announce)
            .filter_map(|s| Some((s.spec.role, s.spec.index, s.child.as_ref()?.pid())))
    }

    /// Role, index and pid of every restarted process that has not announced its `Up` yet
    /// (the hang watch gives it the start-up timeout).
    pub(super) fn starting(&self) -> impl Iterator<Item = (Role, u32, u32)> + '_ {
        self.slots
            .iter()
            .filter(|s| s.announce)
            .filter_map(|s| Some((s.spec.role, s.spec.index, s.child.as_ref()?.pid())))
    }

    /// The current incarnation of `role`/`index` (for an agent: the process that hosts robot
    /// `index`), if it runs.
    pub(super) fn child(&self, role: Role, index: u32) -> Option<&Child> {
        self.slots
            .iter()
            .find(|s| s.is(role, index))
            .and_then(|s| s.child.as_ref())
    }

    /// Whether `target` is the running, unreaped incarnation of its slot, not yet told
    /// `Down`.
    pub(super) fn may_tell_down(&self, target: Incarnation) -> bool {
        self.slots.iter().any(|s| s.may_tell_down(target))
    }

    /// `target`, which the supervisor SIGKILLed, can no longer act: its `Down` (one per robot
    /// of an agent process), told now rather than at its reap (which then does not tell it
    /// again). None if `target` is not the slot's running incarnation or was told already.
    pub(super) fn told_down(&mut self, target: Incarnation) -> Vec<Action> {
        let Some(s) = self.slots.iter_mut().find(|s| s.may_tell_down(target)) else {
            return Vec::new();
        };
        s.down_told = Some(target.pid);
        s.tell(Lifecycle::down).collect()
    }

    /// Whether the incarnation `pid` of `role`/`index` is over for good or replaced: it was
    /// reaped, and it is either not restarted or its successor is up and announced.
    pub(super) fn settled(&self, role: Role, index: u32, pid: u32) -> bool {
        self.slots
            .iter()
            .find(|s| s.is(role, index))
            .is_none_or(|s| match &s.child {
                Some(c) => c.pid() != pid && !s.announce,
                None => s.restart_at.is_none(),
            })
    }

    /// Whether an agent runs or is due to be restarted.
    fn any_agent_left(&self) -> bool {
        self.slots
            .iter()
            .any(|s| s.spec.role == Role::Agent && (s.child.is_some() || s.restart_at.is_some()))
    }

    /// The agents gone for good and why, by robot (every robot of a lost process).
    pub(super) fn lost_agents(&self) -> Vec<(u32, String)> {
        let agents = self.slots.iter().filter(|s| s.spec.role == Role::Agent);
        agents
            .filter_map(|s| Some(s.indices().zip(std::iter::repeat(s.lost.clone()?))))
            .flatten()
            .collect()
    }

    /// Restarts per process (by node name) of every process restarted at least once.
    pub(super) fn restarts(&self) -> std::collections::BTreeMap<String, u32> {
        self.slots
            .iter()
            .filter(|s| s.tracker.restarts() > 0)
            .map(|s| (s.spec.role.node_name(s.spec.index), s.tracker.restarts()))
            .collect()
    }

    /// What state each agent is in now (`Roster`), for a sim or a coordinator that was down
    /// and missed their events.
    fn roster(&self) -> impl Iterator<Item = Action> + '_ {
        let agents = self.slots.iter().filter(|s| s.spec.role == Role::Agent);
        agents.flat_map(|s| {
            let restarts = s.tracker.restarts();
            let (state, restarts) = match (&s.child, s.lost.is_some()) {
                (_, true) => (RosterState::Lost, restarts),
                // Told `Down` and not reaped yet: its restart is not counted yet.
                (Some(c), false) if s.down_told == Some(c.pid()) => (RosterState::Down, restarts),
                (Some(_), false) if !s.announce => (RosterState::Up, restarts),
                // Dead, waiting for its restart, or restarted and not up yet: the restart
                // already counted is still to be announced.
                _ => (RosterState::Down, restarts.saturating_sub(1)),
            };
            (s.indices()).map(move |i| Action::Publish(Lifecycle::roster(i, state, restarts)))
        })
    }

    /// The earliest pending restart.
    pub(super) fn next_restart(&self) -> Option<Instant> {
        self.slots.iter().filter_map(|s| s.restart_at).min()
    }

    /// Writes every running process's pid and restarts to the registry entry; a failed write
    /// only costs `hnav ps` its view, so it is a warning.
    pub(super) fn write_record(&self, record: &mut RunRecord) {
        for s in &self.slots {
            // Each robot of an agent process under the process's pid: `hnav ps` lists robots,
            // and `hnav kill agent:N` finds the process that hosts robot N.
            if let Some(c) = &s.child {
                for i in s.indices() {
                    record.set_process(s.spec.role, i, c.pid(), s.tracker.restarts());
                }
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

    /// Reaps exited children and restarts what is due. Returns what is to be done about it,
    /// in this order: each exit journalled and told (`Down`; `Lost` if not restarted), the
    /// dead processes' resources removed, the respawns; and whether the run goes on.
    pub(super) fn reap_and_restart(&mut self) -> Reaped {
        let mut todo = Vec::new();
        let mut gone = Gone::default();
        let mut died = false;
        for k in 0..self.slots.len() {
            let Some(exit) = self.slots[k].child.as_ref().and_then(|c| c.try_reap()) else {
                continue;
            };
            died = true;
            if let Err(full) = self.on_exit(k, exit, &mut gone, &mut todo) {
                return Reaped {
                    todo,
                    verdict: Err(full),
                };
            }
        }
        if died {
            todo.push(Action::CleanUpDead);
        }
        let verdict = self.cannot_go_on(gone);
        if verdict.is_none() {
            todo.extend(self.due_restarts());
        }
        Reaped {
            todo,
            verdict: Ok(verdict),
        }
    }

    /// Slot `k`'s child exited with `exit`: journalled, told `Down`, then restarted later or
    /// given up on (told `Lost`, noted in `gone`). One that stopped on a full disk is
    /// [`RunError::NoSpace`]: a restart would meet the same full disk.
    fn on_exit(
        &mut self,
        k: usize,
        exit: ExitInfo,
        gone: &mut Gone,
        todo: &mut Vec<Action>,
    ) -> Result<(), RunError> {
        let s = &mut self.slots[k];
        let pid = s.child.take().map_or(0, |c| c.pid());
        let (role, index) = (s.spec.role, s.spec.index);
        let node = role.node_name(index);
        tracing::warn!(node, %exit, "process exited");
        todo.push(Action::Journal(RunEvent::Exited {
            node: node.clone(),
            pid,
            how: exit.to_string(),
        }));
        if s.down_told.take() != Some(pid) {
            todo.extend(s.tell(Lifecycle::down));
        }
        let why = match s.tracker.on_exit(&exit) {
            RestartDecision::Restart { after } => {
                s.restart_at = Some(Instant::now() + after);
                return Ok(());
            }
            RestartDecision::GiveUp(GiveUpReason::NoSpace) => {
                let writes = role_writes(role, index, &self.dir);
                return Err(RunError::NoSpace { node, writes });
            }
            RestartDecision::GiveUp(why) => why,
        };
        tracing::warn!(node, %why, "not restarted");
        todo.extend(s.tell(Lifecycle::lost));
        let ended = not_restarted(role, s.indices(), &exit, why);
        let why = gone.note(role, index, &ended, self.on_give_up);
        todo.push(Action::Journal(RunEvent::GaveUp { node, why }));
        s.lost = Some(ended);
        Ok(())
    }

    /// Why the run cannot go on after the losses of one reaping (`gone`), if it cannot: the
    /// sim or the coordinator is gone for good; a replica only once no majority is left
    /// (Raft's cluster goes on without a minority); an agent only if it was the last one.
    fn cannot_go_on(&self, gone: Gone) -> Option<String> {
        if gone.core.is_some() {
            return gone.core;
        }
        if let Some(last) = gone.replica.filter(|_| !self.replica_majority_left()) {
            return Some(format!(
                "no majority of the coordinator replicas is left; the last lost: {last}"
            ));
        }
        let last = gone.agent.filter(|_| !self.any_agent_left())?;
        Some(format!("no agent is left; the last: {last}"))
    }

    /// The respawns that are due, each taken off the schedule.
    fn due_restarts(&mut self) -> Vec<Action> {
        let now = Instant::now();
        let due = self
            .slots
            .iter_mut()
            .filter(|s| s.restart_at.is_some_and(|t| t <= now));
        due.map(|s| {
            s.restart_at = None;
            Action::Respawn {
                role: s.spec.role,
                index: s.spec.index,
            }
        })
        .collect()
    }

    /// Starts `role`/`index` again with `--resume`; its `Restarted` waits for its `Up`.
    /// Returns the journal's line for it (none: the run has no such process).
    pub(super) fn respawn(
        &mut self,
        role: Role,
        index: u32,
    ) -> Result<Option<RunEvent>, ChildError> {
        let Some(s) = self.slots.iter_mut().find(|s| s.is(role, index)) else {
            return Ok(None);
        };
        let child = Child::spawn(&s.spec.clone().arg("--resume"))?;
        let (node, pid) = (role.node_name(s.spec.index), child.pid());
        tracing::info!(node, pid, "restarted");
        s.child = Some(child);
        s.announce = true;
        Ok(Some(RunEvent::Spawned {
            node,
            pid,
            restarts: s.tracker.restarts(),
        }))
    }

    /// Whether more than half of the coordinator replicas are not lost for good (running, or
    /// to be restarted): Raft can still commit. True for a single coordinator. A replica of
    /// another host counts as left: its own supervisor judges it.
    fn replica_majority_left(&self) -> bool {
        let replicas = self
            .slots
            .iter()
            .filter(|s| s.spec.role == Role::Coordinator && s.spec.index > 0);
        let (total, left) = replicas.fold((0, 0), |(t, l), s| {
            (t + 1, l + usize::from(s.lost.is_none()))
        });
        let remote = (self.host.iter().flat_map(HostPart::remote))
            .filter(|&(role, index, _)| role == Role::Coordinator && index > 0)
            .count();
        let (total, left) = (total + remote, left + remote);
        total == 0 || 2 * left > total
    }

    /// Restarted processes that announced themselves up (`ups`: role and index as they came
    /// in on `ready`): each journalled `Up` and announced `Restarted`, and after a sim's or a
    /// coordinator's, the agents' roster that it missed. In a run across hosts the `Up` of a
    /// sim or a coordinator of another host (its start-up `Up`s were taken by the handshake,
    /// so this one is a restart's) is answered with this host's agents' roster: each host
    /// tells the restarted process about the agents it runs, and together they name them all.
    pub(super) fn on_up(&mut self, ups: &[(u8, u32)]) -> Vec<Action> {
        let mut todo = Vec::new();
        for &(role, index) in ups {
            let announced = self
                .slots
                .iter_mut()
                .find(|s| s.announce && s.spec.role as u8 == role && s.spec.index == index);
            let Some(s) = announced else {
                if self.runs_elsewhere(role, index) {
                    todo.extend(self.roster());
                }
                continue;
            };
            s.announce = false;
            let (role, index) = (s.spec.role, s.spec.index);
            todo.push(Action::Journal(RunEvent::Up {
                node: role.node_name(index),
                pid: s.child.as_ref().map_or(0, |c| c.pid()),
            }));
            todo.extend(s.tell(Lifecycle::restarted));
            if role != Role::Agent {
                todo.extend(self.roster());
            }
        }
        todo
    }
}

impl Slots {
    /// Whether `role` (as on the wire) / `index` is a sim or a coordinator that another host
    /// of a run across hosts runs.
    fn runs_elsewhere(&self, role: u8, index: u32) -> bool {
        let Some(role) = Role::from_u8(role).filter(|r| matches!(r, Role::Sim | Role::Coordinator))
        else {
            return false;
        };
        (self.host.iter().flat_map(HostPart::remote)).any(|(r, i, _)| r == role && i == index)
    }
}

/// What one reaping found.
pub(super) struct Reaped {
    /// What to do about it, in this order.
    pub(super) todo: Vec<Action>,
    /// `Ok(Some(why))`: the run cannot go on; `Err`: a process stopped on a full disk.
    pub(super) verdict: Result<Option<String>, RunError>,
}
