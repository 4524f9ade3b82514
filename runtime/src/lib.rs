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
//! | [`transport`] | run-scoped iceoryx2 services: publisher+notifier, subscriber+listener, WaitSets |
//! | [`logging`] | `tracing` set-up shared by the binaries, with iceoryx2's own logs routed into it |

pub mod grid;
pub mod logging;
pub mod msg;
pub mod scenario;
pub mod transport;
