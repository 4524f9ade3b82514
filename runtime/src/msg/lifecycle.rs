//! The lifecycle protocol's payload and its vocabulary: which process ([`Role`], with the one
//! spelling of its name), what happened to it ([`LifecycleEvent`]), why a run is stopped
//! ([`StopReason`]), what a process is busy with before it is up ([`StartupPhase`]), and the
//! [`Lifecycle`] sample built by its constructors.
//!
//! Besides a process's `Up` and the supervisor's `Start`, `Down`, `Restarted` and `Stop`, a
//! lockstep run with a fault plan has one more exchange: the sim holds before stepping a
//! fault's period and says so with `Hold` on `ready`; the supervisor fires the fault, waits
//! until it is done (the target reaped and, if it is restarted, up again) and answers with
//! `Resume` on `lifecycle`. Both carry the period ([`Lifecycle::period`]).

use std::time::{SystemTime, UNIX_EPOCH};

use iceoryx2::prelude::ZeroCopySend;

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
    /// One host's `hnav-bridge` in a run across hosts (index: the host's place in the
    /// placement). It announces `Up` once it hears every other host's bridge.
    Bridge = 4,
}

impl Role {
    /// Decodes a role byte received from another process.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            1 => Some(Self::Sim),
            2 => Some(Self::Coordinator),
            3 => Some(Self::Agent),
            4 => Some(Self::Bridge),
            _ => None,
        }
    }

    /// The role's name: `sim`, `coordinator`, `agent` or `bridge`, the one spelling used by node names,
    /// the run registry, `hnav ps` and `hnav log show`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Sim => "sim",
            Self::Coordinator => "coordinator",
            Self::Agent => "agent",
            Self::Bridge => "bridge",
        }
    }

    /// The inverse of [`Role::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "sim" => Some(Self::Sim),
            "coordinator" => Some(Self::Coordinator),
            "agent" => Some(Self::Agent),
            "bridge" => Some(Self::Bridge),
            _ => None,
        }
    }

    /// The iceoryx2 node name of the process: `sim`, `coordinator` (a single one, index 0),
    /// `coordinator-<id>` (replica `id` of a replicated coordinator, 1-based) or
    /// `agent-<index>` (what `hnav ps` matches dead nodes against).
    pub fn node_name(self, index: u32) -> String {
        match self {
            Self::Agent => format!("{}-{index}", self.name()),
            Self::Coordinator if index > 0 => format!("{}-{index}", self.name()),
            other => other.name().to_string(),
        }
    }
}

/// The most coordinator replicas a run has (`coordinator.replicas`); a replica's index is its
/// Raft id, 1 to this, and index 0 is a single coordinator.
pub const MAX_REPLICAS: u32 = 5;

/// In JSON (run records, `hnav ps --json`) a role is its [`Role::name`].
impl serde::Serialize for Role {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for Role {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        Role::from_name(&name)
            .ok_or_else(|| serde::de::Error::custom(format!("unknown role {name:?}")))
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
    /// Supervisor to all: finish cleanly and exit; [`Lifecycle::reason`] says why.
    Stop = 5,
    /// Sim to supervisor (on `ready`): every live robot's command for the period is in, and
    /// the sim holds before stepping it because a fault is planned at that round.
    Hold = 6,
    /// Supervisor to all: the faults of the held period are done, step on.
    Resume = 7,
    /// A process to the supervisor, on `ready` before its `Up`: it has entered a slow
    /// start-up phase ([`Lifecycle::reason`] holds the [`StartupPhase`], [`Lifecycle::restarts`]
    /// its size), so that a start-up timeout can say what the process was doing.
    Phase = 8,
    /// Supervisor to all: the process exited and is not restarted (its policy, or its
    /// restart budget used up); for an agent, its robot stands for the rest of the run.
    /// [`Lifecycle::restarts`] holds the restarts it had.
    Lost = 9,
    /// Supervisor to all, once for every agent, right after the `Restarted` of the sim or
    /// the coordinator: the agent's state at that moment ([`Lifecycle::reason`] holds a
    /// [`RosterState`], [`Lifecycle::restarts`] its restarts so far). A process that was down
    /// missed the events of that time; the roster tells it what they were.
    Roster = 10,
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
            6 => Some(Self::Hold),
            7 => Some(Self::Resume),
            8 => Some(Self::Phase),
            9 => Some(Self::Lost),
            10 => Some(Self::Roster),
            _ => None,
        }
    }

    /// Lower-case name (`up`, `down`, `restarted`, `start`, `stop`, `hold`, `resume`,
    /// `phase`, `lost`, `roster`), as in `hnav log show`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Up => "up",
            Self::Down => "down",
            Self::Restarted => "restarted",
            Self::Start => "start",
            Self::Stop => "stop",
            Self::Hold => "hold",
            Self::Resume => "resume",
            Self::Phase => "phase",
            Self::Lost => "lost",
            Self::Roster => "roster",
        }
    }
}

