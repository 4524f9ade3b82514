//! A replica's snapshot ([`SnapshotRecord`]): the applied state of a compacted prefix of its
//! Raft log, standing in for the entries it replaced.
//!
//! A replica that compacts writes its log anew: header, one snapshot record, its hard state,
//! and the entries after the snapshot's index. The snapshot carries what the coordinator needs
//! to go on deciding and what the log's readers need of the records it replaced
//! ([`AppliedState`]): the last round and its record, the per-agent [`Tally`], who is live,
//! down or lost, the unreachable goals, the end. The individual records of the prefix are
//! gone: `hnav log show` prints the snapshot as one line, the run summary starts from its
//! tally, and a replay or an export sees only the records after it.
//!
//! The state travels encoded ([`SnapshotRecord::state`], bincode 2 like a record): it is
//! also the data of the Raft snapshot a leader sends to a replica too far behind.

use serde::{Deserialize, Serialize};

use super::error::FrameProblem;
use super::record::{
    EndRecord, LifecycleRecord, MapChangeRecord, Record, RoundRecord, RunHeader, SnapshotRecord,
    TaskRecord, UnreachableRecord,
};
use super::tally::Tally;
use crate::msg::{LifecycleEvent, Role};

/// One agent's liveness, as the coordinator's roster keeps it from the lifecycle records.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct AgentLife {
    /// Waited for in a round (not down, not lost).
    pub live: bool,
    /// Gone for good: its robot stands for the rest of the run.
    pub lost: bool,
    /// Its restarts so far, as the supervisor counted them.
    pub restarts: u32,
}

impl Default for AgentLife {
    fn default() -> Self {
        AgentLife {
            live: true,
            lost: false,
            restarts: 0,
        }
    }
}

impl AgentLife {
    /// What a lifecycle event says: a `Down` agent is not waited for until it is back, a
    /// `Lost` one never again; the restarts only grow.
    pub fn event(&mut self, ev: LifecycleEvent, restarts: u32) {
        self.restarts = self.restarts.max(restarts);
        match ev {
            LifecycleEvent::Down => self.live = false,
            LifecycleEvent::Restarted => self.live = !self.lost,
            LifecycleEvent::Lost => (self.live, self.lost) = (false, true),
            _ => {}
        }
    }
}

/// What a sequence of decided records adds up to: everything a coordinator rebuilds from
/// them and everything the run summary reads of them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AppliedState {
    /// Decided records folded (the header not counted).
    pub records: u64,
    /// The last decided round, 0 before the first.
    pub round: u64,
    /// Its record, for the agents that missed its commit.
    pub last_round: Option<RoundRecord>,
    /// The per-agent tally of the decisions.
    pub tally: Tally,
    /// Per agent, its liveness.
    pub agents: Vec<AgentLife>,
    /// The unreachable goals logged, in log order.
    pub unreachable: Vec<UnreachableRecord>,
    /// The end of the run, once logged.
    pub end: Option<EndRecord>,
    /// The lifecycle of the processes other than agents (replicas, the sim): per process
    /// and event, the record with the most restarts, so that a replica that comes to lead
    /// knows which of the events it overheard the log already holds. Bounded by the
    /// processes times the event kinds.
    pub processes: Vec<LifecycleRecord>,
    /// A lifelong run's task records, in log order: the coordinator restores each agent's
    /// current goal from them and the summary its task times. This is the one part that
    /// grows with the run, by one record (about 10 bytes encoded) per task done.
    pub tasks: Vec<TaskRecord>,
    /// The map changes logged (`[sensing]`), in log order: the coordinator rebuilds the map
    /// it decides on from them. Grows by one record per accepted change of the world, which
    /// is bounded by the world's changes, not the run's length.
    pub map_changes: Vec<MapChangeRecord>,
}

impl AppliedState {
    /// Nothing decided yet in the run `header` describes.
    pub fn new(header: &RunHeader) -> Self {
        AppliedState {
            records: 0,
            round: 0,
            last_round: None,
            tally: Tally::from_header(header),
            agents: vec![AgentLife::default(); header.agents.len()],
            unreachable: Vec::new(),
            end: None,
            processes: Vec::new(),
            tasks: Vec::new(),
            map_changes: Vec::new(),
        }
    }

    /// Folds one decided record in, as a restarted coordinator replays it.
    pub fn fold(&mut self, r: &Record) {
        match r {
            Record::Round(rec) => {
                self.round = self.round.max(rec.round);
                self.tally.fold_round(rec);
                self.last_round = Some(rec.clone());
            }
            Record::End(e) => self.end = Some(*e),
            Record::Lifecycle(l) => self.fold_lifecycle(l),
            Record::Unreachable(u) => self.unreachable.push(*u),
            Record::Task(t) => self.tasks.push(*t),
            Record::MapChange(m) => self.map_changes.push(m.clone()),
            Record::Replan(_) => {}
            Record::Header(_) | Record::Raft(_) | Record::RaftState(_) | Record::Snapshot(_) => {
                return
            }
        }
        self.records += 1;
    }

