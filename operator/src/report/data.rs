//! What the report shows, gathered from a run directory: the map copy (`map.map`), the
//! consensus log (`log/`), the recording (`recording/`) and the summary (`summary.json`).
//!
//! Conflicts are the log's [`Tally`]'s, the summary's count: a mark where a request was
//! first refused or held, not one per round it waited. Process events (down, restarted,
//! lost) are the log's lifecycle records.
//!
//! Only the log is required. Without a recording the report has no trajectories, neural
//! maps or collision marks, and says so in [`RunData::notes`]; so it does for an agent with
//! no recorded snapshot.

use std::path::Path;

use crate::recording::{self, MapReader, MapSnapshot, PoseSource, TrajectoryReader};
use hnav_runtime::consensus_log::{read_decided, Counted, Record, RunHeader, Tally};
use hnav_runtime::grid::read_map_file;
use hnav_runtime::msg::{LifecycleEvent, Role};

use super::{ReportError, MAP_FILE};

/// A cell, `(column, row)`.
pub type CellXy = (u32, u32);

/// A decision marked where it happened: the agent's cell in that round.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mark {
    /// The agent.
    pub agent: u32,
    /// Its cell when the decision was taken (its start, or its last accepted move).
    pub cell: CellXy,
    /// The round.
    pub round: u64,
}

/// A process event of the log: a process down, restarted or lost.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LifeMark {
    /// The last round committed when it was logged.
    pub round: u64,
    /// The process's role.
    pub role: Role,
    /// Its agent index (or replica id), else 0.
    pub index: u32,
    /// Down, restarted or lost.
    pub event: LifecycleEvent,
    /// For an agent, its robot's cell then (its start, or its last accepted move).
    pub cell: Option<CellXy>,
}

/// A robot's true position when the sim's collision count rose, in cell units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CollisionMark {
    /// The robot.
    pub robot: u32,
    /// x, cells.
    pub x: f64,
    /// y, cells.
    pub y: f64,
    /// Simulated time, ns since Start.
    pub t_ns: u64,
}

/// Everything the report draws.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct RunData {
    /// Map width, cells.
    pub width: u32,
    /// Map height, cells.
    pub height: u32,
    /// Row-major: blocked cells.
    pub blocked: Vec<bool>,
    /// Per robot.
    pub starts: Vec<CellXy>,
    /// Per robot.
    pub goals: Vec<CellXy>,
    /// Per robot: the cells of its accepted moves, in order.
    pub committed: Vec<Vec<CellXy>>,
    /// Conflicts: requests refused or held for another robot or the map, each marked once
    /// where it was first decided.
    pub conflicts: Vec<Mark>,
    /// Rounds waited (requests held), all agents.
    pub waited: u32,
    /// Global replans.
    pub replans: Vec<Mark>,
    /// Processes down, restarted or lost, in log order.
    pub lifecycle: Vec<LifeMark>,
    /// The conflict rules the run ran, from the summary; `None` when it does not say.
    pub rules: Option<String>,
    /// Rounds committed.
    pub rounds: u64,
    /// Per robot: its true positions over time, in cell units.
    pub trajectories: Vec<Vec<(f64, f64)>>,
    /// Collisions the run counted (the summary's count).
    pub collisions: u32,
    /// The robots involved in each rise of the count, where they were.
    pub collision_marks: Vec<CollisionMark>,
    /// The chosen agents' final neural maps, in the order asked for.
    pub maps: Vec<MapSnapshot>,
    /// The summary's criteria in at most two lines (see [`criteria_lines`]); none when the
    /// summary has none.
    pub criteria: Vec<String>,
    /// What is missing from the picture, and why.
    pub notes: Vec<String>,
    /// Cells the swarm saw close during the run (`[sensing]`: the log's map changes), each
    /// once.
    pub closed: Vec<CellXy>,
    /// Per mover (`[[events]]` movers): its recorded positions, in cell units.
    pub movers: Vec<Vec<(f64, f64)>>,
    /// Row-major: cells some robot's range sensor saw during the run (`[sensing]`); empty
    /// when the run did not sense or its scenario is not at hand.
    pub sensed: Vec<bool>,
    /// The log header's scenario hash: which scenario the run's was.
    pub scenario_hash: u64,
}

