//! A deterministic simulation of the replicated log: one process, one seed, the real
//! [`Replica`](super::Replica) and [`Journal`](super::Journal) of three or five replicas
//! (not a model of them), a simulated network and a simulated disk, under a scheduler that
//! owns time. A nemesis kills, pauses, partitions, slows, drops, duplicates and reorders,
//! jumps clocks, and fails the disk; a checker asserts Raft's safety properties on what
//! the replicas really did, and liveness after the heal; a failing schedule is shrunk to
//! the shortest that still fails and printed with its seed. `hnav-bench raft-sim` sweeps
//! seeds (docs/explanation/raft-sim.md); `coordinator/tests/raft_sim.rs` runs a fixed set.
//!
//! Modules, highest first (each uses only those below it):
//!
//! | module | concept |
//! |---|---|
//! | `sweep` | [`sweep()`]: seeds by nemesis, the table, failures shrunk |
//! | `shrink` | [`shrink()`]: delta debugging of a failing schedule |
//! | `world` | [`run`]: the scheduler that owns time, and one run of the cluster |
//! | `node` | one coordinator process: its replica on the simulated disk, its lead, its life |
//! | `checker` | [`Checker`]: the safety properties, [`Violation`] |
//! | `nemesis` | [`Nemesis`], [`Action`], [`Event`]: the faults, a run's schedule, its text |
//! | `network` | the links, cut or not, and when a message arrives |
//! | `disk` | [`SimDisk`]: durable and unsynced bytes, failed writes and fsyncs, power loss |
//! | `clock` | [`Time`], and a replica's tick clock, normal, fast or stalled |
//! | `rng` | the seeded random streams |

mod checker;
mod clock;
mod disk;
mod nemesis;
mod network;
mod node;
mod rng;
mod shrink;
mod sweep;
mod world;

pub use checker::{Checker, Property, Violation};
pub use clock::Time;
pub use disk::{DiskFault, SimDisk};
pub use nemesis::{parse, schedule, text, Action, Event, Nemesis, ParseError, Target};
pub use shrink::shrink;
pub use sweep::{shrunk, sweep, Failure, Report, Row, Sweep};
pub use world::{run, Config, Outcome, Sabotage, CATCH_UP, HEAL, LIVENESS};
