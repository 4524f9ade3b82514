//! The coordinator's replication (`coordinator.replicas` 3 or 5): one replica's Raft peer, its
//! journal on disk, its link to the other replicas, and its end of the cluster as the
//! coordinator process uses it.
//!
//! The dissertation's consensus log is a replicated state machine: a cluster of coordinators
//! agrees on every decision, and a cluster of `2f + 1` keeps deciding while `f` are lost. The
//! agreement is Raft from a well-kept library, the `raft` crate (the consensus core of TiKV),
//! not a hand-written one. It is a passive state machine: the owner ticks it, steps it with
//! the messages other replicas sent, and takes what it has to persist, send and apply from its
//! `Ready` cycle. That fits the coordinator's loop (one thread, a [`Waiter`]) without an async
//! runtime, which is why it was picked over `openraft` (async, tokio).
//!
//! [`Replica`] owns that cycle, in the order Raft's safety needs: new entries and the hard
//! state reach the storage before the messages that acknowledge them are released
//! ([`Replica::take_messages`]), and only entries a majority holds come out of
//! [`Replica::take_committed`]. What the coordinator proposes is opaque bytes (an encoded
//! round record); what it gets back, in the same order on every replica, is the committed
//! sequence.
//!
//! Raft reads its log from the library's `MemStorage`; a durable replica also writes every
//! entry and hard state to its [`Journal`], the consensus-log segments of `DIR/log/<id>/`,
//! and flushes it before the messages that acknowledge them leave ([`Replica::durable`]).
//! A replica restarted over its journal comes back with its term, vote and entries, and Raft
//! hands its committed entries out again. [`RaftLink`] carries the messages between processes
//! on the HNAV transport (`raft/<i>` topics). [`RaftLog`] is what the coordinator process
//! holds: the peer over its journal and link, ticked on the replica's clock; it proposes the
//! rounds a leader decides and hands out the records other leaders committed. [`Overheard`]
//! keeps what a following replica hears of the supervisor until it comes to lead.
//!
//! The *format* of a replica's log (its records, how the decided sequence is resolved from
//! them, the role file) stays in [`hnav_runtime::consensus_log::replicated`]: the run summary,
//! `hnav log show`, `replay`, the exports and the operator's `hnav ps` and `hnav kill` read it
//! there, and the operator must not depend on this crate. What lives here is the writing side,
//! which only a coordinator process runs.
//!
//! | module | concept |
//! |---|---|
//! | [`sim`] | the deterministic simulation of the replicated log: real replicas, simulated network, disk and time, a nemesis, a checker |
//! | `raft_log` | [`RaftLog`]: the peer, journal and link together, as the coordinator uses them |
//! | `overheard` | [`Overheard`]: the supervisor's liveness events a following replica keeps |
//! | `lead` | [`Lead`]: when a replica may decide, and when its decision is final |
//! | `peer` | [`Replica`], [`ReplicaConfig`], [`Role`], [`Committed`]: one voter and its `Ready` cycle |
//! | `journal` | [`Journal`]: the Raft log on disk, in the consensus-log segments, compacted behind a snapshot |
//! | `store` | [`Store`]: Raft's storage in memory and the last snapshot |
//! | `link` | [`RaftLink`]: the `raft/<i>` topics between replicas |
//! | `wire` | [`encode`], [`decode`]: a Raft message as bytes |
//! | `log_bridge` | Raft's `slog` lines into `tracing` |
//! | `error` | [`ReplicaError`] |
//!
//! [`Waiter`]: hnav_runtime::transport::Waiter

mod error;
mod journal;
mod lead;
mod link;
mod log_bridge;
mod overheard;
mod peer;
mod raft_log;
pub mod sim;
mod store;
#[cfg(test)]
mod tests;
mod wire;

pub use error::ReplicaError;
pub use journal::Journal;
pub use lead::Lead;
pub use link::{topic, Inbox, RaftLink, MAX_ENTRIES_BYTES, MAX_MESSAGE_BYTES};
pub use overheard::Overheard;
pub use peer::{Committed, Replica, ReplicaConfig, Role};
pub use raft_log::RaftLog;
pub use store::Store;
pub use wire::{decode, encode};
