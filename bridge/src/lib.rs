//! `hnav-bridge`: a run's topics between hosts, over Zenoh.
//!
//! iceoryx2's shared memory ends at the host. A robot that carries its own computer runs its
//! agent there, the base station runs the coordinator, and the bridge of each host forwards
//! the run's topics both ways under Zenoh key expressions `hnav/<run>/<topic>`. Robotics
//! already has a distributed engine for this (dora-rs joins its daemons with Zenoh, ROS 2 has
//! rmw_zenoh); HNAV uses it instead of a protocol of its own.
//!
//! **Must not depend on**: any HNAV crate but `hnav-runtime` (the processes whose topics it
//! carries are reached only through their messages), nor on the operator's libraries
//! (plotters, ratatui, mcap, indicatif).
//!
//! Modules, highest first (a module uses only those below it in this table; imports never run
//! back up):
//!
//! | module | what it holds |
//! |---|---|
//! | `bridge` | [`Bridge`]: one host's end: the ports, the loop, the counters |
//! | `port` | one topic's two ends: iceoryx2 in and out, Zenoh in and out, and their [`Counts`] |
//! | `outlet` | a port's way out to Zenoh, and the record of a put that held the bridge's loop |
//! | [`hosts`] | the other hosts of a placed run, followed by Zenoh liveliness tokens: the bridge's `Up` once all are heard, `Down`/`Restarted` for the robots of a host cut off and back |
//! | [`session`] | the Zenoh session (endpoints, no multicast scouting) |
//! | [`delay`] | a test-only delay on every sample from another host |
//! | [`topics`] | which topics cross, with their payload types and QoS |
//!
//! Out of iceoryx2 a sample is read in place and its bytes go straight into Zenoh's buffer;
//! into iceoryx2 the bytes are written into a loaned sample, checked there ([`Wire`]) and
//! sent, or dropped and counted. Nothing crosses twice: a bridge never forwards what its own
//! publishers brought in, and its Zenoh subscribers hear only other sessions.
//!
//! [`Wire`]: hnav_runtime::msg::Wire

mod bridge;
pub mod delay;
pub mod hosts;
mod outlet;
mod port;
pub mod session;
pub mod topics;

pub use bridge::{Bridge, BridgeError, Stopper};
pub use port::Counts;