impl RunData {
    /// Reads the run in `dir`; `agents` are those whose final neural map is wanted.
    pub fn load(dir: &Path, agents: &[u32]) -> Result<RunData, ReportError> {
        let log_dir = dir.join("log");
        let mut data = RunData::from_log(&log_dir)?;
        for &a in agents {
            if a as usize >= data.starts.len() {
                return Err(ReportError::NoSuchAgent {
                    agent: a,
                    agents: data.starts.len(),
                });
            }
        }
        data.read_map(&dir.join(MAP_FILE))?;
        let rec = dir.join(recording::DIR);
        let trajectories = rec.join(recording::TRAJECTORIES);
        let mut cell_size = None;
        if trajectories.exists() {
            let cs = data.read_trajectories(&trajectories)?;
            data.read_world(dir, &trajectories, cs)?;
            cell_size = Some(cs);
        } else {
            data.notes.push(format!(
                "{}: absent, no trajectories",
                trajectories.display()
            ));
        }
        let summary = dir.join("summary.json");
        let times = data.read_summary(&summary)?;
        if let Some(cs) = cell_size {
            data.read_collisions(&trajectories, cs, &times)?;
        }
        let maps = rec.join(recording::MAPS);
        if maps.exists() {
            data.read_maps(&maps, agents)?;
        } else if !agents.is_empty() {
            data.notes
                .push(format!("{}: absent, no neural maps", maps.display()));
        }
        Ok(data)
    }

    /// Starts, goals, committed cells, conflicts and replans from the log in `log_dir`.
    pub fn from_log(log_dir: &Path) -> Result<RunData, ReportError> {
        let contents = read_decided(log_dir)?;
        let header: &RunHeader = contents
            .records
            .iter()
            .find_map(|r| match r {
                Record::Header(h) => Some(h),
                _ => None,
            })
            .ok_or_else(|| ReportError::NoHeader {
                dir: log_dir.to_path_buf(),
            })?;
        let w = header.width.max(1);
        let xy = |c: u32| (c % w, c / w);
        let n = header.agents.len();
        let mut data = RunData {
            width: header.width,
            height: header.height,
            blocked: vec![false; header.width as usize * header.height as usize],
            starts: header.agents.iter().map(|a| xy(a.start)).collect(),
            goals: header.agents.iter().map(|a| xy(a.goal)).collect(),
            committed: vec![Vec::new(); n],
            trajectories: vec![Vec::new(); n],
            scenario_hash: header.scenario_hash,
            ..RunData::default()
        };
        let mut at = data.starts.clone();
        let mut tally = Tally::from_header(header);
        if let Some(c) = &contents.compacted {
            // The map draws what the log still holds; the totals count the snapshot's too.
            data.notes.push(format!(
                "{}: compacted, the first {} decided records (through round {}) are in its \
                 snapshot: the paths start there",
                contents.dir.display(),
                c.records,
                c.round
            ));
            tally = c.tally.clone();
            data.rounds = c.round;
            at = tally.cells().iter().map(|&c| xy(c)).collect();
        }
        for r in &contents.records {
            match r {
                Record::Round(round) => data.fold_round(round, &mut tally, &mut at, xy),
                Record::Lifecycle(l) => {
                    let (Some(role), Some(event)) =
                        (Role::from_u8(l.role), LifecycleEvent::from_u8(l.event))
                    else {
                        continue;
                    };
                    let cell = (role == Role::Agent)
                        .then(|| at.get(l.index as usize).copied())
                        .flatten();
                    data.lifecycle.push(LifeMark {
                        round: l.round,
                        role,
                        index: l.index,
                        event,
                        cell,
                    });
                }
                Record::MapChange(m) => {
                    for c in m.closed.iter().map(|&c| xy(c)) {
                        if !data.closed.contains(&c) {
                            data.closed.push(c);
                        }
                    }
                }
                _ => {}
            }
        }
        data.waited = tally.waited();
        Ok(data)
    }

    /// One round's decisions, marked at each agent's cell (`at`, moved by accepted moves).
    fn fold_round(
        &mut self,
        round: &hnav_runtime::consensus_log::RoundRecord,
        tally: &mut Tally,
        at: &mut [CellXy],
        xy: impl Fn(u32) -> CellXy,
    ) {
        self.rounds = self.rounds.max(round.round);
        for d in &round.decisions {
            let i = d.agent as usize;
            let Some(cell) = at.get_mut(i) else { continue };
            let mark = Mark {
                agent: d.agent,
                cell: *cell,
                round: round.round,
            };
            match tally.fold(d) {
                Counted::Step => {
                    *cell = xy(d.cell);
                    self.committed[i].push(*cell);
                }
                Counted::Conflict => self.conflicts.push(mark),
                Counted::Replan => self.replans.push(mark),
                Counted::StillHeld | Counted::Waited | Counted::Nothing => {}
            }
        }
    }

