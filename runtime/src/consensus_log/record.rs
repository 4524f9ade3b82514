//! The records of a consensus log and their conversions from and to the message contracts.
//!
//! Cells are 0-based row-major indices (`y * width + x`) as in [`msg`](crate::msg), with
//! [`NO_CELL`](crate::msg::NO_CELL) for "none". Nothing here holds a process id or a wall-clock
//! time, so the log of a lockstep run is byte-identical across runs of the same scenario.

use serde::{Deserialize, Serialize};

use crate::hash::Fnv1a64;
use crate::msg::{Candidate, Commit, CommitHeader, Decision, Lifecycle};

/// One entry of the log. A log starts with exactly one [`Header`](Record::Header).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Record {
    /// What the run is: written once, first.
    Header(RunHeader),
    /// One decision round; its Commit is published only after this record is durable.
    Round(RoundRecord),
    /// A process came up, went down or was restarted.
    Lifecycle(LifecycleRecord),
    /// A global replan for one agent.
    Replan(ReplanRecord),
    /// The run ended.
    End(EndRecord),
    /// An agent reported that its goal cannot be reached (logged once per agent; after the
    /// kinds above so that their encoding is unchanged).
    Unreachable(UnreachableRecord),
    /// A Raft log entry of a replicated log ([`REPLICATED_VERSION`](super::REPLICATED_VERSION)):
    /// one of the kinds above, encoded, with the term and index Raft gave it.
    Raft(RaftEntryRecord),
    /// A replica's Raft hard state (term, vote, commit index) from this point of its log on.
    RaftState(RaftStateRecord),
    /// A lifelong run (`[tasks]`) gave an agent standing on its goal its next goal (after the
    /// kinds above so that their encoding is unchanged).
    Task(TaskRecord),
    /// A replica's snapshot: the applied state of the Raft entries it replaced, which are
    /// gone from its log ([`snapshot`](super::snapshot)).
    Snapshot(SnapshotRecord),
    /// The coordinator accepted cells an agent saw close or open (`[sensing]`): it decides
    /// this round and the next on the changed map (after the kinds above so that their
    /// encoding is unchanged).
    MapChange(MapChangeRecord),
}

impl Record {
    /// Lower-case name of the record's kind (`header`, `round`, `lifecycle`, `replan`, `end`,
    /// `unreachable`, `raft-entry`, `raft-state`, `task`, `snapshot`, `map-change`).
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Header(_) => "header",
            Self::Round(_) => "round",
            Self::Lifecycle(_) => "lifecycle",
            Self::Replan(_) => "replan",
            Self::End(_) => "end",
            Self::Unreachable(_) => "unreachable",
            Self::Raft(_) => "raft-entry",
            Self::RaftState(_) => "raft-state",
            Self::Task(_) => "task",
            Self::Snapshot(_) => "snapshot",
            Self::MapChange(_) => "map-change",
        }
    }

    /// The round the record belongs to (`None` for the header).
    pub fn round(&self) -> Option<u64> {
        match self {
            Self::Header(_) => None,
            Self::Round(r) => Some(r.round),
            Self::Lifecycle(r) => Some(r.round),
            Self::Replan(r) => Some(r.round),
            Self::End(r) => Some(r.round),
            Self::Unreachable(r) => Some(r.round),
            Self::Task(r) => Some(r.round),
            Self::MapChange(r) => Some(r.round),
            Self::Raft(_) | Self::RaftState(_) | Self::Snapshot(_) => None,
        }
    }
}

/// One Raft log entry as a replica stores it. A later entry with the same or a lower index
/// replaces this one and every entry after it (Raft overwrote an uncommitted suffix); see
/// [`replicated`](super::replicated).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RaftEntryRecord {
    /// The term of the leader that proposed it.
    pub term: u64,
    /// Raft's log index, from 1.
    pub index: u64,
    /// The decided [`Record`] in the log's own payload encoding, or empty for the empty entry
    /// a new leader appends.
    pub data: Vec<u8>,
}

/// A replica's snapshot: the applied state of every Raft entry up to `index`, which it
/// replaces in the log. The first record after the header of a compacted log; see
/// [`snapshot`](super::snapshot).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SnapshotRecord {
    /// The last Raft index it covers (every entry up to it is committed).
    pub index: u64,
    /// That entry's term.
    pub term: u64,
    /// The cluster's voters.
    pub voters: Vec<u64>,
    /// The [`AppliedState`](super::snapshot::AppliedState), encoded: the bytes Raft sends to a
    /// replica that needs the snapshot.
    pub state: Vec<u8>,
}

/// A replica's Raft hard state, as of this point in its log.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RaftStateRecord {
    /// The current term.
    pub term: u64,
    /// Whom the replica voted for in that term (0 for nobody).
    pub vote: u64,
    /// The highest index known committed.
    pub commit: u64,
}

