//! # hnav-runtime
//!
//! What every HNAV process shares, and nothing else: the grid and its map files, the message
//! contracts that cross process boundaries, the typed transport over iceoryx2 shared memory,
//! the scenario format that describes a run, the consensus-log format, and the toolkit for
//! files that must survive a crash.
//!
//! The process crates (`hnav-agent`, `hnav-coordinator`, `hnav-sim`, `hnav-bridge`) depend on
//! this one and on no other HNAV crate, so the contracts live in exactly one place. The
//! operator's side (`hnav-operator`: supervisor, live view, report, export, recording, the
//! `hnav` binary) sits above them; `hnav-bench` and `hnav-tests` may use everything.
//!
//! **Must not depend on**: any other HNAV crate, nor on the operator's libraries (plotters,
//! ratatui, mcap, indicatif): every process binary links this crate, and none of them draws,
//! exports or shows progress.
//!
//! Modules, highest first (a module uses only those below it in this table; imports never run
//! back up):
//!
//! | module | what it holds |
//! |---|---|
//! | [`launch`] | the command line every process of a run shares, and the start-up handshake with the supervisor |
//! | [`health`] | a process's heartbeat, beaten from its main loop for the supervisor's hang detection |
//! | [`consensus_log`] | the durable consensus log: record types, segment format, writer, reader, verifier |
//! | [`placement`] | `hosts.toml`: which host runs which process of a run across hosts, and how their bridges reach each other |
//! | [`criteria`] | the criteria only a process can measure (motor energy, candidate-to-commit latency) and the run-directory files that carry them to the summary |
//! | [`scenario`] | the TOML description of a run, validated with file/line errors |
//! | [`rejected`] | the classes of hostile or malformed messages a receiver drops, and their counts for the run summary |
//! | [`layout`] | the table of every payload's size, alignment and field offsets, and of the topic that carries it, for clients in other languages (`hnav layout --json`) |
//! | [`topics`] | the run's service names and their QoS, defined once for every process |
//! | [`transport`] | run-scoped iceoryx2 services: publisher+notifier, subscriber+listener, the [`Waiter`](transport::Waiter) every process blocks in (or, with one source, the [`SingleWaiter`](transport::SingleWaiter)) |
//! | [`plan`] | [`PlanResult`](plan::PlanResult), the answer to one planning query, whichever planner gave it |
//! | [`grid`] | occupancy grids, terrain, coordinates, octile neighbours, MovingAI `.map`/`.scen` files |
//! | [`msg`] | `#[repr(C)]` zero-copy payloads (Candidate, Commit, WheelCommand, ...) and their layouts |
//! | [`logging`] | `tracing` set-up shared by the binaries, with iceoryx2's own logs routed into it |
//! | [`file_lock`] | exclusive `flock` locks that name their holder: a run's directory, its run id, its consensus log |
//! | [`durable`] | files that must survive a crash: whole-file replace, checkpoint slots, framed append logs |
//! | [`clock`] | `CLOCK_MONOTONIC` in nanoseconds: one time base for the supervisor, the processes and observers of a host |
//! | [`hash`] | FNV-1a 64 and SplitMix64: digests and seeded random numbers, stable across platforms |
//! | [`diag`] | printing that never panics: `outln!`/`errln!` and the `tracing` writer drop (and count) a failed write |

pub mod clock;
pub mod consensus_log;
pub mod criteria;
pub mod diag;
pub mod durable;
pub mod file_lock;
pub mod grid;
pub mod hash;
pub mod health;
pub mod launch;
pub mod layout;
pub mod logging;
pub mod msg;
pub mod placement;
pub mod plan;
pub mod rejected;
pub mod scenario;
pub mod topics;
pub mod transport;
