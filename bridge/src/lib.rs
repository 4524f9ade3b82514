//! `hnav-bridge`: a run's topics between hosts, over Zenoh.
//!
//! iceoryx2's shared memory ends at the host. A robot that carries its own computer runs its
//! agent there, the base station runs the coordinator, and the bridge of each host forwards
//! the run's topics both ways under Zenoh key expressions `hnav/<run>/<topic>`. Robotics
//! already has a distributed engine for this (dora-rs joins its daemons with Zenoh, ROS 2 has
//! rmw_zenoh); HNAV uses it instead of a protocol of its own.
//!
//! - [`topics`]: which topics cross, with their payload types and QoS.
//! - [`session`]: the Zenoh session (endpoints, no multicast scouting).
//! - [`hosts`]: the other hosts of a placed run, followed by Zenoh liveliness tokens: the
//!   bridge's `Up` once all are heard, `Down`/`Restarted` for the robots of a host cut off
//!   and back.
//! - [`delay`]: a test-only delay on every sample from another host.
//! - [`Bridge`]: one host's end: the ports, the loop, the counters.
//! - `outlet` (private): a port's way out to Zenoh; in a realtime run the samples that must
//!   not be dropped (lifecycle, `ready`) go through a thread of their own, so that a link
//!   that cannot take them never holds the loop.
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

pub use bridge::{Bridge, BridgeError, Counts, Stopper};