/// A slow part of a process's start-up, reported with [`Lifecycle::phase`] when the process
/// enters it. A process that reports nothing before its `Up` is still loading its scenario and
/// map or opening its ports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum StartupPhase {
    /// An agent allocates and builds its neural map toward its goal; the size is the map's
    /// memory in MiB.
    BuildingNeuralMap = 1,
}

impl StartupPhase {
    /// Decodes a phase byte received from another process.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            1 => Some(Self::BuildingNeuralMap),
            _ => None,
        }
    }

    /// What the process is doing, for an error message: `size` is the [`Lifecycle::restarts`]
    /// field of the report.
    pub fn describe(self, size: u32) -> String {
        match self {
            Self::BuildingNeuralMap => format!("building its neural map, {size} MiB"),
        }
    }
}

/// An agent's state in a [`LifecycleEvent::Roster`] entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum RosterState {
    /// Running and announced (up since its last `Restarted`, or since the start).
    Up = 1,
    /// Dead or not yet up again, and to be restarted: its `Restarted` is still to come.
    Down = 2,
    /// Gone for good ([`LifecycleEvent::Lost`]).
    Lost = 3,
}

impl RosterState {
    /// Decodes a state byte received from another process.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            1 => Some(Self::Up),
            2 => Some(Self::Down),
            3 => Some(Self::Lost),
            _ => None,
        }
    }
}

/// Why the supervisor sends `Stop`: the coordinator logs it as the end of the run.
///
/// There is no "all at goal": the coordinator ends such a run itself, before the supervisor
/// learns of it from the progress topic.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum StopReason {
    /// Asked to stop: the run is complete, or the supervisor was signalled.
    Requested = 1,
    /// The scenario's time limit passed.
    TimeLimit = 2,
}

impl StopReason {
    /// Decodes a reason byte received from another process.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            1 => Some(Self::Requested),
            2 => Some(Self::TimeLimit),
            _ => None,
        }
    }
}

/// A process came up, went down or was restarted, or the supervisor starts or stops the run.
///
/// Built by the constructors ([`Lifecycle::up`], [`Lifecycle::down`],
/// [`Lifecycle::restarted`], [`Lifecycle::start`], [`Lifecycle::stop`]), which stamp the
/// wall-clock time and leave every byte they do not set zero.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
#[type_name("hnav::Lifecycle")]
pub struct Lifecycle {
    /// Wall-clock time of the event, ns since the Unix epoch (never used for decisions).
    pub time_ns: u64,
    /// OS process id of the process the event is about; 0 when the sender does not say.
    pub pid: u32,
    /// Agent index for [`Role::Agent`], else 0. For `Hold` and `Resume`, the low 32 bits of
    /// the period ([`Lifecycle::period`]).
    pub index: u32,
    /// A [`Role`] as `u8`. `Start` and `Stop` are addressed to every process and carry
    /// [`Role::Sim`] and index 0 as placeholders, since a receiver drops unknown roles.
    pub role: u8,
    /// A [`LifecycleEvent`] as `u8`.
    pub event: u8,
    /// For `Stop`, a [`StopReason`] as `u8`; for `Phase`, a [`StartupPhase`] as `u8`; for
    /// `Roster`, a [`RosterState`] as `u8`; zero for every other event.
    pub reason: u8,
    /// Zero.
    pub reserved: u8,
    /// Restarts of this process so far. For `Hold` and `Resume`, the high 32 bits of the
    /// period; for `Phase`, the size of the phase in the unit [`StartupPhase::describe`] names.
    pub restarts: u32,
}

impl Lifecycle {
    /// `Up` of the calling process (with its own pid): its ports are open.
    pub fn up(role: Role, index: u32) -> Self {
        Self::about(role, index, LifecycleEvent::Up, 0).with_pid(std::process::id())
    }

    /// `Down`: the process exited or was killed, after `restarts` restarts.
    pub fn down(role: Role, index: u32, restarts: u32) -> Self {
        Self::about(role, index, LifecycleEvent::Down, restarts)
    }

    /// `Restarted`: the process runs again, its `restarts`-th incarnation after the first.
    pub fn restarted(role: Role, index: u32, restarts: u32) -> Self {
        Self::about(role, index, LifecycleEvent::Restarted, restarts)
    }

