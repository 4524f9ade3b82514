//! Message contracts: the payloads that cross process boundaries.
//!
//! Every type here is `#[repr(C)]`, [`ZeroCopySend`] and carries a `#[type_name("hnav::...")]`
//! so that two separately built binaries (or a foreign client using the iceoryx2 C++ or Python
//! bindings) agree on its identity. Layouts contain no implicit padding: every gap is an explicit
//! `reserved` field that senders set to zero, so a sample's bytes are fully defined and can be
//! hashed or checksummed as they are.
//!
//! Cells travel as 0-based row-major indices (`y * width + x`, MovingAI `x` = column, `y` = row)
//! in a `u32`; [`NO_CELL`] marks "none". Enumerations travel as plain integers with associated
//! constants instead of Rust enums, because reading an out-of-range discriminant out of shared
//! memory would be undefined behaviour: a receiver validates with `from_u8` and drops what it
//! does not understand.
//!
//! All sizes and offsets below are for a 64-bit little-endian target and are asserted by the
//! tests at the bottom of this file, so this table cannot drift from the code.
//!
//! | type | size | align | fields (offset: name type) |
//! |---|---|---|---|
//! | [`Candidate`] | 40 | 8 | 0 round u64, 8 agent u32, 12 current u32, 16 next u32, 20 probable u32, 24 priority f32, 28 speed f32, 32 flags u32, 36 reserved u32 |
//! | [`Decision`] | 16 | 4 | 0 agent u32, 4 verdict u8, 5 refused u8, 6 kind u8, 7 reserved u8, 8 cell u32, 12 waypoint u32 |
//! | [`Commit`] | 16 + 16·[`MAX_AGENTS`] = 4112 | 8 | 0 round u64, 8 count u32, 12 reserved u32, 16 decisions [Decision; 256] |
//! | [`WheelCommand`] | 32 | 8 | 0 period u64, 8 agent u32, 12 flags u32, 16 left_rad_s f64, 24 right_rad_s f64 |
//! | [`Odometry`] | 40 | 8 | 0 sim_time_ns u64, 8 period u64, 16 agent u32, 20 reserved u32, 24 ticks_left i64, 32 ticks_right i64 |
//! | [`Pose`] | 24 | 8 | 0 x_m f64, 8 y_m f64, 16 theta_rad f64 |
//! | [`Truth`] | 24 + 24·[`MAX_AGENTS`] = 6168 | 8 | 0 sim_time_ns u64, 8 period u64, 16 robots u32, 20 collisions u32, 24 poses [Pose; 256] |
//! | [`Lifecycle`] | 24 | 8 | 0 time_ns u64, 8 pid u32, 12 index u32, 16 role u8, 17 event u8, 18 reserved u16, 20 restarts u32 |
//! | [`Progress`] | 32 | 8 | 0 round u64, 8 agents u32, 12 at_goal u32, 16 conflicts u32, 20 replans u32, 24 done u8, 25 reserved [u8; 7] |
//! | [`MapHeader`] | 32 | 8 | 0 round u64, 8 agent u32, 12 width u32, 16 height u32, 20 iterations u32, 24 target u32, 28 activation u8, 29 reserved [u8; 3] |
//!
//! The neural-map snapshot is a slice service of `f32` (one activation per cell, row-major) whose
//! user header is a [`MapHeader`].

use iceoryx2::prelude::ZeroCopySend;

/// The largest swarm one [`Commit`] or [`Truth`] sample can describe.
pub const MAX_AGENTS: usize = 256;

/// Marks "no cell" in a cell field.
pub const NO_CELL: u32 = u32::MAX;

/// One agent's row of the dissertation's `shared_paths` table, proposed for a decision round.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
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
}

impl Verdict {
    /// Decodes a verdict byte received from another process.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            1 => Some(Self::Accept),
            2 => Some(Self::Block),
            3 => Some(Self::Hold),
            4 => Some(Self::Replan),
            _ => None,
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
        }
    }
}

