//! The run summary `hnav run` writes to `DIR/summary.json` and prints as a table.
//!
//! Per-agent numbers come from the consensus log, the durable record of what was decided:
//! accepted moves (steps and their octile length from the start in the log's header),
//! refused or held requests (conflicts) and global replans. Whether a robot reached its goal
//! comes from the sim's ground truth — its true pose lies in its goal cell — not from what the
//! agents believed.

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::consensus_log::{read_log, LogError, Record};
use crate::msg::{Truth, Verdict};

/// One agent's line of the summary.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AgentSummary {
    /// Agent index.
    pub id: u32,
    /// Whether the robot's true pose ended in its goal cell.
    pub reached_goal: bool,
    /// Accepted moves.
    pub steps: u32,
    /// Length of the accepted moves in cells (straight 1, diagonal sqrt 2).
    pub length: f64,
    /// Refused or held requests.
    pub conflicts: u32,
    /// Global replans.
    pub replans: u32,
}

/// The whole run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunSummary {
    /// The run id.
    pub run_id: String,
    /// `lockstep` or `realtime`.
    pub mode: String,
    /// Per agent.
    pub agents: Vec<AgentSummary>,
    /// Collisions the sim recorded on ground truth.
    pub collisions: u32,
    /// Decision rounds committed.
    pub rounds: u64,
    /// Wall time of the run in seconds.
    pub wall_time_s: f64,
    /// How the run ended: `all-at-goal`, `time-limit`, `stopped`, or `incomplete`.
    pub end: String,
    /// The consensus log directory.
    pub log: PathBuf,
}

impl RunSummary {
    /// Whether every robot reached its goal without a collision.
    pub fn success(&self) -> bool {
        self.collisions == 0 && self.agents.iter().all(|a| a.reached_goal)
    }

    /// Builds the summary from the log in `log_dir` and the last ground truth (poses in
    /// metres, cells `cell_size_m` wide).
    pub fn from_log(
        run_id: &str,
        log_dir: &Path,
        truth: Option<&Truth>,
        cell_size_m: f64,
        wall_time_s: f64,
    ) -> Result<RunSummary, LogError> {
        let contents = read_log(log_dir)?;
        let mut header = None;
        let mut agents: Vec<AgentSummary> = Vec::new();
        let mut pos: Vec<u32> = Vec::new();
        let mut goals: Vec<u32> = Vec::new();
        let mut rounds = 0;
        let mut end = "incomplete".to_string();
        let mut width = 1u32;
        for r in &contents.records {
            match r {
                Record::Header(h) => {
                    width = h.width.max(1);
                    agents = (0..h.agents.len() as u32)
                        .map(|id| AgentSummary {
                            id,
                            reached_goal: false,
                            steps: 0,
                            length: 0.0,
                            conflicts: 0,
                            replans: 0,
                        })
                        .collect();
                    pos = h.agents.iter().map(|a| a.start).collect();
                    goals = h.agents.iter().map(|a| a.goal).collect();
                    header = Some(h.clone());
                }
                Record::Round(rec) => {
                    rounds = rounds.max(rec.round);
                    for d in &rec.decisions {
                        let i = d.agent as usize;
                        let (Some(a), Some(p)) = (agents.get_mut(i), pos.get_mut(i)) else {
                            continue;
                        };
                        match Verdict::from_u8(d.verdict) {
                            Some(Verdict::Accept) => {
                                a.steps += 1;
                                a.length += step_length(*p, d.cell, width);
                                *p = d.cell;
                            }
                            Some(Verdict::Block | Verdict::Hold) => a.conflicts += 1,
                            Some(Verdict::Replan) => a.replans += 1,
                            None => {}
                        }
                    }
                }
                Record::End(e) => end = e.reason.name().to_string(),
                Record::Lifecycle(_) | Record::Replan(_) => {}
            }
        }
        if let Some(t) = truth {
            for (a, pose) in agents.iter_mut().zip(t.poses()) {
                let g = goals[a.id as usize];
                let (gx, gy) = (g % width, g / width);
                let cx = (pose.x_m / cell_size_m).floor();
                let cy = (pose.y_m / cell_size_m).floor();
                a.reached_goal = cx == f64::from(gx) && cy == f64::from(gy);
            }
        }
        Ok(RunSummary {
            run_id: run_id.to_string(),
            mode: header.map(|h| h.clock).unwrap_or_default(),
            agents,
            collisions: truth.map_or(0, |t| t.collisions),
            rounds,
            wall_time_s,
            end,
            log: log_dir.to_path_buf(),
        })
    }

    /// Writes `summary.json` into `dir`; returns its path.
    pub fn write_json(&self, dir: &Path) -> std::io::Result<PathBuf> {
        let path = dir.join("summary.json");
        let text = serde_json::to_string_pretty(self).map_err(std::io::Error::other)?;
        std::fs::write(&path, text + "\n")?;
        Ok(path)
    }

    /// The table `hnav run` prints.
    pub fn render(&self) -> String {
        let mut s = String::from("agent  goal  steps  length  conflicts  replans\n");
        for a in &self.agents {
            s += &format!(
                "{:>5}  {:>4}  {:>5}  {:>6.2}  {:>9}  {:>7}\n",
                a.id,
                if a.reached_goal { "yes" } else { "NO" },
                a.steps,
                a.length,
                a.conflicts,
                a.replans
            );
        }
        let at_goal = self.agents.iter().filter(|a| a.reached_goal).count();
        s += &format!(
            "{} of {} at goal, {} collisions, {} rounds, {:.2} s wall ({}, {})\n",
            at_goal,
            self.agents.len(),
            self.collisions,
            self.rounds,
            self.wall_time_s,
            self.mode,
            self.end
        );
        s
    }
}

/// Octile length of one move between row-major cell indices (0 when not a single move).
fn step_length(from: u32, to: u32, width: u32) -> f64 {
    let (fx, fy) = (i64::from(from % width), i64::from(from / width));
    let (tx, ty) = (i64::from(to % width), i64::from(to / width));
    match ((tx - fx).abs(), (ty - fy).abs()) {
        (1, 1) => std::f64::consts::SQRT_2,
        (1, 0) | (0, 1) => 1.0,
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_lengths_are_octile() {
        assert_eq!(step_length(0, 1, 10), 1.0);
        assert_eq!(step_length(0, 10, 10), 1.0);
        assert_eq!(step_length(0, 11, 10), std::f64::consts::SQRT_2);
        assert_eq!(step_length(0, 22, 10), 0.0);
        assert_eq!(step_length(9, 10, 10), 0.0, "no wrap across rows");
    }
}
