//! The consensus log as the operator reads it: the `hnav log` command (show, verify, tail,
//! a run directory) and the run summary read from a log.
//!
//! Every log here is written by the real
//! [`LogWriter`](hnav_runtime::consensus_log::LogWriter), with the fixtures of the format's
//! own tests (one copy, in `runtime/tests/consensus_log/fixtures.rs`).

mod cli;
#[allow(dead_code)]
#[path = "../../../runtime/tests/consensus_log/fixtures.rs"]
mod fixtures;
mod run_dir;
mod show_filters;
mod summary;
