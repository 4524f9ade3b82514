//! Removing what a dead run left behind: `hnav clean [RUN]`, and `hnav run` on start.
//!
//! A supervisor killed by SIGKILL cannot clean up: its children die with it
//! (`PR_SET_PDEATHSIG`, see [`super::child`]), but their iceoryx2 nodes stay registered as
//! dead, their shared memory stays in `/dev/shm`, their service and node files under
//! iceoryx2's root directory, and the run's registry entry stays in the registry. Cleaning a
//! run removes all of that: it kills whatever process of the run still runs (each child
//! leads its own process group, so `killpg` of its recorded pid, and only when the pid still
//! names the recorded process), then [`purge_run`], then the registry entry.
//!
//! A run whose supervisor is alive is never cleaned; while a run is being cleaned its id is
//! claimed ([`RunRegistry::claim`]), so no new run with that id can start in between.

use std::time::{Duration, Instant};

use nix::sys::signal::{killpg, Signal};
use nix::unistd::Pid;

use super::registry::{process_alive, RegistryError, RunRecord, RunRegistry};
use hnav_runtime::transport::{
    purge_run, run_iceoryx2_files, run_shm_files, RunId, TransportError,
};

/// How long a killed leftover process gets to disappear.
const KILL_WAIT: Duration = Duration::from_secs(5);

/// Why a run could not be cleaned.
#[derive(Debug, thiserror::Error)]
pub enum CleanError {
    /// The run's supervisor is alive.
    #[error("run {run} is live (supervisor pid {pid}); stop it first (Ctrl-C in its terminal, or kill -TERM {pid})")]
    Live {
        /// The run id.
        run: String,
        /// The supervisor's pid.
        pid: u32,
    },
    /// The registry could not be read or written, or another process holds the run id.
    #[error(transparent)]
    Registry(#[from] RegistryError),
    /// The run id in a registry entry is not valid.
    #[error("run {run}: {source}")]
    BadId {
        /// The id as recorded.
        run: String,
        /// Why it is not valid.
        source: TransportError,
    },
    /// A process of the run survived SIGKILL.
    #[error("run {run}: process {pid} is still alive after SIGKILL")]
    Survivor {
        /// The run id.
        run: String,
        /// The process.
        pid: u32,
    },
    /// The run's shared memory could not be removed (a node of it is still alive).
    #[error("run {run}: {source}")]
    Purge {
        /// The run id.
        run: String,
        /// The cause.
        source: TransportError,
    },
}

/// What cleaning one run removed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cleaned {
    /// The run id.
    pub run_id: String,
    /// Its iceoryx2 domain (a host's part of a run across hosts), if any.
    pub domain: Option<String>,
    /// Processes of the run that were still alive and were killed.
    pub killed: usize,
    /// Files removed from `/dev/shm` and iceoryx2's root directory.
    pub files: usize,
    /// Whether a registry entry was removed.
    pub registered: bool,
}

impl core::fmt::Display for Cleaned {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "cleaned run {}{}: {} process(es) killed, {} shared-memory file(s) removed{}",
            self.run_id,
            self.domain
                .as_ref()
                .map_or(String::new(), |d| format!(" (host {d})")),
            self.killed,
            self.files,
            if self.registered {
                ", registry entry removed"
            } else {
                ""
            }
        )
    }
}

/// Cleans `run`: refused while its supervisor is alive. A run the registry does not know is
/// cleaned too (its shared memory, if no process of it is alive). See [`clean_named`] for a
/// run named by id alone.
pub fn clean_run(registry: &RunRegistry, run: &RunId) -> Result<Cleaned, CleanError> {
    let record = registry.find(run)?;
    if let Some(r) = record.as_ref().filter(|r| r.supervisor_alive()) {
        return Err(CleanError::Live {
            run: r.run_id.clone(),
            pid: r.supervisor_pid,
        });
    }
    let dir = record.as_ref().map(|r| r.dir.clone()).unwrap_or_default();
    let claim = registry.claim(run, &dir)?;
    let result = clean_claimed(run, record.as_ref());
    if let Err(e) = claim.release() {
        tracing::warn!("{e}");
    }
    result
}

/// Cleans the run named `run` (`hnav clean RUN`): `run` itself, and where hosts of a run
/// across hosts ran here, each host's part (in its own domain, with its own registry entry).
pub fn clean_named(registry: &RunRegistry, run: &RunId) -> Vec<Result<Cleaned, CleanError>> {
    let parts: Vec<RunRecord> = registry
        .list_runs()
        .into_iter()
        .map(|e| e.record)
        .filter(|r| r.run_id == run.as_str() && r.domain.is_some() && run.domain().is_none())
        .collect();
    let mut results = vec![clean_run(registry, run)];
    for part in parts {
        results.push(
            part.run()
                .map_err(|source| CleanError::BadId {
                    run: part.run_id.clone(),
                    source,
                })
                .and_then(|id| clean_run(registry, &id)),
        );
    }
    results
}

fn clean_claimed(run: &RunId, record: Option<&RunRecord>) -> Result<Cleaned, CleanError> {
    let killed = match record {
        Some(r) => kill_leftovers(r)?,
        None => 0,
    };
    // purge_run counts only what is left after iceoryx2's own clean-up of the dead nodes.
    let files_of = || run_shm_files(run).len() + run_iceoryx2_files(run).len();
    let before = files_of();
    purge_run(run).map_err(|source| CleanError::Purge {
        run: run.to_string(),
        source,
    })?;
    let files = before.saturating_sub(files_of());
    if let Some(r) = record {
        r.remove()?;
    }
    Ok(Cleaned {
        run_id: run.to_string(),
        domain: run.domain().map(str::to_string),
        killed,
        files,
        registered: record.is_some(),
    })
}

/// Cleans every registered run whose supervisor is dead; live runs are left alone. One
/// result per dead run, in the registry's order.
pub fn clean_dead_runs(registry: &RunRegistry) -> Vec<Result<Cleaned, CleanError>> {
    registry
        .list_runs()
        .into_iter()
        .filter(|e| e.stale)
        .map(|e| {
            let run = e.record.run().map_err(|source| CleanError::BadId {
                run: e.record.run_id.clone(),
                source,
            })?;
            clean_run(registry, &run)
        })
        .collect()
}

/// SIGKILLs the process group of every recorded process that still runs, and waits (bounded)
/// until each is gone.
fn kill_leftovers(record: &RunRecord) -> Result<usize, CleanError> {
    let alive: Vec<u32> = record
        .processes
        .iter()
        .filter(|p| process_alive(p.pid, p.start_ticks))
        .map(|p| p.pid)
        .collect();
    for &pid in &alive {
        tracing::info!(run = record.run_id, pid, "killing a leftover process group");
        let _ = killpg(Pid::from_raw(pid as i32), Signal::SIGKILL);
    }
    let deadline = Instant::now() + KILL_WAIT;
    for &pid in &alive {
        // Not our children: whoever inherited them reaps them; a zombie counts as gone.
        while process_alive(pid, None) {
            if Instant::now() >= deadline {
                return Err(CleanError::Survivor {
                    run: record.run_id.clone(),
                    pid,
                });
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }
    Ok(alive.len())
}