    /// `Lost`: the process is gone for good, after `restarts` restarts.
    pub fn lost(role: Role, index: u32, restarts: u32) -> Self {
        Self::about(role, index, LifecycleEvent::Lost, restarts)
    }

    /// `Roster`: agent `index` is in `state` now, after `restarts` restarts.
    pub fn roster(index: u32, state: RosterState, restarts: u32) -> Self {
        Self {
            reason: state as u8,
            ..Self::about(Role::Agent, index, LifecycleEvent::Roster, restarts)
        }
    }

    /// `Start`: every process is up, begin the run.
    pub fn start() -> Self {
        Self::about(Role::Sim, 0, LifecycleEvent::Start, 0)
    }

    /// `Stop`: finish cleanly and exit, for `reason`.
    pub fn stop(reason: StopReason) -> Self {
        Self {
            reason: reason as u8,
            ..Self::about(Role::Sim, 0, LifecycleEvent::Stop, 0)
        }
    }

    /// `Hold`: the sim holds before stepping `period` (a fault is planned at that round).
    pub fn hold(period: u64) -> Self {
        Self::at_period(LifecycleEvent::Hold, period).with_pid(std::process::id())
    }

    /// `Resume`: the faults planned at `period` are done; the sim steps it.
    pub fn resume(period: u64) -> Self {
        Self::at_period(LifecycleEvent::Resume, period)
    }

    /// The period a `Hold` or `Resume` is about (meaningless for other events).
    pub fn period(&self) -> u64 {
        u64::from(self.index) | (u64::from(self.restarts) << 32)
    }

    /// An event about the sim's `period`, split over `index` (low half) and `restarts` (high
    /// half) so that the sample keeps its 24-byte layout.
    fn at_period(event: LifecycleEvent, period: u64) -> Self {
        Self::about(Role::Sim, period as u32, event, (period >> 32) as u32)
    }

    /// `Phase`: the calling process (with its own pid) has entered start-up `phase`, of
    /// `size` (see [`StartupPhase`]).
    pub fn phase(role: Role, index: u32, phase: StartupPhase, size: u32) -> Self {
        Self {
            reason: phase as u8,
            restarts: size,
            ..Self::about(role, index, LifecycleEvent::Phase, 0).with_pid(std::process::id())
        }
    }

    /// The same event about the process with id `pid`.
    pub fn with_pid(self, pid: u32) -> Self {
        Self { pid, ..self }
    }

    fn about(role: Role, index: u32, event: LifecycleEvent, restarts: u32) -> Self {
        Self {
            time_ns: wall_clock_ns(),
            pid: 0,
            index,
            role: role as u8,
            event: event as u8,
            reason: 0,
            reserved: 0,
            restarts,
        }
    }
}

