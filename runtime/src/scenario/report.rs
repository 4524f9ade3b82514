//! `hnav check`: the facts about a validated scenario, as text for people and JSON for tools.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::params::{CoordinatorParams, RestartConfig, RobotParams, SimParams};
use super::Scenario;
use crate::grid::{octile, octile_shortest_path_len, CornerCutting};

/// The map part of a [`ScenarioReport`].
#[derive(Clone, PartialEq, Debug, Serialize)]
pub struct MapReport {
    /// The map file, or `"inline"`.
    pub source: String,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Blocked cells.
    pub blocked_cells: usize,
    /// Blocked cells in percent of all cells.
    pub blocked_percent: f64,
    /// Whether diagonals may pass blocked corners.
    pub corner_cutting: bool,
}

/// One agent in a [`ScenarioReport`].
#[derive(Clone, PartialEq, Debug, Serialize)]
pub struct AgentReport {
    /// Agent number (0-based, as in faults).
    pub index: usize,
    /// Start `[x, y]`.
    pub start: [u32; 2],
    /// Goal `[x, y]`.
    pub goal: [u32; 2],
    /// Start as the dissertation's 1-based cell id.
    pub start_id: u32,
    /// Goal as the dissertation's 1-based cell id.
    pub goal_id: u32,
    /// Speed in cells/s.
    pub speed: f64,
    /// Conflict priority in effect (given, or `1 / speed`).
    pub priority: f64,
    /// The planner that drives it (`"hnav"`, `"pso"`, `"ga-fuzzy"`).
    pub planner: &'static str,
    /// Straight-line octile distance, ignoring obstacles.
    pub octile_distance: f64,
    /// Shortest octile path length under the map's corner-cutting rule; `None` if unreachable.
    pub shortest_path_len: Option<f64>,
}

/// Everything `hnav check` reports.
#[derive(Clone, PartialEq, Debug, Serialize)]
pub struct ScenarioReport {
    /// Scenario name.
    pub name: String,
    /// Scenario file.
    pub source: String,
    /// [`Scenario::scenario_hash`] as 16 hex digits.
    pub scenario_hash: String,
    /// The map.
    pub map: MapReport,
    /// The agents.
    pub agents: Vec<AgentReport>,
    /// The fault plan, one line per fault.
    pub faults: Vec<String>,
    /// `[robot]` in effect.
    pub robot: RobotParams,
    /// `[sim]` in effect.
    pub sim: SimParams,
    /// `[coordinator]` in effect.
    pub coordinator: CoordinatorParams,
    /// `[restart]` in effect.
    pub restart: RestartConfig,
    /// Things that are legal but probably unintended (e.g. an unreachable goal).
    pub warnings: Vec<String>,
    /// A lifelong run's `[tasks]` in words; absent without the section.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tasks: Option<String>,
    /// How the world changes (`[[events]]`), one line each; absent without events.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<String>,
}

impl ScenarioReport {
    /// Computes the report (runs one shortest-path query per agent).
    pub fn new(s: &Scenario) -> ScenarioReport {
        let g = &s.map.grid;
        let rule = s.map.corner_cutting;
        let mut warnings = Vec::new();
        let agents = s
            .agents
            .iter()
            .enumerate()
            .map(|(index, a)| {
                let shortest = octile_shortest_path_len(g, a.start, a.goal, rule);
                if shortest.is_none() {
                    warnings.push(format!(
                        "agent {index}: goal {} is unreachable from start {} (allowed by \
                         allow_unreachable = true: the agent will report it and stand still)",
                        a.goal, a.start
                    ));
                }
                AgentReport {
                    index,
                    start: [a.start.x, a.start.y],
                    goal: [a.goal.x, a.goal.y],
                    start_id: g.cell_id(a.start),
                    goal_id: g.cell_id(a.goal),
                    speed: a.speed,
                    priority: a.effective_priority(),
                    planner: a.planner.name(),
                    octile_distance: octile(a.start, a.goal),
                    shortest_path_len: shortest,
                }
            })
            .collect();
        // As the command line writes them (`--kill agent:3@round:40`), one spelling for
        // both sources of a fault plan.
        let faults = s.faults.iter().map(ToString::to_string).collect();
        let tasks = s.tasks.as_ref().map(|t| {
            let stream = match t.stream {
                super::StreamKind::Seeded => format!("seeded stream, seed {}", t.seed),
                super::StreamKind::List => {
                    let lists = t.cycles.iter().filter(|c| c.len() > 1).count();
                    format!("lists of goals for {lists} of the agents, cycled")
                }
            };
            format!("{stream}; a lifelong run, ended by the time limit")
        });
        let events = s.events.iter().map(event_line).collect();
        ScenarioReport {
            tasks,
            events,
            name: s.name.clone(),
            source: s.source_name.clone(),
            scenario_hash: format!("{:016x}", s.scenario_hash()),
            map: MapReport {
                source: s
                    .map
                    .file
                    .as_deref()
                    .map_or_else(|| "inline".into(), |p| tidy_path(p).display().to_string()),
                width: g.width(),
                height: g.height(),
                blocked_cells: g.blocked_count(),
                blocked_percent: 100.0 * g.blocked_fraction(),
                corner_cutting: rule == CornerCutting::Allowed,
            },
            agents,
            faults,
            robot: s.robot.clone(),
            sim: s.sim.clone(),
            coordinator: s.coordinator.clone(),
            restart: s.restart,
            warnings,
        }
    }

