//! # hnav-runtime
//!
//! The shared foundation of every HNAV process: the grid and its map files, the message
//! contracts that cross process boundaries, the typed transport over iceoryx2 shared memory,
//! and the scenario format that describes a run.
//!
//! Every other crate (`hnav-agent`, `hnav-coordinator`, `hnav-sim`, `hnav-bench`) depends on
//! this one and on nothing else of HNAV, so the contracts live in exactly one place.
//!
//! | module | what it holds |
//! |---|---|
//! | [`grid`] | occupancy grids, terrain, coordinates, octile neighbours, MovingAI `.map`/`.scen` files |
//! | [`scenario`] | the TOML description of a run, validated with file/line errors |
//! | [`msg`] | `#[repr(C)]` zero-copy payloads (Candidate, Commit, WheelCommand, ...) and their layouts |
//! | [`topics`] | the run's service names and their QoS, defined once for every process |
//! | [`report`] | the run report `DIR/report.svg` (plotters, SVG): map, committed cells, true trajectories, conflicts, replans, collisions, neural-map heatmaps |
//! | [`rejected`] | the classes of hostile or malformed messages a receiver drops, and their counts for the run summary |
//! | [`plan`] | [`PlanResult`](plan::PlanResult), the answer to one planning query, whichever planner gave it |
//! | [`placement`] | `hosts.toml`: which host runs which process of a run across hosts, and how their bridges reach each other |
//! | [`launch`] | the command line every process of a run shares, and the start-up handshake with the supervisor |
//! | [`transport`] | run-scoped iceoryx2 services: publisher+notifier, subscriber+listener, the one [`Waiter`](transport::Waiter) every process blocks in |
//! | [`supervisor`] | starting, watching, restarting and stopping a run's processes; the registry behind `hnav ps`. It sits on top: only `monitor` uses it |
//! | [`recording`] | a run's recording on disk: pose samples (truth and estimate) and neural-map snapshots, for the report, the MCAP export and replay |
//! | [`monitor`] | the live view behind `hnav top`: a feed of a run's updates, the view's state, its ratatui drawing |
//! | [`consensus_log`] | the durable consensus log: record types, segment format, reader, verifier |
//! | [`invocation`] | `DIR/invocation.json`: the scenario file and command-line overrides a run was started with, for replay and export |
//! | [`export`] | `hnav log export`: a run's log and recording as an MCAP file for Foxglove Studio |
//! | [`clock`] | `CLOCK_MONOTONIC` in nanoseconds: one time base for the supervisor, the processes and observers of a host |
//! | [`health`] | a process's heartbeat, beaten from its main loop for the supervisor's hang detection |
//! | [`hash`] | FNV-1a 64 and SplitMix64: digests and seeded random numbers, stable across platforms |
//! | [`diag`] | printing that never panics: `outln!`/`errln!` and the `tracing` writer drop (and count) a failed write |
//! | [`file_lock`] | exclusive `flock` locks that name their holder: a run's directory, its run id, its consensus log |
//! | [`logging`] | `tracing` set-up shared by the binaries, with iceoryx2's own logs routed into it |

pub mod clock;
pub mod consensus_log;
pub mod diag;
pub mod export;
pub mod file_lock;
pub mod grid;
pub mod hash;
pub mod health;
pub mod invocation;
pub mod launch;
pub mod logging;
pub mod monitor;
pub mod msg;
pub mod placement;
pub mod plan;
pub mod recording;
pub mod rejected;
pub mod report;
pub mod scenario;
pub mod supervisor;
pub mod topics;
pub mod transport;
