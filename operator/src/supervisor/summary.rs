//! The run summary `hnav run` writes to `DIR/summary.json` and prints as a table.
//!
//! Per-agent numbers are the [`Tally`] of the consensus log, the durable record of what was
//! decided: accepted moves (steps and their octile length from the start in the log's
//! header), conflicts (requests refused or held for another robot or the map, each once),
//! rounds waited (held) and global replans. Whether a robot reached its goal comes from
//! the sim's ground truth — its true pose lies in its goal cell — not from what the agents
//! believed. The conflict rules the run ran and each process's restarts come from the
//! supervisor, which started the run and its processes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Serialize;

use hnav_runtime::consensus_log::{read_decided, LogError, Record, Tally};

mod criteria;
mod table;
mod tasks;
pub use criteria::LatencySummary;
use hnav_runtime::msg::{LifecycleEvent, Role, Truth};
use hnav_runtime::rejected::Rejections;
pub use tasks::TaskSummary;

/// One agent's line of the summary.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct AgentSummary {
    /// Agent index.
    pub id: u32,
    /// Whether the robot's true pose ended in its goal cell.
    pub reached_goal: bool,
    /// Accepted moves.
    pub steps: u32,
    /// Length of the accepted moves in cells (straight 1, diagonal sqrt 2).
    pub length: f64,
    /// Requests refused or held for another robot or the map, each once however many rounds
    /// it waited ([`Tally`]).
    pub conflicts: u32,
    /// Rounds in which its request was held: the time it waited (for a cell to be left, for
    /// another robot's turn; under `lacam`, every hold is a wait for the plan).
    pub waited: u32,
    /// Global replans.
    pub replans: u32,
    /// Whether the agent reported its goal unreachable (an unreachable record in the log).
    pub unreachable: bool,
    /// Whether the agent's process is gone for good (a `lost` record in the log, or the
    /// supervisor gave it up): its robot stood for the rest of the run and its goal counts
    /// as not reached, wherever the robot is.
    pub lost: bool,
    /// Octile shortest path from its start to its goal on the map the run ended with, cells
    /// (`None`: none there, or a run with `[tasks]`).
    pub shortest: Option<f64>,
    /// Path optimality: `length / shortest`, for a robot that reached its goal.
    pub optimality: Option<f64>,
    /// Simulated seconds until its true pose first ended a control period in its goal cell
    /// (the sim's measure; `None` if it never did or the sim left no figures).
    pub time_to_goal_s: Option<f64>,
    /// Energy its motors drew over the run, J (the sim's wheel model).
    pub energy_j: Option<f64>,
    /// Energy of `shortest` driven straight at its nominal speed under the same model, J.
    pub energy_budget_j: Option<f64>,
    /// Partial corrections of its neural map (§2.10 A), from its log.
    pub repairs_partial: u32,
    /// Neural map rebuilt from zero (§2.10 Б), from its log.
    pub repairs_rebuild: u32,
    /// New routes of a route planner (PSO, GA) after a change, from its log.
    pub repairs_replan: u32,
    /// Requests into a cell that was closed in the sim's truth at that round.
    pub false_positives: u32,
}

/// A robot lost during the run: its agent's process exited and was not restarted.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LostRobot {
    /// Agent index.
    pub id: u32,
    /// Why, as the supervisor saw it (`hnav-agent 2 ended (killed by SIGKILL) and is not
    /// restarted (restart limit of 1 reached)`).
    pub why: String,
}