    fn fold_lifecycle(&mut self, l: &LifecycleRecord) {
        match (Role::from_u8(l.role), LifecycleEvent::from_u8(l.event)) {
            (Some(Role::Agent), Some(ev)) => {
                if let Some(a) = self.agents.get_mut(l.index as usize) {
                    a.event(ev, l.restarts);
                }
            }
            (Some(_), Some(_)) => {
                let same = |p: &&mut LifecycleRecord| {
                    (p.role, p.index, p.event) == (l.role, l.index, l.event)
                };
                match self.processes.iter_mut().find(same) {
                    Some(p) if p.restarts < l.restarts => *p = *l,
                    Some(_) => {}
                    None => self.processes.push(*l),
                }
            }
            _ => {}
        }
    }

    /// The state as the bytes of a [`SnapshotRecord`].
    pub fn encode(&self) -> Vec<u8> {
        bincode::serde::encode_to_vec(self, bincode::config::standard())
            .expect("an applied state always encodes")
    }

    /// The state a [`SnapshotRecord`] holds.
    pub fn decode(bytes: &[u8]) -> Result<AppliedState, FrameProblem> {
        let config = bincode::config::standard();
        match bincode::serde::decode_from_slice(bytes, config) {
            Ok((state, used)) if used == bytes.len() => Ok(state),
            Ok((_, used)) => Err(FrameProblem::Undecodable {
                detail: format!("{} bytes after the snapshot's state", bytes.len() - used),
            }),
            Err(e) => Err(FrameProblem::Undecodable {
                detail: format!("snapshot state: {e}"),
            }),
        }
    }
}

impl SnapshotRecord {
    /// A snapshot of `state` at Raft index `index` of term `term`.
    pub fn new(index: u64, term: u64, voters: Vec<u64>, state: &AppliedState) -> Self {
        SnapshotRecord {
            index,
            term,
            voters,
            state: state.encode(),
        }
    }

    /// The state it holds.
    pub fn applied(&self) -> Result<AppliedState, FrameProblem> {
        AppliedState::decode(&self.state)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header() -> RunHeader {
        RunHeader::tiny(1)
    }

    fn life(role: Role, index: u32, event: LifecycleEvent, restarts: u32) -> Record {
        Record::Lifecycle(LifecycleRecord {
            round: 7,
            role: role as u8,
            index,
            event: event as u8,
            restarts,
        })
    }

    #[test]
    fn the_state_keeps_each_processes_latest_events_and_every_task() {
        let mut s = AppliedState::new(&header());
        let task = |task, goal| {
            Record::Task(TaskRecord {
                round: 9,
                agent: 0,
                task,
                goal,
            })
        };
        for r in [
            life(Role::Coordinator, 3, LifecycleEvent::Down, 0),
            life(Role::Coordinator, 3, LifecycleEvent::Restarted, 1),
            life(Role::Coordinator, 3, LifecycleEvent::Down, 1),
            // Logged late by a new leader: an older event of the same kind is not kept.
            life(Role::Coordinator, 3, LifecycleEvent::Down, 0),
            life(Role::Sim, 0, LifecycleEvent::Down, 0),
            task(1, 5),
            task(2, 11),
        ] {
            s.fold(&r);
        }
        let kept: Vec<(u8, u32, u8, u32)> = s
            .processes
            .iter()
            .map(|p| (p.role, p.index, p.event, p.restarts))
            .collect();
        let (c, down, up) = (
            Role::Coordinator as u8,
            LifecycleEvent::Down as u8,
            LifecycleEvent::Restarted as u8,
        );
        assert_eq!(
            kept,
            [
                (c, 3, down, 1),
                (c, 3, up, 1),
                (Role::Sim as u8, 0, down, 0)
            ]
        );
        assert_eq!(s.tasks.iter().map(|t| t.goal).collect::<Vec<_>>(), [5, 11]);
        assert_eq!(s.records, 7);
        assert_eq!(AppliedState::decode(&s.encode()).unwrap(), s);
    }

    #[test]
    fn the_state_keeps_every_map_change_in_log_order() {
        let mut s = AppliedState::new(&header());
        let change = |round, closed: Vec<u32>, opened: Vec<u32>| MapChangeRecord {
            round,
            agent: 1,
            closed,
            opened,
        };
        let (shut, reopened) = (change(3, vec![5], vec![]), change(8, vec![], vec![5]));
        s.fold(&Record::MapChange(shut.clone()));
        s.fold(&Record::MapChange(reopened.clone()));
        assert_eq!(s.map_changes, [shut, reopened]);
        assert_eq!(s.records, 2);
        assert_eq!(AppliedState::decode(&s.encode()).unwrap(), s);
    }
}
