//! The consensus log: the format (records, framing, torn tails vs corruption, segments,
//! verify), the writer (reopen, recovery on open, rollover), the `hnav log` command and the
//! run summary read from a log.
//!
//! Every log here is written by the real [`LogWriter`](hnav_runtime::consensus_log::LogWriter);
//! a test that needs a broken log breaks the writer's output (cuts, flipped bits, removed or
//! swapped frames).

mod cli;
mod fixtures;
mod format;
mod lost;
mod run_dir;
mod summary;
mod writer;
