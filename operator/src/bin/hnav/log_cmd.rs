//! `hnav log verify|show|replay|export DIR`: inspect a run's consensus log (never modifies it). DIR is the
//! log directory or the run directory holding it in `log/`.
//!
//! Exit codes of `verify`: 0 intact, 1 not intact (torn tail, corruption, order problems),
//! 2 the directory cannot be read as a log at all (missing, unreadable, no segments).
//! `show`: 0 every complete record printed (those `--round`, `--agent` and `--kind` keep; a
//! torn tail is noted on stderr), 1 reading stopped
//! at corruption (records before it are printed), 2 unreadable as for `verify`.
//! `replay` (`log_replay_cmd`): 0 identical, 1 diverged, 2 not a replayable run.
//! `export` (`log_export_cmd`): 0 written, 1 the output cannot be written, 2 unreadable input.
//!
//! A run with coordinator replicas keeps one log per replica in `log/<id>/`: `verify` checks
//! each (the exit code is the worst), `show` prints the log of the replica that decided the
//! most (saying which on stderr); a replica's own directory can be named as well.

use std::io::Write;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Subcommand;

use crate::pager::Paged;
use hnav_runtime::consensus_log::filter::{parse_kind, parse_rounds};
use hnav_runtime::consensus_log::show::{describe, to_json};
use hnav_runtime::consensus_log::{
    list_segments, read_decided, replica_dirs, segment_name, verify, LogReader, Record,
    RecordFilter, VerifyStatus,
};

/// `hnav log` subcommands.
#[derive(Subcommand, Debug)]
pub enum LogCommand {
    /// Check a consensus log: exit 0 when intact, 1 when torn/corrupt/out of order, 2 when
    /// unreadable.
    Verify {
        /// The log directory (holding seg-00000000.hlog, ...) or the run directory (holding
        /// it in log/).
        dir: PathBuf,
    },
    /// Print one line per record (speeds and priorities to three decimals; --json keeps
    /// every digit). --round, --agent and --kind narrow what is printed; together, a record
    /// must pass each.
    Show {
        /// The log directory or the run directory.
        dir: PathBuf,
        /// One JSON object per line instead of text.
        #[arg(long)]
        json: bool,
        /// Only rounds A to B, both included: A..B, A.., ..B, or one round A (records without
        /// a round, the header, are left out).
        #[arg(long, value_name = "A..B", value_parser = parse_rounds)]
        round: Option<RangeInclusive<u64>>,
        /// Only what concerns agent N: its decisions (a round without one is left out), its
        /// lifecycle events, replans and unreachable reports.
        #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = crate::arg_values::agent_index)]
        agent: Option<u32>,
        /// Only records of these kinds (comma-separated or repeated): header, round,
        /// lifecycle, replan, unreachable, end, raft-entry, raft-state, snapshot.
        #[arg(long, value_name = "KIND", value_delimiter = ',', value_parser = parse_kind)]
        kind: Vec<String>,
        /// Print straight to the terminal: without it, output to a terminal goes through
        /// `$HNAV_PAGER`, `$PAGER` or `less` (a pipe or a file is never paged).
        #[arg(long)]
        no_pager: bool,
    },
    /// Run a lockstep run again from its scenario and seed and check that every round
    /// decides as logged: exit 0 identical, 1 diverged (the first divergence is printed), 2
    /// not a replayable run (realtime, no invocation.json, the scenario changed).
    Replay(crate::log_replay_cmd::ReplayArgs),
    /// Write the run as an MCAP file for Foxglove Studio: poses, committed cells, decisions,
    /// replans and neural maps as JSON channels. Exit 0 written, 1 the file cannot be
    /// written, 2 the run cannot be read.
    Export(crate::log_export_cmd::ExportArgs),
}

/// Runs a `hnav log` subcommand.
pub fn run(cmd: LogCommand) -> ExitCode {
    match cmd {
        LogCommand::Verify { dir } => verify_cmd(&log_dir(&dir)),
        LogCommand::Show {
            dir,
            json,
            round,
            agent,
            kind,
            no_pager,
        } => {
            let filter = RecordFilter {
                rounds: round,
                agent,
                kinds: kind,
            };
            let out = Paged::start(!no_pager);
            show_cmd(&log_dir(&dir), json, &filter, out)
        }
        LogCommand::Replay(args) => crate::log_replay_cmd::run(args),
        LogCommand::Export(args) => crate::log_export_cmd::run(args),
    }
}

