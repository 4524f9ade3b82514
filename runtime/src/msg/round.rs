//! The decision round's payloads: agents' candidates, the coordinator's commit, its tally.

use iceoryx2::prelude::ZeroCopySend;

use super::NO_CELL;

/// One agent's row of the dissertation's `shared_paths` table, proposed for a decision round.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
#[type_name("hnav::Candidate")]
pub struct Candidate {
    /// Decision round this candidate is for.
    pub round: u64,
    /// Agent index (0-based, < the run's agent count).
    pub agent: u32,
    /// Cell the robot is in.
    pub current: u32,
    /// Cell already committed for the robot (it will not change), or [`NO_CELL`].
    pub next: u32,
    /// Cell the agent proposes to enter after `next`, or [`NO_CELL`] when it stands still.
    pub probable: u32,
    /// Conflict priority; larger wins. `1 / speed` unless the scenario gives one.
    pub priority: f32,
    /// Nominal speed in cells per second.
    pub speed: f32,
    /// Bit set of [`CandidateFlags`] values.
    pub flags: u32,
    /// Zero.
    pub reserved: u32,
}

impl Default for Candidate {
    fn default() -> Self {
        Self {
            round: 0,
            agent: 0,
            current: NO_CELL,
            next: NO_CELL,
            probable: NO_CELL,
            priority: 0.0,
            speed: 0.0,
            flags: 0,
            reserved: 0,
        }
    }
}

/// Bits of [`Candidate::flags`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CandidateFlags;

impl CandidateFlags {
    /// The robot is at its goal and stays there.
    pub const AT_GOAL: u32 = 1 << 0;
    /// The agent proposes no move this round.
    pub const STANDING: u32 = 1 << 1;
    /// The ascent found no neighbour better than the current cell (local extremum).
    pub const LOCAL_EXTREMUM: u32 = 1 << 2;
    /// The agent process was restarted and resumes from the committed state.
    pub const RESTARTED: u32 = 1 << 3;
    /// The neural map reports the goal unreachable.
    pub const NO_PATH: u32 = 1 << 4;
    /// Every bit an agent may set; a receiver drops a candidate with any other.
    pub const ALL: u32 =
        Self::AT_GOAL | Self::STANDING | Self::LOCAL_EXTREMUM | Self::RESTARTED | Self::NO_PATH;
}

/// What the coordinator decided for one agent in a round.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Verdict {
    /// The probable cell is accepted: `next <- probable`.
    Accept = 1,
    /// The move is refused; [`Decision::refused`] names the refused directions.
    Block = 2,
    /// No move asked or possible (standing, finished, missing in the round).
    Hold = 3,
    /// A global replan was made; [`Decision::waypoint`] is the next intermediate target.
    Replan = 4,
    /// A lifelong run's next task (`[tasks]`): [`Decision::waypoint`] is the agent's new
    /// goal. Given to an agent that stands on its goal and was not moved this round.
    Task = 5,
}

impl Verdict {
    /// Decodes a verdict byte received from another process.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            1 => Some(Self::Accept),
            2 => Some(Self::Block),
            3 => Some(Self::Hold),
            4 => Some(Self::Replan),
            5 => Some(Self::Task),
            _ => None,
        }
    }

    /// Lower-case name (`accept`, `block`, `hold`, `replan`, `task`), as in `hnav log show`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Accept => "accept",
            Self::Block => "block",
            Self::Hold => "hold",
            Self::Replan => "replan",
            Self::Task => "task",
        }
    }
}