/// One agent's entry in a [`Commit`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, ZeroCopySend)]
#[repr(C)]
#[type_name("hnav::Decision")]
pub struct Decision {
    /// Agent index.
    pub agent: u32,
    /// A [`Verdict`] as `u8`.
    pub verdict: u8,
    /// Refused directions, bit `d` for direction index `d` (0 = N, clockwise to 7 = NW).
    pub refused: u8,
    /// Why a move was refused or held: a [`ConflictKind`] as `u8` (0 when accepted).
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

/// One decision round's outcome, published only after it is durable in the consensus log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ZeroCopySend)]
#[repr(C)]
#[type_name("hnav::Commit")]
pub struct Commit {
    /// The round decided.
    pub round: u64,
    /// How many entries of `decisions` are valid.
    pub count: u32,
    /// Zero.
    pub reserved: u32,
    /// The decisions, `decisions[..count]`.
    pub decisions: [Decision; MAX_AGENTS],
}

impl Default for Commit {
    fn default() -> Self {
        Self {
            round: 0,
            count: 0,
            reserved: 0,
            decisions: [Decision::default(); MAX_AGENTS],
        }
    }
}

impl Commit {
    /// The valid decisions (`count` clamped to [`MAX_AGENTS`], so a corrupt count cannot
    /// index out of bounds).
    pub fn decisions(&self) -> &[Decision] {
        &self.decisions[..(self.count as usize).min(MAX_AGENTS)]
    }
}

/// Wheel speed set-points for one robot and one control period.
#[derive(Debug, Clone, Copy, PartialEq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("hnav::WheelCommand")]
pub struct WheelCommand {
    /// Control period this command is for (lockstep) or the sender's counter (realtime).
    pub period: u64,
    /// Agent (robot) index.
    pub agent: u32,
    /// Zero for now; reserved for brake requests and similar.
    pub flags: u32,
    /// Left wheel angular speed set-point, rad/s.
    pub left_rad_s: f64,
    /// Right wheel angular speed set-point, rad/s.
    pub right_rad_s: f64,
}

/// Cumulative Hall-sensor counts of one robot, as a motor driver reports them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("hnav::Odometry")]
pub struct Odometry {
    /// Simulated time of the reading, ns since the start of the run.
    pub sim_time_ns: u64,
    /// Control period the reading closes.
    pub period: u64,
    /// Agent (robot) index.
    pub agent: u32,
    /// Zero.
    pub reserved: u32,
    /// Signed cumulative ticks of the left wheel.
    pub ticks_left: i64,
    /// Signed cumulative ticks of the right wheel.
    pub ticks_right: i64,
}

/// A planar pose in metres and radians (x right, y down the map's rows, as the grid).
#[derive(Debug, Clone, Copy, PartialEq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("hnav::Pose")]
pub struct Pose {
    /// x, metres.
    pub x_m: f64,
    /// y, metres.
    pub y_m: f64,
    /// Heading, radians.
    pub theta_rad: f64,
}

/// Ground truth from the sim: every robot's pose and the collision count so far.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[repr(C)]
#[type_name("hnav::Truth")]
pub struct Truth {
    /// Simulated time, ns since the start of the run.
    pub sim_time_ns: u64,
    /// Control period.
    pub period: u64,
    /// How many entries of `poses` are valid.
    pub robots: u32,
    /// Collisions detected since the start of the run.
    pub collisions: u32,
    /// The poses, `poses[..robots]`.
    pub poses: [Pose; MAX_AGENTS],
}

impl Default for Truth {
    fn default() -> Self {
        Self {
            sim_time_ns: 0,
            period: 0,
            robots: 0,
            collisions: 0,
            poses: [Pose::default(); MAX_AGENTS],
        }
    }
}

impl Truth {
    /// The valid poses (`robots` clamped to [`MAX_AGENTS`]).
    pub fn poses(&self) -> &[Pose] {
        &self.poses[..(self.robots as usize).min(MAX_AGENTS)]
    }
}

/// Which kind of process a [`Lifecycle`] event is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Role {
    /// The physics stepper `hnav-sim`.
    Sim = 1,
    /// The central compute block `hnav-coordinator`.
    Coordinator = 2,
    /// One robot's `hnav-agent`.
    Agent = 3,
}

impl Role {
    /// Decodes a role byte received from another process.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            1 => Some(Self::Sim),
            2 => Some(Self::Coordinator),
            3 => Some(Self::Agent),
            _ => None,
        }
    }
}