/// The log directory `dir` names: `dir` itself if it holds a segment, else `dir/log` if that
/// is a directory (`dir` is a run directory), else `dir` (whose errors then name it).
fn log_dir(dir: &Path) -> PathBuf {
    let has_segment = std::fs::read_dir(dir).is_ok_and(|entries| {
        entries.flatten().any(|e| {
            let name = e.file_name();
            let name = name.to_string_lossy();
            name.starts_with("seg-") && name.ends_with(".hlog")
        })
    });
    let inner = dir.join("log");
    if !has_segment && inner.is_dir() {
        inner
    } else {
        dir.to_path_buf()
    }
}

/// The replicas' logs under `dir` when `dir` holds no segment of its own (a run with
/// replicas), else none.
fn replicas_in(dir: &Path) -> Vec<PathBuf> {
    if list_segments(dir).is_ok_and(|s| !s.is_empty()) {
        return Vec::new();
    }
    replica_dirs(dir)
        .map(|r| r.into_iter().map(|(_, d)| d).collect())
        .unwrap_or_default()
}

fn verify_cmd(dir: &Path) -> ExitCode {
    let mut dirs = replicas_in(dir);
    if dirs.is_empty() {
        dirs.push(dir.to_path_buf());
    }
    let mut worst = 0;
    for (i, d) in dirs.iter().enumerate() {
        let report = verify(d);
        let sep = if i > 0 { "\n" } else { "" };
        // A closed stdout must not turn into a panic; the exit code still tells.
        let _ = write!(std::io::stdout().lock(), "{sep}{}", report.render());
        worst = worst.max(match report.status() {
            VerifyStatus::Intact => 0,
            VerifyStatus::NotIntact => 1,
            VerifyStatus::Unreadable => 2,
        });
    }
    ExitCode::from(worst)
}

/// Prints the records `filter` keeps to `out` (a pager on a terminal), then waits for the
/// pager; errors go to standard error, after the lines printed so far.
fn show_cmd(dir: &Path, json: bool, filter: &RecordFilter, out: Paged) -> ExitCode {
    let mut out = std::io::BufWriter::new(out);
    let code = show_records(dir, json, filter, &mut out);
    let _ = out.flush();
    if let Ok(paged) = out.into_inner() {
        paged.finish();
    }
    code
}

fn show_records(dir: &Path, json: bool, filter: &RecordFilter, out: &mut impl Write) -> ExitCode {
    let dir = if replicas_in(dir).is_empty() {
        dir.to_path_buf()
    } else {
        match read_decided(dir) {
            Ok(d) => {
                hnav_runtime::errln!("note: the log of the replica that decided the most:");
                hnav_runtime::errln!("note: {}", d.dir.display());
                d.dir
            }
            Err(e) => {
                hnav_runtime::errln!("error: {e}");
                return ExitCode::from(if e.is_unreadable() { 2 } else { 1 });
            }
        }
    };
    let mut reader = match LogReader::open(&dir) {
        Ok(r) => r,
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            return ExitCode::from(if e.is_unreadable() { 2 } else { 1 });
        }
    };
    let mut width = 0;
    loop {
        let (pos, record) = match reader.next_record() {
            Ok(Some(next)) => next,
            Ok(None) => break,
            Err(e) => {
                let _ = out.flush();
                hnav_runtime::errln!("error: {e}");
                return ExitCode::from(if e.is_unreadable() { 2 } else { 1 });
            }
        };
        if let Record::Header(h) = &record {
            width = h.width;
        }
        let Some(record) = filter.apply(&record) else {
            continue;
        };
        let written = if json {
            writeln!(out, "{}", to_json(&pos, &record, width))
        } else {
            writeln!(out, "{}", describe(&record, width))
        };
        if written.is_err() {
            // Reader gone (e.g. `| head`): stop quietly.
            return ExitCode::SUCCESS;
        }
    }
    let _ = out.flush();
    if let Some(t) = reader.torn_tail() {
        hnav_runtime::errln!(
            "note: torn tail: {} bytes at {} byte {} ({})",
            t.bytes,
            segment_name(t.segment),
            t.offset,
            t.problem
        );
    }
    ExitCode::SUCCESS
}