/// Why the coordinator refused or held a move (the dissertation's conflict types, Fig. 3-6,
/// plus the checks a physical swarm needs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum ConflictKind {
    /// No conflict (accepted, or nothing asked).
    None = 0,
    /// (a) crossing: two moves claim the same cell or sweep the same corner.
    Crossing = 1,
    /// (b) head-on: two agents ask for each other's cells.
    HeadOn = 2,
    /// (c) combined: a move that is both crossing and head-on at once.
    Combined = 3,
    /// (d) the cell of a standing or finished agent, refused whatever the priority.
    StableCell = 4,
    /// A diagonal past a blocked or occupied corner cell.
    CornerCut = 5,
    /// A cell still held (current or next) by an agent that is moving out of it.
    Reserved = 6,
    /// Not a legal move at all: not a neighbour, off the grid, or a blocked cell.
    Invalid = 7,
    /// `[coordinator] rules = "pibt"` or `"lacam"`, on an accept: the agent is moved out of
    /// the way of a higher-priority agent (priority inheritance) or along the plan, though it
    /// asked for no step.
    Pushed = 8,
    /// `[coordinator] rules = "pibt"` or `"lacam"`, on an accept: the coordinator chose another
    /// step than the agent asked for (pibt: its cell was taken, or it asked for none, by
    /// distance to its goal; lacam: the plan's step).
    Redirected = 9,
}

impl ConflictKind {
    /// Decodes a kind byte received from another process.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            0 => Some(Self::None),
            1 => Some(Self::Crossing),
            2 => Some(Self::HeadOn),
            3 => Some(Self::Combined),
            4 => Some(Self::StableCell),
            5 => Some(Self::CornerCut),
            6 => Some(Self::Reserved),
            7 => Some(Self::Invalid),
            8 => Some(Self::Pushed),
            9 => Some(Self::Redirected),
            _ => None,
        }
    }

    /// Short lower-case name, as in logs and reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Crossing => "crossing",
            Self::HeadOn => "head-on",
            Self::Combined => "combined",
            Self::StableCell => "stable-cell",
            Self::CornerCut => "corner-cut",
            Self::Reserved => "reserved",
            Self::Invalid => "invalid",
            Self::Pushed => "pushed",
            Self::Redirected => "redirected",
        }
    }
}

/// One agent's entry in a [`Commit`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
#[type_name("hnav::Decision")]
pub struct Decision {
    /// Agent index.
    pub agent: u32,
    /// A [`Verdict`] as `u8`.
    pub verdict: u8,
    /// Refused directions, bit `d` for direction index `d` (0 = N, clockwise to 7 = NW).
    pub refused: u8,
    /// Why a move was refused or held: a [`ConflictKind`] as `u8`; 0 when accepted as asked,
    /// [`ConflictKind::Pushed`] or [`ConflictKind::Redirected`] on an accept the coordinator
    /// chose.
    pub kind: u8,
    /// Zero.
    pub reserved: u8,
    /// The committed cell (the accepted `probable`), or [`NO_CELL`].
    pub cell: u32,
    /// The next waypoint of a global replan, or [`NO_CELL`].
    pub waypoint: u32,
}

impl Default for Decision {
    fn default() -> Self {
        Self {
            agent: 0,
            verdict: Verdict::Hold as u8,
            refused: 0,
            kind: ConflictKind::None as u8,
            reserved: 0,
            cell: NO_CELL,
            waypoint: NO_CELL,
        }
    }
}

/// The user header of a round's commit (`commit`, a `[Decision]` slice sized to the run's
/// agents): one decision round's outcome, published only after it is durable in the
/// consensus log.
///
/// These are the 16 bytes that opened the fixed-size `Commit` of 256 decisions before runs
/// were sized to their swarm; the decisions now follow as the sample's slice, one per agent of
/// the run, so a commit of 1 000 agents is 16 kB and one of 6 agents is 96 bytes.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
#[type_name("hnav::CommitHeader")]
pub struct CommitHeader {
    /// The round decided.
    pub round: u64,
    /// How many decisions the slice holds, said again for readers whose binding reports a
    /// slice's length in bytes (iceoryx2's Python does).
    pub count: u32,
    /// The Raft term of the coordinator replica that published it (`coordinator.replicas`
    /// 3 or 5), 0 for a single coordinator. A replica publishes only committed rounds, so a
    /// deposed leader can only repeat a round every agent already has: agents ignore a
    /// commit for a round at or below the last they applied, whatever its term.
    pub term: u32,
}