/// The whole run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunSummary {
    /// The run id.
    pub run_id: String,
    /// `lockstep` or `realtime`.
    pub mode: String,
    /// The conflict rules the coordinator ran (`[coordinator] rules`: `lacam`, `pibt` or
    /// `dissertation`); empty when not known.
    pub rules: String,
    /// Per agent.
    pub agents: Vec<AgentSummary>,
    /// Collisions the sim recorded on ground truth.
    pub collisions: u32,
    /// The robots were outside HNAV (`[sim] kind = "ros2"`): `collisions` is not counted
    /// here but by their world. Only written when true.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub robots_outside: bool,
    /// Decision rounds committed.
    pub rounds: u64,
    /// Wall time of the run in seconds.
    pub wall_time_s: f64,
    /// How the run ended: `all-at-goal`, `time-limit`, `stopped`, or `incomplete` (the log
    /// has no end record; `time-limit` when the supervisor ended the run at its time limit).
    pub end: String,
    /// The consensus log directory.
    pub log: PathBuf,
    /// Why the supervisor ended the run early because it could not go on (the sim or the
    /// coordinator down and not restarted, or no agent left); absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cannot_go_on: Option<String>,
    /// Candidates the coordinator dropped as malformed or hostile, per
    /// [`Rejected`](hnav_runtime::rejected::Rejected) class (every class, zeros included).
    pub rejected: BTreeMap<String, u64>,
    /// The robots lost during the run, by index; empty when none was.
    pub lost: Vec<LostRobot>,
    /// Restarts per process (`sim`, `coordinator`, `agent-3`, ...) of every process the
    /// supervisor restarted at least once; empty when none was.
    pub restarts: BTreeMap<String, u32>,
    /// What the recorder wrote into `DIR/recording/`; absent with `hnav run --no-record`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub recording: Option<super::recorder::RecordingSummary>,
    /// Why `DIR/report.svg` could not be drawn, if it could not (the run still counts).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub report_error: Option<String>,
    /// On a host of a run across hosts without the coordinator: the host whose consensus
    /// log has the agents' steps, length, conflicts and replans (here they are 0, not
    /// known); the table prints `-` for them and says where they are.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub counts_on_host: Option<String>,
    /// A lifelong run's tasks (`[tasks]`); absent for a run without.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tasks: Option<TaskSummary>,
    /// The rounds' candidate-to-commit latencies as the coordinator measured them (`None`:
    /// it left none, as on a host without the coordinator).
    pub consensus_latency_us: Option<LatencySummary>,
}

impl RunSummary {
    /// Marks each of `lost` (index, why) lost: its goal counts as not reached.
    pub fn mark_lost(&mut self, lost: &[(u32, String)]) {
        for (id, why) in lost {
            if let Some(a) = self.agents.get_mut(*id as usize) {
                a.lost = true;
            }
            self.lost.push(LostRobot {
                id: *id,
                why: why.clone(),
            });
        }
        for a in self.agents.iter_mut().filter(|a| a.lost) {
            a.reached_goal = false;
        }
    }

    /// Whether every robot reached its goal without a collision; for a lifelong run, whether
    /// it ran to its time limit without a collision and got tasks done.
    pub fn success(&self) -> bool {
        let goals = match &self.tasks {
            Some(t) => self.end == "time-limit" && t.tasks_done > 0,
            None => self.agents.iter().all(|a| a.reached_goal),
        };
        self.cannot_go_on.is_none() && self.collisions == 0 && goals
    }

