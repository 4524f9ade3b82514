//! `[tasks]`: goals that keep coming (lifelong operation, as in warehouse benchmarks).
//!
//! ```toml
//! [tasks]
//! stream = "seeded"      # or "list"
//! seed = 7               # seeded only; default the [sim] seed
//!
//! [[tasks.goals]]        # list only: a robot's goals after its [[agents]] goal
//! agent = 0
//! cells = [[5, 3], [0, 0]]
//! ```
//!
//! A robot's first goal is its `[[agents]] goal`. Once it stands on its current goal, the
//! coordinator gives it the next one ([`TaskStream::next`]) and logs the assignment (a
//! `task` record of the consensus log). With `stream = "seeded"` every next goal is drawn
//! from the free cells of the robot's connected part of the map, never the cell it stands
//! on nor another robot's current goal; with `stream = "list"` a robot with a `[[tasks.goals]]`
//! entry goes through its `[[agents]] goal` and `cells` in a cycle, and a robot without one
//! keeps its single goal. A scenario with `[tasks]` does not end when every robot stands on
//! its goal: it ends by time, at `[coordinator] time_limit_s` (end reason `time-limit`).
//!
//! Errors name the line: a `cells` entry off the map, on an obstacle, equal to the goal
//! before it in the cycle, or not reachable from the robot's start; an `agent` that is not
//! in the scenario or listed twice; `[[tasks.goals]]` with the seeded stream, `seed` with
//! the list; a robot with no other free cell to draw.
//!
//! The section is hashed only when present, so that every earlier scenario keeps its hash.

use serde::Deserialize;
use toml::Spanned;

use super::error::ScenarioError;
use super::lines::Lines;
use super::AgentSpec;
use crate::grid::{components, Cell, CornerCutting, Grid};
use crate::hash::SplitMix64;

/// `[tasks]` as `serde` sees it.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTasks {
    pub stream: Spanned<StreamKind>,
    pub seed: Option<Spanned<u64>>,
    #[serde(default)]
    pub goals: Vec<Spanned<RawGoals>>,
}

/// One `[[tasks.goals]]` entry.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawGoals {
    pub agent: Spanned<i64>,
    pub cells: Spanned<Vec<Spanned<Vec<i64>>>>,
}

/// Where the next goals come from.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[serde(rename_all = "kebab-case")]
pub enum StreamKind {
    /// Drawn from the free cells with a seed.
    Seeded,
    /// Each robot's own list, cycled.
    List,
}

/// The validated `[tasks]` section.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct TasksSpec {
    /// Where the next goals come from.
    pub stream: StreamKind,
    /// The seeded stream's seed.
    pub seed: u64,
    /// Per agent, its goals in the order they come, its `[[agents]] goal` first (list only;
    /// empty for the seeded stream).
    pub cycles: Vec<Vec<Cell>>,
}

/// Validates `[tasks]` against the agents and the map.
pub(super) fn build_tasks(
    raw: Option<Spanned<RawTasks>>,
    sim_seed: u64,
    agents: &[AgentSpec],
    (grid, corners): (&Grid, CornerCutting),
    lines: &Lines<'_>,
) -> Result<Option<TasksSpec>, ScenarioError> {
    let Some(raw) = raw else { return Ok(None) };
    let section = lines.at(&raw);
    let raw = raw.into_inner();
    let bad = |at, key: &str, problem: String| ScenarioError::InvalidParameter {
        at,
        key: key.into(),
        problem,
    };
    let stream = *raw.stream.get_ref();
    let label = components(grid, corners);
    match (stream, &raw.seed, raw.goals.first()) {
        (StreamKind::List, Some(s), _) => {
            let p = "is for `stream = \"seeded\"`; a list has no seed".to_string();
            return Err(bad(lines.at(s), "tasks.seed", p));
        }
        (StreamKind::Seeded, _, Some(g)) => {
            let p = "are for `stream = \"list\"`; the seeded stream draws the goals".to_string();
            return Err(bad(lines.at(g), "tasks.goals", p));
        }
        (StreamKind::Seeded, _, None) => {
            for (i, a) in agents.iter().enumerate() {
                let part = label[grid.index(a.start)];
                if !label.iter().enumerate().any(|(c, &l)| {
                    l == part && c != grid.index(a.goal) && c != grid.index(a.start)
                }) {
                    let p = format!("agent {i} has no free cell to draw a next goal from");
                    return Err(bad(section, "tasks.stream", p));
                }
            }
        }
        (StreamKind::List, None, _) => {}
    }
    let mut cycles: Vec<Vec<Cell>> = match stream {
        StreamKind::List => agents.iter().map(|a| vec![a.goal]).collect(),
        StreamKind::Seeded => Vec::new(),
    };
    for entry in &raw.goals {
        let e = entry.get_ref();
        let at = lines.at(&e.agent);
        let i = *e.agent.get_ref();
        let Some(a) = usize::try_from(i).ok().and_then(|k| agents.get(k)) else {
            let p = format!("names agent {i}; the scenario has agents 0 to {}", agents.len() - 1);
            return Err(bad(at, "tasks.goals.agent", p));
        };
        let k = i as usize;
        if cycles[k].len() > 1 {
            let p = format!("agent {k} has a [[tasks.goals]] entry already");
            return Err(bad(at, "tasks.goals.agent", p));
        }
        if e.cells.get_ref().is_empty() {
            let p = "is empty; give at least one [x, y]".to_string();
            return Err(bad(lines.at(&e.cells), "tasks.goals.cells", p));
        }
        for c in e.cells.get_ref() {
            let at = lines.at(c);
            let cell = goal_cell(c.get_ref(), grid).map_err(|p| bad(at.clone(), "tasks.goals.cells", p))?;
            if label[grid.index(cell)] != label[grid.index(a.start)] {
                let p = format!("({}, {}) cannot be reached from agent {k}'s start", cell.x, cell.y);
                return Err(bad(at, "tasks.goals.cells", p));
            }
            if cycles[k].last() == Some(&cell) {
                let p = format!("({}, {}) repeats the goal before it", cell.x, cell.y);
                return Err(bad(at, "tasks.goals.cells", p));
            }
            cycles[k].push(cell);
        }
        if cycles[k].first() == cycles[k].last() {
            let p = "the last goal is the [[agents]] goal the cycle starts again with".to_string();
            return Err(bad(lines.at(&e.cells), "tasks.goals.cells", p));
        }
    }
    Ok(Some(TasksSpec {
        stream,
        seed: raw.seed.map_or(sim_seed, |s| *s.get_ref()),
        cycles,
    }))
}