/// A round's commit as it is read: its header and decisions, borrowed from a sample in
/// shared memory (no copy) or from an owned [`Commit`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CommitView<'a> {
    header: CommitHeader,
    decisions: &'a [Decision],
}

impl<'a> CommitView<'a> {
    /// The commit of `header` and `decisions`. A header whose count disagrees with the slice
    /// reads as the shorter of the two, so a corrupt count cannot index out of bounds.
    pub fn new(header: &CommitHeader, decisions: &'a [Decision]) -> Self {
        let n = (header.count as usize).min(decisions.len());
        Self {
            header: *header,
            decisions: &decisions[..n],
        }
    }

    /// The round decided.
    pub fn round(&self) -> u64 {
        self.header.round
    }

    /// The publishing replica's Raft term (0 for a single coordinator).
    pub fn term(&self) -> u32 {
        self.header.term
    }

    /// The decisions, one per agent of the run.
    pub fn decisions(&self) -> &'a [Decision] {
        self.decisions
    }

    /// The header, its count that of [`CommitView::decisions`].
    pub fn header(&self) -> CommitHeader {
        CommitHeader {
            count: self.decisions.len() as u32,
            ..self.header
        }
    }
}

/// A round's commit held in memory (a replay, an export, a test); what travels is a
/// [`CommitHeader`] and its decisions, read as a [`CommitView`].
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Commit {
    /// The round decided.
    pub round: u64,
    /// The publishing replica's Raft term (0 for a single coordinator).
    pub term: u32,
    /// The decisions, one per agent of the run.
    pub decisions: Vec<Decision>,
}

impl Commit {
    /// The commit borrowed as it is read from a topic.
    pub fn view(&self) -> CommitView<'_> {
        CommitView {
            header: CommitHeader {
                round: self.round,
                count: self.decisions.len() as u32,
                term: self.term,
            },
            decisions: &self.decisions,
        }
    }

    /// The valid decisions.
    pub fn decisions(&self) -> &[Decision] {
        &self.decisions
    }

    /// Holds `v` (copied out of its sample), reusing this commit's memory for the decisions.
    pub fn set(&mut self, v: CommitView<'_>) {
        self.round = v.round();
        self.term = v.term();
        self.decisions.clear();
        self.decisions.extend_from_slice(v.decisions());
    }
}

/// The coordinator's running tally, published after every round (latest value only) for the
/// supervisor's progress bar and for viewers.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
#[type_name("hnav::Progress")]
pub struct Progress {
    /// Last committed round.
    pub round: u64,
    /// Agents in the run.
    pub agents: u32,
    /// Agents standing on their goal.
    pub at_goal: u32,
    /// Refused or held moves so far.
    pub conflicts: u32,
    /// Global replans so far.
    pub replans: u32,
    /// [`Progress::ALL_AT_GOAL`] once every agent is at its goal or (reported) unable to reach
    /// it, [`Progress::TIME_LIMIT`] once a lockstep run has committed its last round, else 0:
    /// the coordinator has ended the run and decides nothing more.
    pub done: u8,
    /// The replica that published it, the Raft leader (1-based; 0 for a single
    /// coordinator): whom a fault aimed at "the coordinator" hits, and what `hnav ps` shows.
    /// Was `reserved[0]`; the layout is unchanged.
    pub leader: u8,
    /// Zero.
    pub reserved: [u8; 6],
}

impl Progress {
    /// [`Progress::done`]: every agent is at its goal or reported unable to reach it.
    pub const ALL_AT_GOAL: u8 = 1;
    /// [`Progress::done`]: a lockstep run committed the last round of its time limit.
    pub const TIME_LIMIT: u8 = 2;
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::mem::{align_of, offset_of, size_of};