/// What happened to a process.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum LifecycleEvent {
    /// Started and attached to the run.
    Up = 1,
    /// Exited or was killed.
    Down = 2,
    /// Started again by the supervisor after a `Down`.
    Restarted = 3,
    /// Supervisor to all: every process is up, begin the run.
    Start = 4,
    /// Supervisor to all: finish cleanly and exit.
    Stop = 5,
}

impl LifecycleEvent {
    /// Decodes an event byte received from another process.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            1 => Some(Self::Up),
            2 => Some(Self::Down),
            3 => Some(Self::Restarted),
            4 => Some(Self::Start),
            5 => Some(Self::Stop),
            _ => None,
        }
    }
}

/// A process came up, went down or was restarted (published by the supervisor).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("hnav::Lifecycle")]
pub struct Lifecycle {
    /// Wall-clock time of the event, ns since the Unix epoch.
    pub time_ns: u64,
    /// OS process id.
    pub pid: u32,
    /// Agent index for [`Role::Agent`], else 0.
    pub index: u32,
    /// A [`Role`] as `u8`.
    pub role: u8,
    /// A [`LifecycleEvent`] as `u8`.
    pub event: u8,
    /// Zero.
    pub reserved: u16,
    /// Restarts of this process so far.
    pub restarts: u32,
}

/// The coordinator's running tally, published after every round (latest value only) for the
/// supervisor's progress bar and for viewers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend)]
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
    /// 1 once every agent is at its goal, else 0.
    pub done: u8,
    /// Zero.
    pub reserved: [u8; 7],
}

/// How a neural map's neurons saturate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum ActivationKind {
    /// Linear with saturation at 1.
    Linear = 1,
    /// Hyperbolic tangent.
    Tanh = 2,
}

impl ActivationKind {
    /// Decodes an activation byte received from another process.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            1 => Some(Self::Linear),
            2 => Some(Self::Tanh),
            _ => None,
        }
    }
}