/// The run a log belongs to.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunHeader {
    /// [`FORMAT_VERSION`](super::FORMAT_VERSION) of the writer.
    pub version: u32,
    /// [`Scenario::scenario_hash`](crate::scenario::Scenario::scenario_hash) of the run.
    pub scenario_hash: u64,
    /// The sim's seed.
    pub seed: u64,
    /// The clock mode: `"lockstep"` or `"realtime"`.
    pub clock: String,
    /// Grid width in cells.
    pub width: u32,
    /// Grid height in cells.
    pub height: u32,
    /// The agents, index = agent number.
    pub agents: Vec<AgentEntry>,
}

#[cfg(test)]
impl RunHeader {
    /// The header of a 4 x 4 run without agents, written by format `version`: the fixture
    /// of the log's unit tests.
    pub(crate) fn tiny(version: u32) -> Self {
        RunHeader {
            version,
            scenario_hash: 1,
            seed: 2,
            clock: "lockstep".into(),
            width: 4,
            height: 4,
            agents: Vec::new(),
        }
    }
}

/// One agent of the run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AgentEntry {
    /// Start cell (row-major index).
    pub start: u32,
    /// Goal cell (row-major index).
    pub goal: u32,
    /// Nominal speed in cells per second.
    pub speed: f64,
    /// Conflict priority (larger wins).
    pub priority: f64,
}

/// One decision round: what was proposed (as a digest) and what was decided.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RoundRecord {
    /// The round.
    pub round: u64,
    /// How many candidates the round received.
    pub candidates: u32,
    /// [`candidates_digest`] of them.
    pub candidates_digest: u64,
    /// The decisions, as published in the round's [`Commit`].
    pub decisions: Vec<LoggedDecision>,
}

impl RoundRecord {
    /// The record of a round that received `candidates` and decided `decisions`.
    pub fn new(round: u64, candidates: &[Candidate], decisions: &[Decision]) -> Self {
        Self {
            round,
            candidates: u32::try_from(candidates.len()).unwrap_or(u32::MAX),
            candidates_digest: candidates_digest(candidates),
            decisions: decisions.iter().map(LoggedDecision::from).collect(),
        }
    }

    /// The header of the commit this record describes, published in Raft term `term`.
    pub fn commit_header(&self, term: u32) -> CommitHeader {
        CommitHeader {
            round: self.round,
            count: u32::try_from(self.decisions.len()).unwrap_or(u32::MAX),
            term,
        }
    }

    /// Decision `i` of the commit this record describes, as published (`i` below the
    /// record's decisions), for writing straight into a loaned sample.
    pub fn decision(&self, i: usize) -> Decision {
        Decision::from(&self.decisions[i])
    }

    /// Writes the commit this record describes into `c`, reusing its decisions' memory (a
    /// replay folds every round into one `Commit`).
    pub fn write_commit(&self, c: &mut Commit) {
        c.round = self.round;
        c.term = 0;
        c.decisions.clear();
        c.decisions
            .extend(self.decisions.iter().map(Decision::from));
    }

    /// The commit this record describes (for a resend after a restart, or a comparison).
    pub fn commit(&self) -> Commit {
        let mut c = Commit::default();
        self.write_commit(&mut c);
        c
    }
}

/// One agent's decision: [`Decision`] without its reserved byte.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct LoggedDecision {
    /// Agent index.
    pub agent: u32,
    /// A [`Verdict`](crate::msg::Verdict) as `u8`.
    pub verdict: u8,
    /// Refused directions, bit `d` for direction `d` (0 = N, clockwise).
    pub refused: u8,
    /// A [`ConflictKind`](crate::msg::ConflictKind) as `u8`.
    pub kind: u8,
    /// The committed cell or [`NO_CELL`](crate::msg::NO_CELL).
    pub cell: u32,
    /// The next replan waypoint or [`NO_CELL`](crate::msg::NO_CELL).
    pub waypoint: u32,
}

impl From<&Decision> for LoggedDecision {
    fn from(d: &Decision) -> Self {
        Self {
            agent: d.agent,
            verdict: d.verdict,
            refused: d.refused,
            kind: d.kind,
            cell: d.cell,
            waypoint: d.waypoint,
        }
    }
}

impl From<&LoggedDecision> for Decision {
    fn from(d: &LoggedDecision) -> Self {
        Self {
            agent: d.agent,
            verdict: d.verdict,
            refused: d.refused,
            kind: d.kind,
            reserved: 0,
            cell: d.cell,
            waypoint: d.waypoint,
        }
    }
}

/// A process event, as the supervisor published it, without pid and wall time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct LifecycleRecord {
    /// The last round committed when the event was logged.
    pub round: u64,
    /// A [`Role`](crate::msg::Role) as `u8`.
    pub role: u8,
    /// Agent index for agents, else 0.
    pub index: u32,
    /// A [`LifecycleEvent`](crate::msg::LifecycleEvent) as `u8`.
    pub event: u8,
    /// Restarts of the process so far.
    pub restarts: u32,
}

impl LifecycleRecord {
    /// The record of `event`, logged at `round` (the event's pid and time are dropped).
    pub fn new(round: u64, event: &Lifecycle) -> Self {
        Self {
            round,
            role: event.role,
            index: event.index,
            event: event.event,
            restarts: event.restarts,
        }
    }
}