    #[test]
    fn candidate_layout() {
        assert_eq!(size_of::<Candidate>(), 40);
        assert_eq!(align_of::<Candidate>(), 8);
        assert_eq!(offset_of!(Candidate, round), 0);
        assert_eq!(offset_of!(Candidate, agent), 8);
        assert_eq!(offset_of!(Candidate, current), 12);
        assert_eq!(offset_of!(Candidate, next), 16);
        assert_eq!(offset_of!(Candidate, probable), 20);
        assert_eq!(offset_of!(Candidate, priority), 24);
        assert_eq!(offset_of!(Candidate, speed), 28);
        assert_eq!(offset_of!(Candidate, flags), 32);
        assert_eq!(offset_of!(Candidate, reserved), 36);
    }

    #[test]
    fn commit_layout() {
        assert_eq!(size_of::<Decision>(), 16);
        assert_eq!(align_of::<Decision>(), 4);
        assert_eq!(offset_of!(Decision, agent), 0);
        assert_eq!(offset_of!(Decision, verdict), 4);
        assert_eq!(offset_of!(Decision, refused), 5);
        assert_eq!(offset_of!(Decision, kind), 6);
        assert_eq!(offset_of!(Decision, reserved), 7);
        assert_eq!(offset_of!(Decision, cell), 8);
        assert_eq!(offset_of!(Decision, waypoint), 12);
        assert_eq!(size_of::<CommitHeader>(), 16);
        assert_eq!(align_of::<CommitHeader>(), 8);
        assert_eq!(offset_of!(CommitHeader, round), 0);
        assert_eq!(offset_of!(CommitHeader, count), 8);
        assert_eq!(offset_of!(CommitHeader, term), 12);
    }

    #[test]
    fn progress_layout() {
        assert_eq!(size_of::<Progress>(), 32);
        assert_eq!(align_of::<Progress>(), 8);
        assert_eq!(offset_of!(Progress, round), 0);
        assert_eq!(offset_of!(Progress, agents), 8);
        assert_eq!(offset_of!(Progress, at_goal), 12);
        assert_eq!(offset_of!(Progress, conflicts), 16);
        assert_eq!(offset_of!(Progress, replans), 20);
        assert_eq!(offset_of!(Progress, done), 24);
        assert_eq!(offset_of!(Progress, leader), 25);
        assert_eq!(offset_of!(Progress, reserved), 26);
    }

    #[test]
    fn enums_round_trip_and_reject_unknown_bytes() {
        for v in [
            Verdict::Accept,
            Verdict::Block,
            Verdict::Hold,
            Verdict::Replan,
            Verdict::Task,
        ] {
            assert_eq!(Verdict::from_u8(v as u8), Some(v));
        }
        for k in 0..=9u8 {
            assert_eq!(ConflictKind::from_u8(k).map(|k| k as u8), Some(k));
        }
        assert_eq!(ConflictKind::from_u8(10), None);
        for bad in [0u8, 6, 200, 255] {
            assert_eq!(Verdict::from_u8(bad), None);
        }
    }

    #[test]
    fn a_corrupt_count_does_not_index_out_of_bounds() {
        let d = [Decision::default(); 3];
        let h = CommitHeader {
            round: 4,
            count: u32::MAX,
            term: 1,
        };
        let v = CommitView::new(&h, &d);
        assert_eq!(v.decisions().len(), 3);
        assert_eq!(v.header().count, 3);
        let short = CommitHeader { count: 2, ..h };
        assert_eq!(CommitView::new(&short, &d).decisions().len(), 2);
    }

    #[test]
    fn an_owned_commit_reads_as_the_view_of_its_decisions() {
        let c = Commit {
            round: 9,
            term: 2,
            decisions: vec![Decision::default(); 5],
        };
        let v = c.view();
        assert_eq!((v.round(), v.term(), v.decisions().len()), (9, 2, 5));
        assert_eq!(v, CommitView::new(&v.header(), c.decisions()));
    }
}