    /// The human summary printed by `hnav check`.
    pub fn render(&self) -> String {
        let mut o = String::new();
        let m = &self.map;
        let _ = writeln!(o, "scenario  {}  ({})", self.name, self.source);
        let _ = writeln!(o, "hash      {}", self.scenario_hash);
        let _ = writeln!(
            o,
            "map       {} x {}, {} blocked ({:.1} %), corner cutting {}, {}",
            m.width,
            m.height,
            m.blocked_cells,
            m.blocked_percent,
            if m.corner_cutting {
                "allowed"
            } else {
                "forbidden"
            },
            m.source
        );
        let _ = writeln!(
            o,
            "run       {} clock, step {} ms, seed {}, round deadline {} ms, time limit {} s, rules {}",
            format!("{:?}", self.sim.clock).to_lowercase(),
            self.sim.step_ms,
            self.sim.seed,
            self.coordinator.round_deadline_ms,
            self.coordinator.time_limit_s,
            self.coordinator.rules.name()
        );
        let _ = writeln!(o, "agents    {}", self.agents.len());
        let _ = writeln!(
            o,
            "  {:>4}  {:<12} {:<12} {:>6} {:>8} {:>10} {:>10}  planner",
            "#", "start", "goal", "speed", "priority", "octile", "shortest"
        );
        for a in &self.agents {
            let shortest = a
                .shortest_path_len
                .map_or_else(|| "unreachable".into(), |l| format!("{l:.3}"));
            let _ = writeln!(
                o,
                "  {:>4}  {:<12} {:<12} {:>6.2} {:>8.3} {:>10.3} {:>10}  {}",
                a.index,
                format!("[{}, {}]", a.start[0], a.start[1]),
                format!("[{}, {}]", a.goal[0], a.goal[1]),
                a.speed,
                a.priority,
                a.octile_distance,
                shortest,
                a.planner
            );
        }
        if !self.faults.is_empty() {
            let _ = writeln!(o, "faults    {}", self.faults.join("; "));
        }
        for e in &self.events {
            let _ = writeln!(o, "event     {e}");
        }
        if let Some(t) = &self.tasks {
            let _ = writeln!(o, "tasks     {t}");
        }
        for w in &self.warnings {
            let _ = writeln!(o, "warning: {w}");
        }
        o
    }

    /// Writes [`REPORT_FILE`] into `dir` (created if needed) and returns its path.
    pub fn write_json(&self, dir: &Path) -> std::io::Result<PathBuf> {
        let path = dir.join(REPORT_FILE);
        self.write_json_to(&path)?;
        Ok(path)
    }

    /// Writes the report as JSON to `path` (its directory created if needed).
    pub fn write_json_to(&self, path: &Path) -> std::io::Result<()> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
        }
        let json = serde_json::to_string_pretty(self).map_err(std::io::Error::other)?;
        std::fs::write(path, json + "\n")
    }
}

/// Removes `.` and `dir/..` pairs lexically (`scenarios/../maps/x.map` -> `maps/x.map`), for
/// display only: with symbolic links the two spellings may differ, so the scenario keeps the
/// joined path it actually opened.
fn tidy_path(p: &Path) -> PathBuf {
    use std::path::Component;
    let mut out: Vec<Component<'_>> = Vec::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir if matches!(out.last(), Some(Component::Normal(_))) => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    if out.is_empty() {
        return PathBuf::from(".");
    }
    out.iter().collect()
}

/// The name of the report [`ScenarioReport::write_json`] writes into a directory.
pub const REPORT_FILE: &str = "scenario-report.json";

/// The default output directory of a scenario, `target/hnav-out/<name>`, with every character
/// outside `[A-Za-z0-9._-]` replaced by `_` so a name cannot escape the directory.
pub fn default_out_dir(name: &str) -> PathBuf {
    let mut safe: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    if safe.is_empty() || safe.chars().all(|c| c == '.') {
        safe = format!("_{safe}");
    }
    Path::new("target").join("hnav-out").join(safe)
}

/// One event in words: `at 1.20 s: close (5, 3), (5, 4)`.
fn event_line(e: &super::EventSpec) -> String {
    let cells = |c: &[crate::grid::Cell]| {
        let all: Vec<String> = c.iter().map(|c| format!("({}, {})", c.x, c.y)).collect();
        all.join(", ")
    };
    let what = match &e.change {
        super::WorldChange::Close(c) => format!("close {}", cells(c)),
        super::WorldChange::Open(c) => format!("open {}", cells(c)),
        super::WorldChange::Mover(m) => format!(
            "mover `{}` at {} cells/s{} from ({}, {}) over {} cells{}",
            m.name,
            m.speed,
            if m.repeat { ", back and forth" } else { "" },
            m.cells[0].x,
            m.cells[0].y,
            m.cells.len(),
            if m.yields {
                ""
            } else {
                ", yielding to no robot"
            }
        ),
    };
    format!("at {:.2} s: {what}", e.at_s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tidy_path_removes_dot_dot() {
        assert_eq!(
            tidy_path(Path::new("scenarios/../maps/x.map")),
            Path::new("maps/x.map")
        );
        assert_eq!(tidy_path(Path::new("./a/./b")), Path::new("a/b"));
        assert_eq!(tidy_path(Path::new("../../x")), Path::new("../../x"));
        assert_eq!(tidy_path(Path::new("/a/../b")), Path::new("/b"));
        assert_eq!(tidy_path(Path::new("a/..")), Path::new("."));
    }

    #[test]
    fn out_dir_is_sanitised() {
        assert_eq!(default_out_dir("demo"), Path::new("target/hnav-out/demo"));
        assert_eq!(
            default_out_dir("../x y"),
            Path::new("target/hnav-out/.._x_y")
        );
        assert_eq!(default_out_dir(".."), Path::new("target/hnav-out/_.."));
        assert_eq!(default_out_dir(""), Path::new("target/hnav-out/_"));
    }
}