    /// Builds the summary from the log in `log_dir` and the last ground truth (poses in
    /// metres, cells `cell_size_m` wide), with the coordinator's counts of dropped candidates
    /// from the run directory holding `log_dir`. `lifelong` is the control period in seconds
    /// of a run with `[tasks]` (its rounds' length), for the [`TaskSummary`].
    pub fn from_log(
        run_id: &str,
        log_dir: &Path,
        truth: Option<&Truth>,
        cell_size_m: f64,
        wall_time_s: f64,
        lifelong: Option<f64>,
    ) -> Result<RunSummary, LogError> {
        let contents = read_decided(log_dir)?;
        let mut header = None;
        let mut tally = Tally::default();
        let mut rounds = 0;
        let mut end = "incomplete".to_string();
        let mut unreachable = Vec::new();
        let mut lost = Vec::new();
        let mut tasks = Vec::new();
        // A compacted replica's log: the records its snapshot stands for add up to its state.
        let compacted = contents.compacted.as_ref();
        if let Some(c) = compacted {
            rounds = c.round;
            tasks.extend_from_slice(&c.tasks);
            if let Some(e) = c.end {
                end = e.reason.name().to_string();
            }
            unreachable.extend(c.unreachable.iter().map(|u| u.agent));
            lost.extend(
                (0u32..)
                    .zip(&c.agents)
                    .filter(|(_, a)| a.lost)
                    .map(|(i, _)| i),
            );
        }
        for r in &contents.records {
            match r {
                Record::Header(h) => {
                    tally = compacted.map_or_else(|| Tally::from_header(h), |c| c.tally.clone());
                    header = Some(h);
                }
                Record::Round(rec) => {
                    rounds = rounds.max(rec.round);
                    tally.fold_round(rec);
                }
                Record::End(e) => end = e.reason.name().to_string(),
                Record::Unreachable(u) => unreachable.push(u.agent),
                Record::Task(t) => tasks.push(*t),
                Record::Lifecycle(l)
                    if l.role == Role::Agent as u8 && l.event == LifecycleEvent::Lost as u8 =>
                {
                    lost.push(l.index);
                }
                Record::Lifecycle(_)
                | Record::Replan(_)
                | Record::Raft(_)
                | Record::RaftState(_)
                | Record::Snapshot(_)
                | Record::MapChange(_) => {}
            }
        }
        let mut agents: Vec<AgentSummary> = (0u32..)
            .zip(tally.agents())
            .map(|(id, t)| AgentSummary {
                id,
                reached_goal: false,
                steps: t.steps,
                length: t.length,
                conflicts: t.conflicts,
                waited: t.waited,
                replans: t.replans,
                unreachable: unreachable.contains(&id),
                lost: lost.contains(&id),
                ..AgentSummary::default()
            })
            .collect();
        if let (Some(t), Some(h)) = (truth, header) {
            let width = h.width.max(1);
            for ((a, pose), entry) in agents.iter_mut().zip(t.poses()).zip(&h.agents) {
                let (gx, gy) = (entry.goal % width, entry.goal / width);
                let cx = (pose.x_m / cell_size_m).floor();
                let cy = (pose.y_m / cell_size_m).floor();
                a.reached_goal = !a.lost && cx == f64::from(gx) && cy == f64::from(gy);
            }
        }
        Ok(RunSummary {
            run_id: run_id.to_string(),
            mode: header.map(|h| h.clock.clone()).unwrap_or_default(),
            rules: String::new(),
            agents,
            collisions: truth.map_or(0, |t| t.collisions),
            robots_outside: false,
            rounds,
            wall_time_s,
            end,
            log: log_dir.to_path_buf(),
            cannot_go_on: None,
            rejected: read_rejected(log_dir.parent().unwrap_or(Path::new("."))),
            lost: Vec::new(),
            restarts: BTreeMap::new(),
            recording: None,
            report_error: None,
            counts_on_host: None,
            tasks: lifelong.map(|period| TaskSummary::new(&tasks, rounds, period)),
            consensus_latency_us: None,
        })
    }

    /// The summary of a host of a run across hosts that does not run the coordinator: the
    /// consensus log is on another host, so only what crossed the bridge is known here (the
    /// last ground truth and the coordinator's last progress). Steps, conflicts and replans
    /// are zero, not known: `hnav log show` on the coordinator's host has them (the caller
    /// names it in [`RunSummary::counts_on_host`]).
    pub fn from_truth(
        run_id: &str,
        scenario: &hnav_runtime::scenario::Scenario,
        truth: Option<&Truth>,
        progress: Option<&hnav_runtime::msg::Progress>,
        wall_time_s: f64,
    ) -> RunSummary {
        let cell = scenario.robot.cell_size_m;
        let reached = |i: usize| {
            let (Some(t), Some(a)) = (truth, scenario.agents.get(i)) else {
                return false;
            };
            t.poses().get(i).is_some_and(|p| {
                (p.x_m / cell).floor() == f64::from(a.goal.x)
                    && (p.y_m / cell).floor() == f64::from(a.goal.y)
            })
        };
        let agents: Vec<AgentSummary> = (0..scenario.agents.len())
            .map(|i| AgentSummary {
                id: i as u32,
                reached_goal: reached(i),
                steps: 0,
                length: 0.0,
                conflicts: 0,
                waited: 0,
                replans: 0,
                unreachable: false,
                lost: false,
                ..AgentSummary::default()
            })
            .collect();
        let all_home = !agents.is_empty() && agents.iter().all(|a| a.reached_goal);
        let end = match progress.map(|p| p.done) {
            Some(hnav_runtime::msg::Progress::ALL_AT_GOAL) => "all-at-goal",
            Some(hnav_runtime::msg::Progress::TIME_LIMIT) => "time-limit",
            // A realtime bridge may drop the coordinator's last progress on a lossy link
            // (state samples are droppable there); the ground truth that crossed after it
            // still shows every robot on its goal, which is what ended the run.
            _ if all_home => "all-at-goal",
            _ => "incomplete",
        };
        RunSummary {
            run_id: run_id.to_string(),
            mode: scenario.sim.clock.to_string(),
            rules: scenario.coordinator.rules.name().to_string(),
            agents,
            collisions: truth.map_or(0, |t| t.collisions),
            robots_outside: false,
            rounds: progress.map_or(0, |p| p.round),
            wall_time_s,
            end: end.to_string(),
            log: PathBuf::new(),
            cannot_go_on: None,
            rejected: BTreeMap::new(),
            lost: Vec::new(),
            restarts: BTreeMap::new(),
            recording: None,
            report_error: None,
            counts_on_host: None,
            tasks: None,
            consensus_latency_us: None,
        }
    }

