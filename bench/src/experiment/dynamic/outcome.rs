//! One run of the experiment: its scenario written, `hnav run` as a child (as the MAPF
//! benchmark runs it, [`crate::swarm_run`]), then what it came to read from `summary.json`,
//! the consensus log and the agents' logs.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use serde::Serialize;

use hnav_operator::supervisor::child::{Child, ExitInfo, Signal};
use hnav_runtime::consensus_log::{read_decided, Record, Tally};
use hnav_runtime::transport::{purge_run, RunId};

use crate::swarm_run::{bin_dir, hnav_run_spec, read_summary, run_files, verify_log};

/// How long `hnav run` gets to stop after a SIGINT at the wall cap.
const STOP_TIMEOUT: Duration = Duration::from_secs(60);

/// The agents' repairs, from their log lines (`repair agent=0 period=186 closed=1 opened=0
/// kind=Rebuild us=46`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Repairs {
    /// Partial corrections.
    pub partial: u32,
    /// Their time, µs in all.
    pub partial_us: u64,
    /// Rebuilds.
    pub rebuild: u32,
    /// Their time, µs in all.
    pub rebuild_us: u64,
    /// A route planner's new routes.
    pub replan: u32,
}

impl Repairs {
    /// Adds the repair lines of one agent's log.
    pub fn read(&mut self, log: &str) {
        for line in log.lines().filter(|l| l.contains(" repair ")) {
            let field = |key: &str| line.split(key).nth(1)?.split(' ').next();
            let us: u64 = field(" us=").and_then(|v| v.parse().ok()).unwrap_or(0);
            match field(" kind=") {
                Some("Partial") => {
                    self.partial += 1;
                    self.partial_us += us;
                }
                Some("Rebuild") => {
                    self.rebuild += 1;
                    self.rebuild_us += us;
                }
                Some("Replan") => self.replan += 1,
                _ => {}
            }
        }
    }
}

/// What one run came to.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Outcome {
    /// Robots whose true pose ended on their goal.
    pub at_goal: usize,
    /// The sim's count: robot-robot collisions and contacts with walls, closed cells and
    /// walkers.
    pub collisions: u64,
    /// Rounds decided.
    pub rounds: u64,
    /// How the run ended (`all-at-goal`, `time-limit`, ...).
    pub end: String,
    /// The robots' accepted moves, cells.
    pub length_sum: f64,
    /// The agents' repairs.
    pub repairs: Repairs,
    /// Map-change records the coordinator logged.
    pub map_changes: u32,
    /// The robots' energy, J, when the summary has it.
    pub energy_j: Option<f64>,
    /// Wall time, s.
    pub wall_s: f64,
}

/// Where the experiment's runs find `hnav`.
fn hnav() -> Result<PathBuf> {
    Ok(bin_dir().map_err(anyhow::Error::msg)?.join("hnav"))
}

/// Runs `scenario` (its text) in `dir`, stopping it at `cap` of wall time.
pub fn run(dir: &Path, scenario: &str, cap: Duration) -> Result<Outcome> {
    std::fs::create_dir_all(dir).with_context(|| dir.display().to_string())?;
    let path = dir.join("scenario.toml");
    std::fs::write(&path, scenario).with_context(|| path.display().to_string())?;
    let (run, out, hnav) = (RunId::unique("dynamic"), dir.join("out"), hnav()?);
    let log = dir.join("hnav-run.log");
    let spec = hnav_run_spec(
        &hnav,
        &path,
        &run,
        &out,
        "lockstep",
        &dir.join("runs"),
        log.clone(),
    );
    let started = Instant::now();
    let child = Child::spawn(&spec).map_err(|e| anyhow::anyhow!("{e}"))?;
    let exit = match child.wait(Some(cap)) {
        Some(exit) => exit,
        None => {
            let _ = child.signal(Signal::SIGINT);
            child.wait(Some(STOP_TIMEOUT)).unwrap_or(ExitInfo::Lost)
        }
    };
    let wall_s = started.elapsed().as_secs_f64();
    if !run_files(&run).is_empty() {
        let _ = purge_run(&run);
    }
    let summary = read_summary(&out).map_err(|e| {
        let said = std::fs::read_to_string(&log).unwrap_or_default();
        anyhow::anyhow!("{e} (hnav run: {exit}):\n{said}")
    })?;
    verify_log(&hnav, &out.join("log")).map_err(anyhow::Error::msg)?;
    read(&out, &summary, wall_s)
}

/// The outcome of the run in `out`.
fn read(out: &Path, summary: &serde_json::Value, wall_s: f64) -> Result<Outcome> {
    let Some(agents) = summary["agents"].as_array() else {
        bail!("{}: no agents", out.join("summary.json").display());
    };
    let mut o = Outcome {
        at_goal: agents.iter().filter(|a| a["reached_goal"] == true).count(),
        collisions: summary["collisions"].as_u64().unwrap_or(u64::MAX),
        end: summary["end"].as_str().unwrap_or("").into(),
        wall_s,
        ..Outcome::default()
    };
    let energy: Vec<f64> = agents
        .iter()
        .filter_map(|a| a["energy_j"].as_f64())
        .collect();
    o.energy_j = (energy.len() == agents.len()).then(|| energy.iter().sum());
    let mut tally: Option<Tally> = None;
    for r in read_decided(out.join("log"))?.records {
        match r {
            Record::Header(h) => tally = Some(Tally::from_header(&h)),
            Record::Round(rec) => {
                o.rounds = o.rounds.max(rec.round);
                if let Some(t) = &mut tally {
                    t.fold_round(&rec);
                }
            }
            Record::MapChange(_) => o.map_changes += 1,
            _ => {}
        }
    }
    o.length_sum = tally.map_or(0.0, |t| t.agents().iter().map(|a| a.length).sum());
    for i in 0..agents.len() {
        let path = out.join(format!("logs/agent-{i}.log"));
        o.repairs
            .read(&std::fs::read_to_string(&path).unwrap_or_default());
    }
    Ok(o)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repair_lines_are_counted_by_kind_with_their_time() {
        let log = "2026-12-05T14:52:07Z  INFO hnav_agent::navigator::sense: repair agent=0 period=186 closed=1 opened=0 kind=Rebuild us=54\n\
                   x  INFO hnav_agent::navigator::sense: repair agent=0 period=190 closed=2 opened=0 kind=Partial us=10\n\
                   x  INFO hnav_agent::navigator::sense: repair agent=0 period=199 closed=1 opened=0 kind=Partial us=12\n\
                   x  INFO hnav_agent::process::state: the coordinator's map closed=1 opened=0 round=250\n";
        let mut r = Repairs::default();
        r.read(log);
        assert_eq!(
            r,
            Repairs {
                partial: 2,
                partial_us: 22,
                rebuild: 1,
                rebuild_us: 54,
                replan: 0
            }
        );
    }
}