    /// The obstacles, from the map copy.
    fn read_map(&mut self, path: &Path) -> Result<(), ReportError> {
        if !path.exists() {
            self.notes
                .push(format!("{}: absent, no obstacles drawn", path.display()));
            return Ok(());
        }
        let grid = read_map_file(path)?;
        if (grid.width(), grid.height()) != (self.width, self.height) {
            return Err(ReportError::MapMismatch {
                path: path.to_path_buf(),
                map_w: grid.width(),
                map_h: grid.height(),
                log_w: self.width,
                log_h: self.height,
            });
        }
        self.blocked = grid.blocked().to_vec();
        Ok(())
    }

    /// The true trajectories; returns the cell size.
    fn read_trajectories(&mut self, path: &Path) -> Result<f64, ReportError> {
        let mut r = TrajectoryReader::open(path)?;
        let cs = f64::from(r.header().cell_size_m).max(f64::MIN_POSITIVE);
        if r.header().truncated {
            self.notes.push(format!(
                "{}: cut at its size cap, trajectories end early",
                path.display()
            ));
        }
        while let Some(s) = r.next_sample()? {
            if s.source != PoseSource::Truth {
                continue;
            }
            if let Some(t) = self.trajectories.get_mut(s.robot as usize) {
                t.push((f64::from(s.x_m) / cs, f64::from(s.y_m) / cs));
            }
        }
        if r.torn_tail() > 0 {
            self.notes.push(format!(
                "{}: a torn last sample ({} bytes) skipped",
                path.display(),
                r.torn_tail()
            ));
        }
        Ok(cs)
    }

    /// The collision count and the times it rose, from `summary.json` (absent: none known).
    fn read_summary(&mut self, path: &Path) -> Result<Vec<u64>, ReportError> {
        let text = match std::fs::read_to_string(path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                self.notes
                    .push(format!("{}: absent, no collisions known", path.display()));
                return Ok(Vec::new());
            }
            Err(e) => {
                return Err(ReportError::Summary {
                    path: path.to_path_buf(),
                    problem: e.to_string(),
                })
            }
        };
        let bad = |problem: String| ReportError::Summary {
            path: path.to_path_buf(),
            problem,
        };
        let v: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| bad(format!("not JSON: {e}")))?;
        self.rules = v
            .get("rules")
            .and_then(serde_json::Value::as_str)
            .filter(|r| !r.is_empty())
            .map(str::to_string);
        self.collisions = v
            .get("collisions")
            .and_then(serde_json::Value::as_u64)
            .and_then(|c| u32::try_from(c).ok())
            .ok_or_else(|| bad("no collision count".into()))?;
        self.criteria = criteria_lines(&v);
        Ok(collisions_at_ns(&v))
    }

    /// Where the robots were at each rise of the collision count: the two closest robots if
    /// they are within a cell of each other (a robot contact), else every robot (a wall
    /// contact leaves no trace in the truth message but the count).
    fn read_collisions(&mut self, path: &Path, cs: f64, times: &[u64]) -> Result<(), ReportError> {
        if times.is_empty() {
            return Ok(());
        }
        let mut at: Vec<Vec<(u32, f64, f64)>> = vec![Vec::new(); times.len()];
        let mut r = TrajectoryReader::open(path)?;
        while let Some(s) = r.next_sample()? {
            if s.source != PoseSource::Truth {
                continue;
            }
            if let Ok(k) = times.binary_search(&s.t_ns) {
                at[k].push((
                    u32::from(s.robot),
                    f64::from(s.x_m) / cs,
                    f64::from(s.y_m) / cs,
                ));
            }
        }
        for (k, poses) in at.iter().enumerate() {
            self.collision_marks
                .extend(
                    involved(poses)
                        .into_iter()
                        .map(|(robot, x, y)| CollisionMark {
                            robot,
                            x,
                            y,
                            t_ns: times[k],
                        }),
                );
        }
        Ok(())
    }

    /// The last snapshot (highest round, then latest in the file) of each of `agents`.
    fn read_maps(&mut self, path: &Path, agents: &[u32]) -> Result<(), ReportError> {
        let mut r = MapReader::open(path)?;
        let mut last: Vec<Option<MapSnapshot>> = vec![None; agents.len()];
        while let Some(s) = r.next_snapshot()? {
            for (slot, a) in last.iter_mut().zip(agents) {
                if s.header.agent == *a
                    && slot
                        .as_ref()
                        .is_none_or(|o| s.header.round >= o.header.round)
                {
                    *slot = Some(s.clone());
                }
            }
        }
        for (slot, a) in last.into_iter().zip(agents) {
            match slot {
                Some(s) if (s.header.width, s.header.height) == (self.width, self.height) => {
                    self.maps.push(s)
                }
                Some(s) => self.notes.push(format!(
                    "{}: agent {a}'s snapshot is {} x {}, the map {} x {}",
                    path.display(),
                    s.header.width,
                    s.header.height,
                    self.width,
                    self.height
                )),
                None => self
                    .notes
                    .push(format!("{}: no snapshot of agent {a}", path.display())),
            }
        }
        Ok(())
    }
}

