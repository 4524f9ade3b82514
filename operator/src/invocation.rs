//! `DIR/invocation.json`: how a run was started, so that `hnav log replay DIR` can start it
//! again.
//!
//! The consensus log's header holds the scenario's hash and seed but not the scenario: the
//! processes load it from its file with the command line's overrides (`--agents`, `--seed`,
//! `--mode`, `--replicas`, the faults), see [`hnav_runtime::launch`]. This file keeps exactly
//! those: the scenario
//! file's absolute path, the overrides, and the hash of the scenario they gave. The scenario
//! is referred to, not copied: a scenario names its map by a path relative to itself, so a
//! copy would have to move the map too. The hash makes a reference safe: a replay recomputes
//! it and refuses a scenario (or map) that changed since the run.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::scenario::{fault_arg, ClockMode, Scenario};

/// The file's name in the run directory.
pub const FILE: &str = "invocation.json";

/// What `hnav run` was given, with the scenario it made.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Invocation {
    /// The scenario file, absolute.
    pub scenario: PathBuf,
    /// `--agents N`, if given.
    pub agents: Option<usize>,
    /// `--seed S`, if given.
    pub seed: Option<u64>,
    /// `--mode`, if given.
    pub mode: Option<ClockMode>,
    /// `--replicas N`, if given: a replay must run as many coordinator replicas, or it writes
    /// a single coordinator's log (another header version) instead of replicas' logs.
    /// Missing in the files of runs that predate it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub replicas: Option<u32>,
    /// The command line's faults, in the processes' `--fault` spelling (`kill=agent:1@round:40`).
    pub faults: Vec<String>,
    /// The scenario hash of the scenario these gave, as `0x` and 16 hex digits (the log's
    /// header holds the same number; `hnav log show` prints it so).
    pub scenario_hash: String,
}

/// Why `invocation.json` cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum InvocationError {
    /// The file is missing or unreadable.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The file is not what `hnav run` writes.
    #[error("{}: not a valid run invocation: {problem}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        problem: String,
    },
}

impl Invocation {
    /// The invocation of a run started with `args`, which gave `scenario`.
    pub fn new(args: &ProcessArgs, scenario: &Scenario) -> Invocation {
        // A relative path would name another file once the replay runs from elsewhere.
        let path = std::fs::canonicalize(&args.scenario).unwrap_or_else(|_| {
            std::env::current_dir()
                .map(|d| d.join(&args.scenario))
                .unwrap_or_else(|_| args.scenario.clone())
        });
        Invocation {
            scenario: path,
            agents: args.agents,
            seed: args.seed,
            mode: args.mode,
            replicas: args.replicas,
            faults: args.faults.iter().map(fault_arg::to_process_arg).collect(),
            scenario_hash: format!("{:#018x}", scenario.scenario_hash()),
        }
    }

    /// Writes `dir/invocation.json` whole or not at all
    /// ([`replace_file`](hnav_runtime::durable::replace_file)).
    pub fn write(&self, dir: &Path) -> std::io::Result<PathBuf> {
        let path = dir.join(FILE);
        let mut text = serde_json::to_string_pretty(self).map_err(std::io::Error::other)?;
        text.push('\n');
        hnav_runtime::durable::replace_file(&path, text.as_bytes())?;
        Ok(path)
    }

    /// Reads `dir/invocation.json`.
    pub fn read(dir: &Path) -> Result<Invocation, InvocationError> {
        let path = dir.join(FILE);
        let text = std::fs::read_to_string(&path).map_err(|source| InvocationError::Io {
            path: path.clone(),
            source,
        })?;
        let inv: Invocation =
            serde_json::from_str(&text).map_err(|e| InvocationError::Invalid {
                path: path.clone(),
                problem: e.to_string(),
            })?;
        // Parsed once here so that a bad fault is this file's error, not a run's.
        for f in &inv.faults {
            fault_arg::parse_process_arg(f).map_err(|problem| InvocationError::Invalid {
                path: path.clone(),
                problem: format!("fault {f:?}: {problem}"),
            })?;
        }
        Ok(inv)
    }

    /// The scenario of the run in `dir` as its processes loaded it: the file `invocation.json`
    /// names with its overrides, if it still hashes as `scenario_hash` (the log header's)
    /// says. Readers of a finished run (the export, the playback) take what only the
    /// scenario holds from it (events, sensor range, periods); `Err` says why there is none.
    pub fn logged_scenario(dir: &Path, scenario_hash: u64) -> Result<Scenario, String> {
        let inv = Invocation::read(dir).map_err(|e| e.to_string())?;
        let s = inv
            .process_args("reader", dir)
            .scenario()
            .map_err(|e| e.to_string())?;
        if s.scenario_hash() == scenario_hash {
            Ok(s)
        } else {
            Err(format!(
                "{}: the scenario no longer hashes as the log's header says",
                inv.scenario.display()
            ))
        }
    }

    /// The processes' arguments that start this run again as run `run` in `dir`.
    pub fn process_args(&self, run: &str, dir: &Path) -> ProcessArgs {
        ProcessArgs {
            run: run.to_string(),
            scenario: self.scenario.clone(),
            agents: self.agents,
            seed: self.seed,
            mode: self.mode,
            replicas: self.replicas,
            dir: Some(dir.to_path_buf()),
            resume: false,
            faults: self
                .faults
                .iter()
                .filter_map(|f| fault_arg::parse_process_arg(f).ok())
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_invocation_round_trips_and_rebuilds_the_same_scenario() {
        let tmp = tempfile::tempdir().unwrap();
        let scenario = tmp.path().join("s.toml");
        std::fs::write(
            &scenario,
            "name = \"s\"\n[map]\nrows = [\"....\", \"....\"]\n[[agents]]\nstart = [0, 0]\ngoal = [3, 1]\n[[agents]]\nstart = [3, 0]\ngoal = [0, 1]\n",
        )
        .unwrap();
        let args = ProcessArgs {
            run: "r".into(),
            scenario: scenario.clone(),
            agents: Some(1),
            seed: Some(7),
            mode: Some(ClockMode::Realtime),
            replicas: Some(3),
            dir: None,
            resume: false,
            faults: vec![fault_arg::parse_process_arg("kill=agent:0@round:5").unwrap()],
        };
        let s = args.scenario().unwrap();
        let inv = Invocation::new(&args, &s);
        assert!(inv.scenario.is_absolute());
        inv.write(tmp.path()).unwrap();
        let back = Invocation::read(tmp.path()).unwrap();
        assert_eq!(back, inv);
        let again = back.process_args("r2", tmp.path());
        assert_eq!(again.replicas, Some(3));
        let again = again.scenario().unwrap();
        assert_eq!(again.scenario_hash(), s.scenario_hash());
        assert_eq!(again.coordinator.replicas, 3);
        assert_eq!(inv.scenario_hash, format!("{:#018x}", s.scenario_hash()));
    }

    #[test]
    fn a_bad_fault_names_the_file() {
        let tmp = tempfile::tempdir().unwrap();
        std::fs::write(
            tmp.path().join(FILE),
            r#"{"scenario": "/x.toml", "agents": null, "seed": null, "mode": null, "faults": ["kill=robot:1@round:2"], "scenario_hash": "0x0"}"#,
        )
        .unwrap();
        let e = Invocation::read(tmp.path()).unwrap_err().to_string();
        assert!(
            e.contains("invocation.json: not a valid run invocation: fault"),
            "{e}"
        );
        let e = Invocation::read(&tmp.path().join("none"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("none/invocation.json: No such file"), "{e}");
    }
}
