//! Message contracts: the payloads that cross process boundaries.
//!
//! Every type here is `#[repr(C)]`, [`ZeroCopySend`](iceoryx2::prelude::ZeroCopySend) and
//! carries a `#[type_name("hnav::...")]` so that two separately built binaries (or a foreign
//! client using the iceoryx2 C++ or Python bindings) agree on its identity. Layouts contain no implicit padding: every gap is an explicit
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
//! layout tests of each submodule, so this table cannot drift from the code.
//!
//! | type | size | align | fields (offset: name type) |
//! |---|---|---|---|
//! | [`Candidate`] | 40 | 8 | 0 round u64, 8 agent u32, 12 current u32, 16 next u32, 20 probable u32, 24 priority f32, 28 speed f32, 32 flags u32, 36 reserved u32 |
//! | [`Decision`] | 16 | 4 | 0 agent u32, 4 verdict u8, 5 refused u8, 6 kind u8, 7 reserved u8, 8 cell u32, 12 waypoint u32 |
//! | [`CommitHeader`] | 16 | 8 | 0 round u64, 8 count u32, 12 term u32 |
//! | [`WheelCommand`] | 32 | 8 | 0 period u64, 8 agent u32, 12 flags u32, 16 left_rad_s f64, 24 right_rad_s f64 |
//! | [`Odometry`] | 64 | 8 | 0 sim_time_ns u64, 8 period u64, 16 agent u32, 20 flags u32, 24 ticks_left i64, 32 ticks_right i64, 40 fix Pose |
//! | [`Pose`] | 24 | 8 | 0 x_m f64, 8 y_m f64, 16 theta_rad f64 |
//! | [`TruthHeader`] | 24 | 8 | 0 sim_time_ns u64, 8 period u64, 16 robots u32, 20 collisions u32 |
//! | [`Estimate`] | 40 | 8 | 0 sim_time_ns u64, 8 agent u32, 12 reserved u32, 16 pose Pose |
//! | [`Lifecycle`] | 24 | 8 | 0 time_ns u64, 8 pid u32, 12 index u32, 16 role u8, 17 event u8, 18 reason u8, 19 reserved u8, 20 restarts u32 |
//! | [`Progress`] | 32 | 8 | 0 round u64, 8 agents u32, 12 at_goal u32, 16 conflicts u32, 20 replans u32, 24 done u8, 25 reserved [u8; 7] |
//! | [`Heartbeat`] | 32 | 8 | 0 t_ns u64, 8 seq u64, 16 pid u32, 20 index u32, 24 role u8, 25 reserved [u8; 7] |
//! | [`View`] | 416 | 8 | 0 sim_time_ns u64, 8 period u64, 16 agent u32, 20 x0 u32, 24 y0 u32, 28 size u32, 32 seen [u32; 32], 160 blocked [u32; 32], 288 moving [u32; 32] |
//! | [`MoversHeader`] | 16 | 8 | 0 sim_time_ns u64, 8 period u64 |
//! | [`MoverPlace`] | 32 | 8 | 0 mover u32, 4 reserved u32, 8 pose Pose |
//! | [`WheelsHeader`], [`OdometryHeader`], [`ViewsHeader`] | 8 | 4 | 0 first u32, 4 count u32 |
//! | [`Sighting`] | 152 | 8 | 0 round u64, 8 agent u32, 12 count u32, 16 closed u32, 20 reserved u32, 24 cells [u32; 32] |
//! | [`WorldHeader`] | 24 | 8 | 0 round u64, 8 closed u32, 12 opened u32, 16 to u32, 20 reserved u32 |
//! | [`MapHeader`] | 32 | 8 | 0 round u64, 8 agent u32, 12 width u32, 16 height u32, 20 iterations u32, 24 target u32, 28 activation u8, 29 reserved [u8; 3] |
//!
//! A round's commit is a slice service of [`Decision`] (one per agent of the run) whose user
//! header is a [`CommitHeader`]; the ground truth is a slice service of [`Pose`] (one per
//! robot) whose user header is a [`TruthHeader`]. Both are sized to the run when their
//! services are created, so nothing in a sample is an array of [`MAX_AGENTS`]: a run of 6
//! robots sends 96 bytes of decisions a round, one of 1 000 sends 16 000. Readers take them
//! as a [`CommitView`] or [`TruthView`] borrowed from the sample; [`Commit`] and [`Truth`]
//! are the same held in memory (a replay, an export).
//!
//! The neural-map snapshot is a slice service of `f32` (one activation per cell, row-major) whose
//! user header is a [`MapHeader`]; the coordinator's map of a changing world is a slice service
//! of `u32` (the addressees' bits, then the cells) whose user header is a [`WorldHeader`]; the movers' places are a slice service of
//! [`MoverPlace`] whose user header is a [`MoversHeader`].
//!
//! A robot's wheel commands, odometry and views travel per agent process: `wheels/<first>`
//! is a slice of [`WheelCommand`] with a [`WheelsHeader`], `odom/<first>` of [`Odometry`]
//! with an [`OdometryHeader`], `view/<first>` of [`View`] with a [`ViewsHeader`], where
//! `first` is the process's first robot (`batch` says why).
//!
//! | module | payloads |
//! |---|---|
//! | `batch` | one agent process's robots in one sample: [`WheelsHeader`], [`OdometryHeader`], [`ViewsHeader`] |
//! | `round` | the decision round: [`Candidate`], [`Decision`], [`CommitHeader`], [`CommitView`], [`Commit`], [`Progress`] |
//! | `motion` | wheels, ground truth and estimates: [`WheelCommand`], [`Odometry`], [`Pose`], [`TruthHeader`], [`TruthView`], [`Truth`], [`Estimate`] |
//! | `lifecycle` | the supervisor's protocol: [`Role`] and its names, [`LifecycleEvent`], [`StopReason`], [`StartupPhase`], [`Lifecycle`] and its constructors |
//! | `map` | the neural-map snapshot: [`MapHeader`], [`ActivationKind`] |
//! | `health` | a process's proof of life: [`Heartbeat`] |
//! | `sensing` | what a robot's range sensor sees, and the movers it may see: [`View`], [`MoversHeader`], [`MoverPlace`] |
//! | `world` | the shared picture of a changing world: [`Sighting`], [`WorldHeader`] |
//! | [`wire`] | a payload as its bytes, checked on arrival, for links that leave the host ([`Wire`], [`WireSlice`]) |

