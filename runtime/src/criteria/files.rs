//! The files a run's processes leave in the run directory for the summary's criteria:
//! the sim's per-robot energy and goal times ([`SimCriteria`], `DIR/sim-criteria.json`) and
//! the coordinator's candidate-to-commit latencies ([`ConsensusLatency`],
//! `DIR/consensus-latency.json`). Each is written whole or not at all
//! ([`replace_file`](crate::durable::replace_file)) when its process exits, and read back
//! by a restarted process, so that the numbers cover the whole run.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::latency::{Histogram, Stored};

/// The sim's file in the run directory.
pub const SIM_FILE: &str = "sim-criteria.json";
/// The coordinator's file in the run directory.
pub const LATENCY_FILE: &str = "consensus-latency.json";

/// A criteria file could not be read back.
#[derive(Debug, thiserror::Error)]
pub enum CriteriaFileError {
    /// The file exists but cannot be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not what its writer writes.
    #[error("{path}: {reason}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

/// One robot's figures as the sim measured them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RobotCriteria {
    /// Energy its two motors drew over the run, J ([`super::energy`]).
    pub energy_j: f64,
    /// Simulated time, s, of the first control period that ended with its true pose in its
    /// scenario goal cell (`[[agents]] goal`); `None` if it never did.
    pub goal_at_s: Option<f64>,
}

/// What the sim measured, per robot in index order.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SimCriteria {
    /// Per robot.
    pub robots: Vec<RobotCriteria>,
}

/// The coordinator's latencies from candidates to the commit, µs, one per round it decided.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ConsensusLatency {
    /// From the round's first candidate taken in to its commit published.
    pub from_first: Histogram,
    /// From the round's last candidate taken in (the one that completed it, or the deadline
    /// that closed it) to its commit published: the decision, its log record and the publish.
    pub from_last: Histogram,
}

#[derive(Serialize, Deserialize)]
struct StoredLatency {
    from_first_candidate_us: Stored,
    from_last_candidate_us: Stored,
}

/// The contents of `dir/name` as `T`; `None` when the file does not exist.
fn load<T: DeserializeOwned>(dir: &Path, name: &str) -> Result<Option<T>, CriteriaFileError> {
    let path = dir.join(name);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => return Err(CriteriaFileError::Read { path, source }),
    };
    serde_json::from_str(&text)
        .map(Some)
        .map_err(|e| CriteriaFileError::Format {
            path,
            reason: e.to_string(),
        })
}

fn store<T: Serialize>(dir: &Path, name: &str, value: &T) -> std::io::Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(std::io::Error::other)?;
    crate::durable::replace_file(&dir.join(name), (text + "\n").as_bytes())
}

impl SimCriteria {
    /// The figures in `dir/sim-criteria.json`; `None` when the file does not exist.
    pub fn load(dir: &Path) -> Result<Option<Self>, CriteriaFileError> {
        load(dir, SIM_FILE)
    }

    /// Writes them to `dir/sim-criteria.json`.
    pub fn store(&self, dir: &Path) -> std::io::Result<()> {
        store(dir, SIM_FILE, self)
    }
}

impl ConsensusLatency {
    /// The latencies in `dir/consensus-latency.json`; `None` when the file does not exist.
    pub fn load(dir: &Path) -> Result<Option<Self>, CriteriaFileError> {
        Ok(
            load::<StoredLatency>(dir, LATENCY_FILE)?.map(|s| ConsensusLatency {
                from_first: Histogram::from_stored(&s.from_first_candidate_us),
                from_last: Histogram::from_stored(&s.from_last_candidate_us),
            }),
        )
    }

    /// Writes them to `dir/consensus-latency.json`.
    pub fn store(&self, dir: &Path) -> std::io::Result<()> {
        let s = StoredLatency {
            from_first_candidate_us: self.from_first.to_stored(),
            from_last_candidate_us: self.from_last.to_stored(),
        };
        store(dir, LATENCY_FILE, &s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_files_round_trip_and_a_missing_one_is_none() {
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(SimCriteria::load(dir.path()).unwrap(), None);
        assert_eq!(ConsensusLatency::load(dir.path()).unwrap(), None);
        let sim = SimCriteria {
            robots: vec![
                RobotCriteria {
                    energy_j: 1.25,
                    goal_at_s: Some(3.5),
                },
                RobotCriteria::default(),
            ],
        };
        sim.store(dir.path()).unwrap();
        assert_eq!(SimCriteria::load(dir.path()).unwrap(), Some(sim));
        let mut lat = ConsensusLatency::default();
        lat.from_first.record(250);
        lat.from_last.record(40);
        lat.store(dir.path()).unwrap();
        assert_eq!(ConsensusLatency::load(dir.path()).unwrap(), Some(lat));
        std::fs::write(dir.path().join(SIM_FILE), "{").unwrap();
        let e = SimCriteria::load(dir.path()).unwrap_err().to_string();
        assert!(e.contains("sim-criteria.json"), "{e}");
    }
}