/// The robots of one collision (see [`RunData::read_collisions`]).
fn involved(poses: &[(u32, f64, f64)]) -> Vec<(u32, f64, f64)> {
    let mut best: Option<(f64, usize, usize)> = None;
    for i in 0..poses.len() {
        for j in i + 1..poses.len() {
            let d = (poses[i].1 - poses[j].1).hypot(poses[i].2 - poses[j].2);
            if best.is_none_or(|b| d < b.0) {
                best = Some((d, i, j));
            }
        }
    }
    match best {
        Some((d, i, j)) if d <= 1.0 => vec![poses[i], poses[j]],
        _ => poses.to_vec(),
    }
}

/// The summary's criteria in two lines: over the robots, mean and largest path optimality,
/// the last time to goal, energy beside its budget, repairs and false positives; then the
/// consensus latency. None when `summary` has no criteria (a summary of before them).
pub fn criteria_lines(summary: &serde_json::Value) -> Vec<String> {
    let Some(agents) = summary.get("agents").and_then(serde_json::Value::as_array) else {
        return Vec::new();
    };
    let f = |a: &serde_json::Value, k: &str| a.get(k).and_then(serde_json::Value::as_f64);
    let all = |k: &str| agents.iter().filter_map(|a| f(a, k)).collect::<Vec<f64>>();
    let sum = |k: &str| all(k).iter().sum::<f64>();
    if agents.iter().all(|a| a.get("energy_j").is_none()) {
        return Vec::new();
    }
    let opt = all("optimality");
    let optimality = match opt.len() {
        0 => "optimality -".to_string(),
        n => format!(
            "optimality mean {:.3} (max {:.3})",
            opt.iter().sum::<f64>() / n as f64,
            opt.iter().copied().fold(f64::MIN, f64::max)
        ),
    };
    let to_goal = all("time_to_goal_s")
        .into_iter()
        .reduce(f64::max)
        .map_or("-".to_string(), |t| format!("{t:.2} s"));
    let mut lines = vec![format!(
        "criteria: {optimality}, last at goal {to_goal}, energy {:.2} J (budget {:.2} J), repairs {:.0} partial / {:.0} rebuild / {:.0} route, {:.0} false positives",
        sum("energy_j"),
        sum("energy_budget_j"),
        sum("repairs_partial"),
        sum("repairs_rebuild"),
        sum("repairs_replan"),
        sum("false_positives"),
    )];
    if let Some(l) = summary.get("consensus_latency_us").filter(|l| !l.is_null()) {
        let u = |k: &str| l.get(k).and_then(serde_json::Value::as_u64).unwrap_or(0);
        lines.push(format!(
            "consensus: candidate -> commit p50 {} us, p99 {} us ({} rounds)",
            u("p50"),
            u("p99"),
            u("rounds")
        ));
    }
    lines
}

/// The simulated times at which a run's collision count rose, from its `summary.json`
/// (`recording.collisions_at_ns`; none without a recording). The report and the playback
/// both read them here.
pub(crate) fn collisions_at_ns(summary: &serde_json::Value) -> Vec<u64> {
    summary
        .pointer("/recording/collisions_at_ns")
        .and_then(serde_json::Value::as_array)
        .map(|a| a.iter().filter_map(serde_json::Value::as_u64).collect())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests;
mod world;
