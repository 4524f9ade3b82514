//! Raft's log lines into the coordinator's `tracing` output.
//!
//! The `raft` crate logs through `slog`; the runtime logs through `tracing`. Elections, term
//! changes and refused messages are what an operator reads after a failover, so they are
//! forwarded (errors and warnings as such, the rest at debug level, where Raft's per-message
//! chatter belongs) instead of being dropped.

use slog::{Drain, Level, OwnedKVList, Record};

/// A `slog` drain that writes each record's message to `tracing`, tagged with the replica.
struct ToTracing {
    replica: u64,
}

impl Drain for ToTracing {
    type Ok = ();
    type Err = slog::Never;

    fn log(&self, record: &Record<'_>, _: &OwnedKVList) -> Result<(), slog::Never> {
        let (replica, msg) = (self.replica, record.msg());
        match record.level() {
            Level::Critical | Level::Error => tracing::error!(replica, "raft: {msg}"),
            Level::Warning => tracing::warn!(replica, "raft: {msg}"),
            Level::Info => tracing::debug!(replica, "raft: {msg}"),
            Level::Debug | Level::Trace => tracing::trace!(replica, "raft: {msg}"),
        }
        Ok(())
    }
}

/// The logger a replica's Raft node writes to.
pub(super) fn logger(replica: u64) -> slog::Logger {
    slog::Logger::root(ToTracing { replica }, slog::o!())
}