/// Nanoseconds since the Unix epoch; 0 if the clock is set before it.
fn wall_clock_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::mem::{align_of, offset_of, size_of};

    const ROLES: [Role; 3] = [Role::Sim, Role::Coordinator, Role::Agent];

    #[test]
    fn lifecycle_layout() {
        assert_eq!(size_of::<Lifecycle>(), 24);
        assert_eq!(align_of::<Lifecycle>(), 8);
        assert_eq!(offset_of!(Lifecycle, time_ns), 0);
        assert_eq!(offset_of!(Lifecycle, pid), 8);
        assert_eq!(offset_of!(Lifecycle, index), 12);
        assert_eq!(offset_of!(Lifecycle, role), 16);
        assert_eq!(offset_of!(Lifecycle, event), 17);
        assert_eq!(offset_of!(Lifecycle, reason), 18);
        assert_eq!(offset_of!(Lifecycle, reserved), 19);
        assert_eq!(offset_of!(Lifecycle, restarts), 20);
    }

    #[test]
    fn enums_round_trip_and_reject_unknown_bytes() {
        for r in ROLES {
            assert_eq!(Role::from_u8(r as u8), Some(r));
        }
        for e in [
            LifecycleEvent::Up,
            LifecycleEvent::Down,
            LifecycleEvent::Restarted,
            LifecycleEvent::Start,
            LifecycleEvent::Stop,
            LifecycleEvent::Hold,
            LifecycleEvent::Resume,
            LifecycleEvent::Phase,
            LifecycleEvent::Lost,
            LifecycleEvent::Roster,
        ] {
            assert_eq!(LifecycleEvent::from_u8(e as u8), Some(e));
        }
        for r in [RosterState::Up, RosterState::Down, RosterState::Lost] {
            assert_eq!(RosterState::from_u8(r as u8), Some(r));
        }
        assert_eq!(RosterState::from_u8(0), None);
        assert_eq!(RosterState::from_u8(4), None);
        let p = StartupPhase::BuildingNeuralMap;
        assert_eq!(StartupPhase::from_u8(p as u8), Some(p));
        assert_eq!(StartupPhase::from_u8(0), None);
        assert_eq!(StartupPhase::from_u8(2), None);
        for s in [StopReason::Requested, StopReason::TimeLimit] {
            assert_eq!(StopReason::from_u8(s as u8), Some(s));
        }
        assert_eq!(LifecycleEvent::from_u8(11), None);
        for bad in [0u8, 5, 200, 255] {
            assert_eq!(Role::from_u8(bad), None);
            assert_eq!(LifecycleEvent::from_u8(bad.max(11)), None);
            assert_eq!(StopReason::from_u8(bad.max(3)), None);
        }
        assert_eq!(StopReason::from_u8(0), None);
    }

    #[test]
    fn role_names_have_one_spelling() {
        for r in ROLES {
            assert_eq!(Role::from_name(r.name()), Some(r));
            let json = serde_json::to_string(&r).unwrap();
            assert_eq!(json, format!("\"{}\"", r.name()));
            assert_eq!(serde_json::from_str::<Role>(&json).unwrap(), r);
        }
        assert_eq!(Role::from_name("robot"), None);
        assert!(serde_json::from_str::<Role>("\"robot\"").is_err());
        assert_eq!(Role::Agent.node_name(7), "agent-7");
        assert_eq!(Role::Sim.node_name(0), "sim");
        assert_eq!(Role::Coordinator.node_name(0), "coordinator");
    }

    /// The fields a lifecycle record copies (role, index, event, restarts) are what the
    /// supervisor and the coordinator sent before the constructors existed.
    #[test]
    fn constructors_fill_the_fields_the_protocol_reads() {
        let fields = |l: Lifecycle| (l.role, l.index, l.event, l.reason, l.reserved, l.restarts);
        let (sim, agent) = (Role::Sim as u8, Role::Agent as u8);
        let up = Lifecycle::up(Role::Agent, 4);
        assert_eq!(up.pid, std::process::id());
        assert_eq!(fields(up), (agent, 4, LifecycleEvent::Up as u8, 0, 0, 0));
        let down = Lifecycle::down(Role::Agent, 4, 2);
        assert_eq!(down.pid, 0);
        assert_eq!(
            fields(down),
            (agent, 4, LifecycleEvent::Down as u8, 0, 0, 2)
        );
        assert_eq!(down.with_pid(77).pid, 77);
        let back = Lifecycle::restarted(Role::Agent, 4, 3);
        assert_eq!(
            fields(back),
            (agent, 4, LifecycleEvent::Restarted as u8, 0, 0, 3)
        );
        let start = Lifecycle::start();
        assert_eq!(
            fields(start),
            (sim, 0, LifecycleEvent::Start as u8, 0, 0, 0)
        );
        let stop = Lifecycle::stop(StopReason::TimeLimit);
        assert_eq!(fields(stop), (sim, 0, LifecycleEvent::Stop as u8, 2, 0, 0));
        assert_eq!(Lifecycle::stop(StopReason::Requested).reason, 1);
        let phase = Lifecycle::phase(Role::Agent, 4, StartupPhase::BuildingNeuralMap, 430);
        assert_eq!(phase.pid, std::process::id());
        assert_eq!(
            fields(phase),
            (agent, 4, LifecycleEvent::Phase as u8, 1, 0, 430)
        );
        assert!(start.time_ns > 0);
        let lost = Lifecycle::lost(Role::Agent, 2, 3);
        assert_eq!(
            fields(lost),
            (agent, 2, LifecycleEvent::Lost as u8, 0, 0, 3)
        );
        let roster = Lifecycle::roster(5, RosterState::Down, 1);
        assert_eq!(
            fields(roster),
            (agent, 5, LifecycleEvent::Roster as u8, 2, 0, 1)
        );
    }

    /// A period travels whole in a `Hold` or `Resume`, past 32 bits too.
    #[test]
    fn hold_and_resume_carry_their_period() {
        for period in [
            0u64,
            50,
            u64::from(u32::MAX),
            u64::from(u32::MAX) + 7,
            u64::MAX,
        ] {
            let hold = Lifecycle::hold(period);
            assert_eq!(hold.event, LifecycleEvent::Hold as u8);
            assert_eq!(hold.role, Role::Sim as u8);
            assert_eq!(hold.period(), period);
            assert_eq!(hold.pid, std::process::id());
            let resume = Lifecycle::resume(period);
            assert_eq!(resume.event, LifecycleEvent::Resume as u8);
            assert_eq!(resume.period(), period);
            assert_eq!((resume.reason, resume.reserved), (0, 0));
        }
    }
}
