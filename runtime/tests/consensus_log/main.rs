//! The consensus log: the format (records, framing, torn tails vs corruption, segments,
//! verify) and the writer (reopen, recovery on open, rollover). The `hnav log` command and
//! the run summary read from a log are tested beside the binary (`operator/tests/log_cli`).
//!
//! Every log here is written by the real [`LogWriter`](hnav_runtime::consensus_log::LogWriter);
//! a test that needs a broken log breaks the writer's output (cuts, flipped bits, removed or
//! swapped frames).

mod fixtures;
mod format;
mod lost;
mod writer;
