//! The state of a coordinator replica (`coordinator.replicas` 3 or 5): rebuilt from the
//! committed records of its Raft log, kept up to date with the leader's while it follows,
//! and made final by the cluster while it leads.

use std::path::Path;
use std::rc::Rc;
use std::time::Instant;

use hnav_runtime::consensus_log::EndReason;
use hnav_runtime::launch::LifecyclePorts;
use hnav_runtime::msg::{LifecycleEvent, Role, RosterState, StopReason};
use hnav_runtime::scenario::Scenario;
use hnav_runtime::transport::{Transport, Waiter, Wake};

use super::{header, State};
use crate::process::decisions::{Decisions, RaftLog};
use crate::process::CoordinatorError;
use crate::replication::RaftLink;

impl State {
    /// Replica `id`'s state: its journal in `run_dir/log/<id>` opened (or created), and the
    /// records it holds committed applied.
    pub(in crate::process) fn open_replica(
        transport: &Transport,
        scenario: &Scenario,
        run_dir: &Path,
        id: u64,
    ) -> Result<Self, CoordinatorError> {
        let raft = RaftLog::open(transport, scenario, run_dir, id, header(scenario))?;
        let mut state = State::new(scenario, run_dir, Decisions::Raft(Box::new(raft)));
        state.apply_committed();
        state.say_resumed();
        Ok(state)
    }

    fn raft(&mut self) -> Option<&mut RaftLog> {
        match &mut self.log {
            Decisions::Raft(r) => Some(r),
            Decisions::Log(_) => None,
        }
    }

    /// The Raft term of this replica, 0 for a single coordinator: what its commits carry.
    pub(in crate::process) fn term(&self) -> u32 {
        match &self.log {
            Decisions::Raft(r) => u32::try_from(r.term()).unwrap_or(u32::MAX),
            Decisions::Log(_) => 0,
        }
    }

    /// This replica's id, 0 for a single coordinator: what its progress names as leader.
    pub(in crate::process) fn replica_id(&self) -> u64 {
        match &self.log {
            Decisions::Raft(r) => r.id(),
            Decisions::Log(_) => 0,
        }
    }

    /// A replica's Raft link, whose `raft/<id>` inbox wakes its loop (none for a single
    /// coordinator).
    pub(in crate::process) fn raft_link(&self) -> Option<Rc<RaftLink>> {
        match &self.log {
            Decisions::Raft(r) => Some(r.link()),
            Decisions::Log(_) => None,
        }
    }

    /// The latest a replica may wait: its next Raft tick (none for a single coordinator).
    pub(in crate::process) fn raft_deadline(&self) -> Option<Instant> {
        match &self.log {
            Decisions::Raft(r) => Some(r.deadline()),
            Decisions::Log(_) => None,
        }
    }

    /// Role and term, for the replica's log lines.
    pub(in crate::process) fn raft_role(&self) -> Option<(&'static str, u64)> {
        match &self.log {
            Decisions::Raft(r) => Some((r.role().name(), r.term())),
            Decisions::Log(_) => None,
        }
    }

    /// One pass of the replica (messages, tick) and the other leaders' committed records
    /// applied. A leader that was deposed after it decided stops here: its state may hold
    /// decisions the cluster never took, and its restart rebuilds it from the journal.
    pub(in crate::process) fn pump(&mut self) -> Result<(), CoordinatorError> {
        let Some(raft) = self.raft() else {
            return Ok(());
        };
        raft.pump()?;
        if let Some(term) = raft.deposed() {
            return Err(CoordinatorError::Deposed {
                term,
                now: raft.term(),
            });
        }
        self.apply_committed();
        Ok(())
    }

    /// Applies the records other leaders committed, as a restarted coordinator replays its
    /// log.
    fn apply_committed(&mut self) {
        let Some(raft) = self.raft() else { return };
        let mut records = std::mem::take(&mut raft.applied);
        for r in &records {
            self.replay(r);
        }
        records.clear();
        if let Some(raft) = self.raft() {
            raft.applied = records;
        }
    }

    /// Whether this replica may decide now: it leads, and every record of earlier leaders is
    /// applied. The first time, the supervisor's events it heard while following are
    /// reconciled with the log (what no leader logged is logged now).
    pub(in crate::process) fn take_lead(&mut self) -> Result<bool, CoordinatorError> {
        let Some(raft) = self.raft() else {
            return Ok(true);
        };
        let first = !raft.leading();
        if !raft.take_lead() {
            return Ok(false);
        }
        if first {
            let heard = std::mem::take(&mut self.heard);
            for (i, h) in heard.iter().enumerate() {
                if let Some((state, restarts)) = *h {
                    self.reconcile(i as u32, state, restarts)?;
                }
            }
        }
        Ok(true)
    }

    /// Waits until the records proposed so far are committed (a no-op for a single
    /// coordinator, whose appends are final). `false` when the process is told to stop first.
    pub(in crate::process) fn settle(
        &mut self,
        waiter: &Waiter,
        tick: &mut dyn FnMut(),
    ) -> Result<bool, CoordinatorError> {
        loop {
            self.pump()?;
            let Some(raft) = self.raft() else {
                return Ok(true);
            };
            if raft.settled() {
                if self.end.is_some() {
                    // The followers are stopped soon after the end: they learn now that it
                    // is committed, not at the next heartbeat.
                    if let Some(raft) = self.raft() {
                        raft.ping()?;
                    }
                }
                return Ok(true);
            }
            tick();
            if waiter.wait(Some(raft.deadline()))? == Wake::Stop {
                return Ok(false);
            }
        }
    }

    /// A following replica takes in the supervisor's events: liveness is remembered for when
    /// it comes to lead (the leader logs it meanwhile); returns how the run ends on a `Stop`.
    pub(in crate::process) fn overhear(
        &mut self,
        life: &LifecyclePorts,
    ) -> Result<Option<EndReason>, CoordinatorError> {
        let heard = &mut self.heard;
        let stop = life.drain_samples(|_, _, l| {
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
        })?;
        Ok(stop.map(|reason| match reason {
            StopReason::TimeLimit => EndReason::TimeLimit,
            StopReason::Requested => EndReason::Stopped,
        }))
    }
}
