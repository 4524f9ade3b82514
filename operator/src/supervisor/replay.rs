//! `hnav log replay DIR`: start a lockstep run again and check that every round decides
//! exactly as its consensus log says.
//!
//! A lockstep run is a function of its scenario and seed (`docs/explanation/design.md`),
//! so the same scenario, seed, agents, coordinator replicas and fault plan must write the same
//! log. The replay takes them from `DIR/invocation.json` ([`crate::invocation`]), refuses a
//! scenario whose
//! hash is no longer the log header's (the file or its map changed since), runs it through
//! the supervisor library ([`super::run::run`], as `hnav run` does) under a fresh run id
//! into a temporary run directory, and compares the two logs decoded, record by record
//! ([`hnav_runtime::consensus_log::compare()`]). The temporary directory is removed afterwards,
//! whatever happened.
//!
//! A run with coordinator replicas is replayed with as many replicas (an `invocation.json`
//! older than its `replicas` field: as many as the log has replica directories). On each
//! side the log compared is the one [`read_decided`] takes from `DIR/log`: the replica that
//! decided the most, the lowest id among equals. In lockstep every replica decides the very
//! records a single coordinator decides (`tests/tests/replicas.rs`), so which replica led
//! when does not matter; only how far each had learned of the commits when the run ended
//! does, and the one that decided the most knew all of them. A replica's log compacted behind
//! a snapshot holds only the records after it: the two logs are compared from the first
//! record both still hold.

use std::path::{Path, PathBuf};

use super::run::{run, RunError, RunOptions};
use crate::invocation::{Invocation, InvocationError, FILE as INVOCATION};
use hnav_runtime::consensus_log::{
    compare, read_decided, replica_dirs, Comparison, Decided, LogError, Record, RunHeader,
    REPLICATED_VERSION,
};
use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::scenario::{ClockMode, ScenarioError};
use hnav_runtime::transport::RunId;

/// What a replay needs.
#[derive(Clone, Debug)]
pub struct ReplayOptions {
    /// The run directory (holding `log/` and `invocation.json`), or its `log/`.
    pub dir: PathBuf,
    /// Where `hnav-sim`, `hnav-coordinator` and `hnav-agent` are.
    pub bin_dir: PathBuf,
    /// A progress bar on stderr (a terminal), else progress lines.
    pub progress: bool,
    /// The replay's run id [default: a fresh unique one].
    pub run: Option<RunId>,
}