    /// Fills the criteria of the dissertation (§2.1) that are not in the log's tally: path
    /// optimality, time to goal, energy and its budget, repairs, false positives and the
    /// consensus latency, from `scenario`, the run directory `run_dir` and the consensus log
    /// (`log`; see the `criteria` module).
    pub fn fill_criteria(&mut self, scenario: &hnav_runtime::scenario::Scenario, run_dir: &Path) {
        let log = self.log.clone();
        criteria::fill(self, scenario, run_dir, &log);
        self.robots_outside = scenario.sim.kind == hnav_runtime::scenario::SimKind::Ros2;
    }

    /// Writes `summary.json` into `dir` atomically; returns its path.
    ///
    /// The text goes to a temporary file in `dir`, is synced, and is renamed over
    /// `summary.json` (then the directory is synced): a reader finds the whole summary or
    /// none, never a truncated one, even when the disk fills up or the supervisor dies
    /// half-way. On failure the temporary file is removed.
    pub fn write_json(&self, dir: &Path) -> std::io::Result<PathBuf> {
        let path = dir.join("summary.json");
        let text = serde_json::to_string_pretty(self).map_err(std::io::Error::other)? + "\n";
        hnav_runtime::durable::replace_file(&path, text.as_bytes())?;
        Ok(path)
    }
}

/// The coordinator's counts of dropped candidates in `run_dir` (see [`hnav_runtime::rejected`]);
/// all zero, with a warning, when its file cannot be read.
fn read_rejected(run_dir: &Path) -> BTreeMap<String, u64> {
    Rejections::load(run_dir)
        .unwrap_or_else(|e| {
            tracing::warn!("{e}; the summary counts no dropped candidates");
            Rejections::default()
        })
        .to_map()
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::msg::{Progress, Truth};
    use hnav_runtime::scenario::Scenario;

    fn demo() -> Scenario {
        Scenario::load(Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/demo.toml"))
            .unwrap()
    }

    /// Every robot of `s` in the middle of its goal cell, or of its start cell for `away`.
    fn truth(s: &Scenario, away: Option<usize>) -> Truth {
        let mut t = Truth {
            poses: vec![Default::default(); s.agents.len()],
            ..Truth::default()
        };
        let cell = s.robot.cell_size_m;
        for (i, a) in s.agents.iter().enumerate() {
            let at = if away == Some(i) { a.start } else { a.goal };
            t.poses[i].x_m = (f64::from(at.x) + 0.5) * cell;
            t.poses[i].y_m = (f64::from(at.y) + 0.5) * cell;
        }
        t
    }

    #[test]
    fn a_host_that_lost_the_last_progress_still_ends_all_at_goal_from_the_truth() {
        let s = demo();
        let not_done = Progress::default();
        let home = RunSummary::from_truth("r", &s, Some(&truth(&s, None)), Some(&not_done), 1.0);
        assert_eq!(home.end, "all-at-goal");
        assert!(home.agents.iter().all(|a| a.reached_goal));
        let one_away = RunSummary::from_truth("r", &s, Some(&truth(&s, Some(2))), None, 1.0);
        assert_eq!(one_away.end, "incomplete");
        assert!(!one_away.agents[2].reached_goal);
        let no_truth = RunSummary::from_truth("r", &s, None, Some(&not_done), 1.0);
        assert_eq!(no_truth.end, "incomplete");
    }

    #[test]
    fn a_host_without_the_log_prints_no_made_up_counts() {
        let s = demo();
        let mut home = RunSummary::from_truth("r", &s, Some(&truth(&s, None)), None, 1.0);
        home.counts_on_host = Some("base".into());
        let table = home.render();
        assert!(
            table.contains("    0   yes      -       -          -       -        -        -        -       -       -    0/0/0       -\n"),
            "{table}"
        );
        assert!(!table.contains("0.00"), "{table}");
        assert!(
            table.contains(
                "(steps, length, conflicts, waited, replans: in the consensus log on host base; optimal and false+ too;"
            ),
            "{table}"
        );
    }
}