/// The user header of a neural-map snapshot (`[f32]` slice, one activation per cell).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("hnav::MapHeader")]
pub struct MapHeader {
    /// Decision round after which the map was built or repaired.
    pub round: u64,
    /// Agent index.
    pub agent: u32,
    /// Grid width (cells).
    pub width: u32,
    /// Grid height (cells).
    pub height: u32,
    /// Sweeps the map took.
    pub iterations: u32,
    /// Target cell (goal or current waypoint).
    pub target: u32,
    /// An [`ActivationKind`] as `u8`.
    pub activation: u8,
    /// Zero.
    pub reserved: [u8; 3],
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
        assert_eq!(size_of::<Commit>(), 16 + 16 * MAX_AGENTS);
        assert_eq!(size_of::<Commit>(), 4112);
        assert_eq!(align_of::<Commit>(), 8);
        assert_eq!(offset_of!(Commit, round), 0);
        assert_eq!(offset_of!(Commit, count), 8);
        assert_eq!(offset_of!(Commit, reserved), 12);
        assert_eq!(offset_of!(Commit, decisions), 16);
    }

    #[test]
    fn wheel_and_odometry_layout() {
        assert_eq!(size_of::<WheelCommand>(), 32);
        assert_eq!(align_of::<WheelCommand>(), 8);
        assert_eq!(offset_of!(WheelCommand, period), 0);
        assert_eq!(offset_of!(WheelCommand, agent), 8);
        assert_eq!(offset_of!(WheelCommand, flags), 12);
        assert_eq!(offset_of!(WheelCommand, left_rad_s), 16);
        assert_eq!(offset_of!(WheelCommand, right_rad_s), 24);
        assert_eq!(size_of::<Odometry>(), 40);
        assert_eq!(align_of::<Odometry>(), 8);
        assert_eq!(offset_of!(Odometry, sim_time_ns), 0);
        assert_eq!(offset_of!(Odometry, period), 8);
        assert_eq!(offset_of!(Odometry, agent), 16);
        assert_eq!(offset_of!(Odometry, reserved), 20);
        assert_eq!(offset_of!(Odometry, ticks_left), 24);
        assert_eq!(offset_of!(Odometry, ticks_right), 32);
    }

    #[test]
    fn truth_layout() {
        assert_eq!(size_of::<Pose>(), 24);
        assert_eq!(offset_of!(Pose, x_m), 0);
        assert_eq!(offset_of!(Pose, y_m), 8);
        assert_eq!(offset_of!(Pose, theta_rad), 16);
        assert_eq!(size_of::<Truth>(), 24 + 24 * MAX_AGENTS);
        assert_eq!(size_of::<Truth>(), 6168);
        assert_eq!(align_of::<Truth>(), 8);
        assert_eq!(offset_of!(Truth, sim_time_ns), 0);
        assert_eq!(offset_of!(Truth, period), 8);
        assert_eq!(offset_of!(Truth, robots), 16);
        assert_eq!(offset_of!(Truth, collisions), 20);
        assert_eq!(offset_of!(Truth, poses), 24);
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
        assert_eq!(offset_of!(Progress, reserved), 25);
    }

    #[test]
    fn lifecycle_and_map_header_layout() {
        assert_eq!(size_of::<Lifecycle>(), 24);
        assert_eq!(align_of::<Lifecycle>(), 8);
        assert_eq!(offset_of!(Lifecycle, time_ns), 0);
        assert_eq!(offset_of!(Lifecycle, pid), 8);
        assert_eq!(offset_of!(Lifecycle, index), 12);
        assert_eq!(offset_of!(Lifecycle, role), 16);
        assert_eq!(offset_of!(Lifecycle, event), 17);
        assert_eq!(offset_of!(Lifecycle, reserved), 18);
        assert_eq!(offset_of!(Lifecycle, restarts), 20);
        assert_eq!(size_of::<MapHeader>(), 32);
        assert_eq!(align_of::<MapHeader>(), 8);
        assert_eq!(offset_of!(MapHeader, round), 0);
        assert_eq!(offset_of!(MapHeader, agent), 8);
        assert_eq!(offset_of!(MapHeader, width), 12);
        assert_eq!(offset_of!(MapHeader, height), 16);
        assert_eq!(offset_of!(MapHeader, iterations), 20);
        assert_eq!(offset_of!(MapHeader, target), 24);
        assert_eq!(offset_of!(MapHeader, activation), 28);
        assert_eq!(offset_of!(MapHeader, reserved), 29);
    }

    #[test]
    fn enums_round_trip_and_reject_unknown_bytes() {
        for v in [
            Verdict::Accept,
            Verdict::Block,
            Verdict::Hold,
            Verdict::Replan,
        ] {
            assert_eq!(Verdict::from_u8(v as u8), Some(v));
        }
        for r in [Role::Sim, Role::Coordinator, Role::Agent] {
            assert_eq!(Role::from_u8(r as u8), Some(r));
        }
        for e in [
            LifecycleEvent::Up,
            LifecycleEvent::Down,
            LifecycleEvent::Restarted,
            LifecycleEvent::Start,
            LifecycleEvent::Stop,
        ] {
            assert_eq!(LifecycleEvent::from_u8(e as u8), Some(e));
        }
        for a in [ActivationKind::Linear, ActivationKind::Tanh] {
            assert_eq!(ActivationKind::from_u8(a as u8), Some(a));
        }
        for k in 0..=7u8 {
            assert_eq!(ConflictKind::from_u8(k).map(|k| k as u8), Some(k));
        }
        assert_eq!(ConflictKind::from_u8(8), None);
        assert_eq!(LifecycleEvent::from_u8(6), None);
        for bad in [0u8, 5, 200, 255] {
            assert_eq!(Verdict::from_u8(bad), None);
            assert_eq!(Role::from_u8(bad), None);
            assert_eq!(LifecycleEvent::from_u8(bad.max(6)), None);
            assert_eq!(ActivationKind::from_u8(bad.max(3)), None);
        }
    }

    #[test]
    fn corrupt_counts_do_not_index_out_of_bounds() {
        let c = Commit {
            count: u32::MAX,
            ..Commit::default()
        };
        assert_eq!(c.decisions().len(), MAX_AGENTS);
        let t = Truth {
            robots: 7,
            ..Truth::default()
        };
        assert_eq!(t.poses().len(), 7);
    }
}