/// An agent whose goal cannot be reached from its robot's cell through free cells (walls and
/// the corner-cutting rule; other robots are not walls): it stands still from then on.
/// Written like a replan, just before the record of the round it is reported in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct UnreachableRecord {
    /// The round the agent reported it in.
    pub round: u64,
    /// Agent index.
    pub agent: u32,
    /// The robot's cell (row-major index).
    pub cell: u32,
}

/// An agent of a lifelong run stood on its goal in `round` and was given its next one: task
/// `task` (counted from 1; task 0 is its `[[agents]] goal`, given at the start). Written like
/// a replan, just before the record of the round whose commit tells the agent (a `task`
/// decision with the goal as its waypoint). The time from one task record of an agent to its
/// next is the time the task took, from its assignment to the robot's arrival.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct TaskRecord {
    /// The round the agent stood on its goal in.
    pub round: u64,
    /// Agent index.
    pub agent: u32,
    /// The task's number for this agent, from 1.
    pub task: u64,
    /// The new goal (row-major index).
    pub goal: u32,
}

/// Cells of the map that changed, as one agent saw them and the coordinator accepted them:
/// each differed from the coordinator's map when it was logged. Logged before the round's
/// record, which is the first decided on the changed map.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct MapChangeRecord {
    /// The round decided first on the changed map.
    pub round: u64,
    /// The agent that saw the change.
    pub agent: u32,
    /// Cells that closed (row-major indices, ascending).
    pub closed: Vec<u32>,
    /// Cells that opened (row-major indices, ascending).
    pub opened: Vec<u32>,
}

impl MapChangeRecord {
    /// Every changed cell, as (cell, closed): the closed ones, then the opened ones.
    pub fn changes(&self) -> impl Iterator<Item = (u32, bool)> + '_ {
        let closed = self.closed.iter().map(|&c| (c, true));
        closed.chain(self.opened.iter().map(|&c| (c, false)))
    }
}

/// A global replan for one agent.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ReplanRecord {
    /// The round it was made in.
    pub round: u64,
    /// The agent.
    pub agent: u32,
    /// Planner name (`a-star`, `theta-star`, `lazy-theta-star`, ...).
    pub planner: String,
    /// Whether a path was found.
    pub found: bool,
    /// The path's waypoints (row-major cells), empty when none was found.
    pub waypoints: Vec<u32>,
}

/// The end of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct EndRecord {
    /// The last round committed.
    pub round: u64,
    /// Agents standing on their goal at the end.
    pub at_goal: u32,
    /// Why the run ended.
    pub reason: EndReason,
}

/// Why a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum EndReason {
    /// Every agent reached its goal.
    AllAtGoal,
    /// The scenario's time limit passed.
    TimeLimit,
    /// The supervisor (or an operator) stopped the run.
    Stopped,
    /// Every agent is at its goal or has reported its goal unreachable (at least one has).
    AllAtGoalOrUnreachable,
    /// Every agent is at its goal, unreachable, or lost (its process gone for good: its robot
    /// stands and its goal counts as not reached); at least one is lost.
    AllAtGoalOrLost,
}

impl EndReason {
    /// Lower-case name (`all-at-goal`, `time-limit`, `stopped`, `all-at-goal-or-unreachable`,
    /// `all-at-goal-or-lost`).
    pub fn name(self) -> &'static str {
        match self {
            Self::AllAtGoal => "all-at-goal",
            Self::TimeLimit => "time-limit",
            Self::Stopped => "stopped",
            Self::AllAtGoalOrUnreachable => "all-at-goal-or-unreachable",
            Self::AllAtGoalOrLost => "all-at-goal-or-lost",
        }
    }
}

/// FNV-1a 64 ([`Fnv1a64`]) over a round's candidates in agent order (the slice is sorted by
/// `agent` first if it is not already).
///
/// Encoding: the count as `u64` LE, then per candidate `round` u64, `agent`, `current`,
/// `next`, `probable` u32, the bits of `priority` and `speed` (f32) and `flags` u32, all
/// little-endian; `reserved` is not hashed.
pub fn candidates_digest(candidates: &[Candidate]) -> u64 {
    let mut h = Fnv1a64::new();
    h.u64(candidates.len() as u64);
    let mut feed = |c: &Candidate| {
        h.bytes(&c.round.to_le_bytes());
        for v in [c.agent, c.current, c.next, c.probable] {
            h.bytes(&v.to_le_bytes());
        }
        h.bytes(&c.priority.to_bits().to_le_bytes());
        h.bytes(&c.speed.to_bits().to_le_bytes());
        h.bytes(&c.flags.to_le_bytes());
    };
    if candidates.windows(2).all(|w| w[0].agent <= w[1].agent) {
        candidates.iter().for_each(&mut feed);
    } else {
        let mut sorted: Vec<&Candidate> = candidates.iter().collect();
        sorted.sort_by_key(|c| c.agent);
        sorted.into_iter().for_each(feed);
    }
    h.finish()
}