/// `[x, y]` as a free cell of `grid`, or what is wrong with it.
fn goal_cell(xy: &[i64], grid: &Grid) -> Result<Cell, String> {
    let [x, y] = xy else {
        return Err(format!("a goal must be [x, y], got {} numbers", xy.len()));
    };
    let inside = |v: i64, n: u32| u32::try_from(v).ok().filter(|&v| v < n);
    let (Some(cx), Some(cy)) = (inside(*x, grid.width()), inside(*y, grid.height())) else {
        return Err(format!(
            "({x}, {y}) is outside the {}x{} map",
            grid.width(),
            grid.height()
        ));
    };
    let cell = Cell::new(cx, cy);
    if grid.is_blocked(cell) {
        return Err(format!("({x}, {y}) is on an obstacle"));
    }
    Ok(cell)
}

/// The goals of a lifelong run as the coordinator hands them out: per agent its current goal
/// and how many it has been given. Every draw depends only on the seed, the agent, its task
/// number and the other agents' current goals, all of which the consensus log holds, so a
/// coordinator restarted (or a replica elected) from the log draws the same next goals.
#[derive(Clone, Debug)]
pub struct TaskStream {
    spec: TasksSpec,
    goals: Vec<Cell>,
    /// Tasks given so far per agent (0: only its `[[agents]] goal`).
    given: Vec<u64>,
    /// Seeded: per agent, the free cells of its start's connected part of the map.
    pool: Vec<std::sync::Arc<Vec<Cell>>>,
}

impl TaskStream {
    /// The stream of a scenario with `[tasks]`, every agent on its first goal.
    pub fn new(spec: &TasksSpec, agents: &[AgentSpec], grid: &Grid, corners: CornerCutting) -> Self {
        let mut pool = Vec::new();
        if spec.stream == StreamKind::Seeded {
            let label = components(grid, corners);
            let mut parts: std::collections::HashMap<u32, std::sync::Arc<Vec<Cell>>> =
                std::collections::HashMap::new();
            for a in agents {
                let part = label[grid.index(a.start)];
                let cells = parts.entry(part).or_insert_with(|| {
                    std::sync::Arc::new(
                        grid.passable_cells()
                            .filter(|&c| label[grid.index(c)] == part)
                            .collect(),
                    )
                });
                pool.push(cells.clone());
            }
        }
        TaskStream {
            spec: spec.clone(),
            goals: agents.iter().map(|a| a.goal).collect(),
            given: vec![0; agents.len()],
            pool,
        }
    }

    /// Agent `agent`'s current goal.
    pub fn goal(&self, agent: usize) -> Option<Cell> {
        self.goals.get(agent).copied()
    }

    /// Tasks given to agent `agent` after its first goal.
    pub fn given(&self, agent: usize) -> u64 {
        self.given.get(agent).copied().unwrap_or(0)
    }

    /// Agent `agent`, standing on its current goal, gets its next one: `(task number, goal)`,
    /// with the task number counted from 1. `None` for a robot of a list without more goals.
    pub fn next(&mut self, agent: usize) -> Option<(u64, Cell)> {
        let k = self.given.get(agent)? + 1;
        let here = self.goals[agent];
        let goal = match self.spec.stream {
            StreamKind::List => {
                let cycle = self.spec.cycles.get(agent).filter(|c| c.len() > 1)?;
                cycle[(k % cycle.len() as u64) as usize]
            }
            StreamKind::Seeded => {
                let pool = &self.pool[agent];
                let taken = |c: &Cell| *c == here || self.goals.contains(c);
                let mut rng = SplitMix64::new(
                    self.spec.seed ^ SplitMix64::new((agent as u64) << 32 ^ k).next_u64(),
                );
                // A few draws nearly always find a free cell; the scan after them makes the
                // draw total (validation saw at least one cell besides the robot's own).
                let drawn = (0..64)
                    .map(|_| pool[rng.below(pool.len() as u64) as usize])
                    .find(|c| !taken(c));
                drawn.or_else(|| pool.iter().copied().find(|c| !taken(c)))?
            }
        };
        self.assigned(agent, k, goal);
        Some((k, goal))
    }

    /// Agent `agent` was given task `task` with `goal` (a replayed record, or [`Self::next`]).
    pub fn assigned(&mut self, agent: usize, task: u64, goal: Cell) {
        if let (Some(g), Some(n)) = (self.goals.get_mut(agent), self.given.get_mut(agent)) {
            *g = goal;
            *n = task;
        }
    }
}