mod batch;
mod health;
mod lifecycle;
mod map;
mod motion;
mod round;
mod sensing;
pub mod wire;
mod world;

pub use batch::{OdometryHeader, ViewsHeader, WheelsHeader};
pub use health::Heartbeat;
pub use lifecycle::{
    Lifecycle, LifecycleEvent, Role, RosterState, StartupPhase, StopReason, MAX_REPLICAS,
};
pub use map::{ActivationKind, MapHeader};
pub use motion::{Estimate, Odometry, Pose, Truth, TruthHeader, TruthView, WheelCommand};
pub use round::{
    Candidate, CandidateFlags, Commit, CommitHeader, CommitView, ConflictKind, Decision, Progress,
    Verdict,
};
pub use sensing::{MoverPlace, MoversHeader, View, VIEW_EDGE};
pub use wire::{Wire, WireError, WireSlice};
pub use world::{Sighting, WorldHeader, SIGHTING_CELLS};

/// The largest swarm a run may hold.
///
/// No message is an array of this length: commits, ground truth and the world's addressees
/// are slices sized to the run. It bounds what a receiver accepts as an agent index and what
/// a scenario may ask for: 4 096 is four times the largest swarm measured on one machine
/// (1 000 robots, `docs/explanation/performance.md`), and a run's per-run tables (progress, the
/// supervisor's roster) stay small at that size.
pub const MAX_AGENTS: usize = 4096;

/// Marks "no cell" in a cell field.
pub const NO_CELL: u32 = u32::MAX;