/// Why a run cannot be replayed (the input is not a replayable run), or the replay could not
/// be made.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The run's log cannot be read.
    #[error(transparent)]
    Log(#[from] LogError),
    /// The log has no header.
    #[error("{}: the log has no run header", dir.display())]
    NoHeader {
        /// The log directory.
        dir: PathBuf,
    },
    /// The run was not a lockstep run.
    #[error("{}: a {clock} run cannot be replayed: only a lockstep run is a function of its scenario and seed (a realtime run's rounds close on wall-clock deadlines)", dir.display())]
    NotLockstep {
        /// The log directory.
        dir: PathBuf,
        /// The header's clock.
        clock: String,
    },
    /// `invocation.json` is missing or bad.
    #[error("{source}; the run directory must hold the {INVOCATION} that `hnav run` writes")]
    Invocation {
        /// The cause.
        source: InvocationError,
    },
    /// The scenario cannot be loaded.
    #[error("the run's scenario cannot be loaded: {0}")]
    Scenario(#[from] ScenarioError),
    /// The scenario is no longer the one the log was written by.
    #[error("{}: the scenario (with the run's --agents, --seed, --mode and faults) hashes to {now:#018x}, the log's header says {logged:#018x}: the scenario file or its map changed since the run", scenario.display())]
    HashMismatch {
        /// The scenario file.
        scenario: PathBuf,
        /// Its hash now.
        now: u64,
        /// The hash in the log's header.
        logged: u64,
    },
    /// The temporary run directory could not be made.
    #[error("{}: cannot create the replay's run directory: {source}", dir.display())]
    TempDir {
        /// The directory.
        dir: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The replayed run failed to happen.
    #[error("the replay could not run: {0}")]
    Run(#[from] RunError),
}

/// A replay's result: how its log compares with the run's, and the header both share.
#[derive(Clone, Debug, PartialEq)]
pub struct Replayed {
    /// The comparison.
    pub comparison: Comparison,
    /// The logged run's header.
    pub header: RunHeader,
}

/// The run directory `dir` names: itself, or the directory holding it when `dir` is a
/// run's `log/`.
pub fn run_dir_of(dir: &Path) -> PathBuf {
    match dir.parent() {
        Some(parent)
            if !dir.join(INVOCATION).exists()
                && dir.file_name().is_some_and(|n| n == "log")
                && parent.join(INVOCATION).exists() =>
        {
            parent.to_path_buf()
        }
        _ => dir.to_path_buf(),
    }
}

/// Replays the run in `opts.dir` (see the [module docs](self)).
pub fn replay(opts: &ReplayOptions) -> Result<Replayed, ReplayError> {
    let dir = run_dir_of(&opts.dir);
    let log_dir = dir.join("log");
    let logged = read_decided(&log_dir)?;
    let header = match logged.records.first() {
        Some(Record::Header(h)) => h.clone(),
        _ => return Err(ReplayError::NoHeader { dir: log_dir }),
    };
    if header.clock != ClockMode::Lockstep.name() {
        return Err(ReplayError::NotLockstep {
            dir: log_dir,
            clock: header.clock,
        });
    }
    let invocation = Invocation::read(&dir).map_err(|source| ReplayError::Invocation { source })?;
    let run_id = opts.run.clone().unwrap_or_else(|| RunId::unique("replay"));
    let tmp = TempRunDir(std::env::temp_dir().join(format!("hnav-{}", run_id.as_str())));
    let mut args = invocation.process_args(run_id.as_str(), &tmp.0);
    replicas_from_log(&mut args, &header, &log_dir)?;
    let scenario = args.scenario()?;
    if scenario.scenario_hash() != header.scenario_hash {
        return Err(ReplayError::HashMismatch {
            scenario: invocation.scenario,
            now: scenario.scenario_hash(),
            logged: header.scenario_hash,
        });
    }
    std::fs::create_dir_all(&tmp.0).map_err(|source| ReplayError::TempDir {
        dir: tmp.0.clone(),
        source,
    })?;
    run(&RunOptions {
        args,
        bin_dir: opts.bin_dir.clone(),
        progress: opts.progress,
        force: false,
        // The comparison reads the log only; a recording would cost the replay time.
        record: false,
        host: None,
        ros2: None,
    })?;
    let replayed = read_decided(tmp.0.join("log"))?;
    // Compacted logs (replicas' snapshots) are compared from where both hold their records.
    let skip = [&logged, &replayed]
        .iter()
        .filter_map(|d| d.compacted.as_ref().map(|c| c.records))
        .max()
        .unwrap_or(0);
    let (logged, replayed) = (after(logged, skip), after(replayed, skip));
    Ok(Replayed {
        comparison: compare(&logged, &replayed, header.width),
        header,
    })
}

/// The header and the decided records after the first `skip`, of which `d` may hold only
/// those after its snapshot.
fn after(d: Decided, skip: u64) -> Vec<Record> {
    let held = skip.saturating_sub(d.compacted.map_or(0, |c| c.records)) as usize;
    let mut records = d.records;
    let drop = held.min(records.len().saturating_sub(1));
    records.drain(1..1 + drop);
    records
}

/// An `invocation.json` written before it recorded `--replicas` leaves the replicas to the
/// scenario; a log of replicas says how many the run had.
fn replicas_from_log(
    args: &mut ProcessArgs,
    header: &RunHeader,
    log_dir: &Path,
) -> Result<(), ReplayError> {
    if args.replicas.is_none() && header.version == REPLICATED_VERSION {
        let n = replica_dirs(log_dir)?.len();
        args.replicas = u32::try_from(n).ok().filter(|&n| n > 1);
    }
    Ok(())
}

/// The replay's run directory, removed when dropped (also when the replay failed).
struct TempRunDir(PathBuf);

impl Drop for TempRunDir {
    fn drop(&mut self) {
        if self.0.exists() {
            if let Err(e) = std::fs::remove_dir_all(&self.0) {
                tracing::warn!("{}: replay directory not removed: {e}", self.0.display());
            }
        }
    }
}
