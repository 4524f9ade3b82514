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
                if !label
                    .iter()
                    .enumerate()
                    .any(|(c, &l)| l == part && c != grid.index(a.goal) && c != grid.index(a.start))
                {
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
            let p = format!(
                "names agent {i}; the scenario has agents 0 to {}",
                agents.len() - 1
            );
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
            let cell = goal_cell(c.get_ref(), grid)
                .map_err(|p| bad(at.clone(), "tasks.goals.cells", p))?;
            if label[grid.index(cell)] != label[grid.index(a.start)] {
                let p = format!(
                    "({}, {}) cannot be reached from agent {k}'s start",
                    cell.x, cell.y
                );
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
    let cell = super::events::on_map(xy, grid)?;
    if grid.is_blocked(cell) {
        return Err(format!("({}, {}) is on an obstacle", cell.x, cell.y));
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
    pub fn new(
        spec: &TasksSpec,
        agents: &[AgentSpec],
        grid: &Grid,
        corners: CornerCutting,
    ) -> Self {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::test_support::{parse, BASE};

    fn with(tasks: &str) -> Result<crate::scenario::Scenario, ScenarioError> {
        parse(&format!("{BASE}[tasks]\n{tasks}"))
    }

    /// Line 16 is `[tasks]`, the section's first key is on line 17.
    fn error(tasks: &str) -> String {
        with(tasks).unwrap_err().to_string()
    }

    #[test]
    fn a_list_cycles_through_the_goals_and_a_robot_without_one_keeps_its_goal() {
        let s = with("stream = \"list\"\n[[tasks.goals]]\nagent = 1\ncells = [[2, 0], [4, 2]]\n")
            .unwrap();
        let spec = s.tasks.clone().unwrap();
        assert_eq!(spec.cycles[0], [Cell::new(5, 3)]);
        assert_eq!(
            spec.cycles[1],
            [Cell::new(0, 3), Cell::new(2, 0), Cell::new(4, 2)]
        );
        let mut t = TaskStream::new(&spec, &s.agents, &s.map.grid, s.map.corner_cutting);
        assert_eq!(t.next(0), None);
        let got: Vec<(u64, Cell)> = (0..4).filter_map(|_| t.next(1)).collect();
        assert_eq!(
            got,
            [
                (1, Cell::new(2, 0)),
                (2, Cell::new(4, 2)),
                (3, Cell::new(0, 3)),
                (4, Cell::new(2, 0))
            ]
        );
        assert_ne!(s.scenario_hash(), parse(BASE).unwrap().scenario_hash());
    }

    #[test]
    fn the_seeded_stream_repeats_itself_and_avoids_taken_cells() {
        let s = with("stream = \"seeded\"\nseed = 9\n").unwrap();
        let spec = s.tasks.clone().unwrap();
        assert_eq!(spec.seed, 9);
        let stream = || TaskStream::new(&spec, &s.agents, &s.map.grid, s.map.corner_cutting);
        let (mut a, mut b) = (stream(), stream());
        for k in 1..200 {
            let here = a.goal(0).unwrap();
            let other = a.goal(1).unwrap();
            let (task, g) = a.next(0).unwrap();
            assert_eq!((task, g), b.next(0).unwrap());
            assert_eq!(task, k);
            assert!(
                g != here && g != other && !s.map.grid.is_blocked(g),
                "{g:?}"
            );
        }
        // A replayed assignment puts a fresh stream where the first one is.
        let mut c = stream();
        c.assigned(0, a.given(0), a.goal(0).unwrap());
        assert_eq!(c.next(0), a.next(0));
        // Without a seed, the sim's.
        let s = with("stream = \"seeded\"\n").unwrap();
        assert_eq!(s.tasks.unwrap().seed, s.sim.seed);
    }

    #[test]
    fn bad_tasks_name_their_line_and_what_is_wrong() {
        assert_eq!(
            error("stream = \"list\"\n[[tasks.goals]]\nagent = 0\ncells = [[9, 0]]\n"),
            "t.toml:20: tasks.goals.cells (9, 0) is outside the 6x4 map"
        );
        assert_eq!(
            error("stream = \"list\"\n[[tasks.goals]]\nagent = 0\ncells = [[0, 0],\n [1, 1]]\n"),
            "t.toml:21: tasks.goals.cells (1, 1) is on an obstacle"
        );
        assert_eq!(
            error("stream = \"list\"\n[[tasks.goals]]\nagent = 0\ncells = [[5, 3]]\n"),
            "t.toml:20: tasks.goals.cells (5, 3) repeats the goal before it"
        );
        assert_eq!(
            error("stream = \"list\"\n[[tasks.goals]]\nagent = 2\ncells = [[0, 0]]\n"),
            "t.toml:19: tasks.goals.agent names agent 2; the scenario has agents 0 to 1"
        );
        assert_eq!(
            error("stream = \"list\"\n[[tasks.goals]]\nagent = 0\ncells = [[1, 0]]\n[[tasks.goals]]\nagent = 0\ncells = [[2, 0]]\n"),
            "t.toml:22: tasks.goals.agent agent 0 has a [[tasks.goals]] entry already"
        );
        assert_eq!(
            error("stream = \"seeded\"\n[[tasks.goals]]\nagent = 0\ncells = [[1, 0]]\n"),
            "t.toml:18: tasks.goals are for `stream = \"list\"`; the seeded stream draws the goals"
        );
        assert_eq!(
            error("stream = \"list\"\nseed = 3\n"),
            "t.toml:18: tasks.seed is for `stream = \"seeded\"`; a list has no seed"
        );
        assert_eq!(
            error("stream = \"list\"\n[[tasks.goals]]\nagent = 0\ncells = []\n"),
            "t.toml:20: tasks.goals.cells is empty; give at least one [x, y]"
        );
        assert_eq!(
            error("stream = \"list\"\n[[tasks.goals]]\nagent = 0\ncells = [[1, 0, 2]]\n"),
            "t.toml:20: tasks.goals.cells a cell must be [x, y], got 3 numbers"
        );
        let e = error("stream = \"sometimes\"\n");
        assert!(e.starts_with("t.toml:17: "), "{e}");
        let e = error("seed = 1\n");
        assert!(e.starts_with("t.toml:") && e.contains("`stream`"), "{e}");
    }

    #[test]
    fn a_goal_cut_off_from_the_start_and_a_robot_with_nothing_to_draw_are_refused() {
        let walled =
            "name = \"w\"\n[map]\nrows = [\".@.\"]\n[[agents]]\nstart = [0, 0]\ngoal = [0, 0]\n";
        // start == goal is allowed for an agent; the seeded stream then has no other cell.
        let e = parse(&format!("{walled}[tasks]\nstream = \"seeded\"\n"));
        assert_eq!(
            e.unwrap_err().to_string(),
            "t.toml:7: tasks.stream agent 0 has no free cell to draw a next goal from"
        );
        let e = parse(&format!(
            "{walled}[tasks]\nstream = \"list\"\n[[tasks.goals]]\nagent = 0\ncells = [[2, 0]]\n"
        ));
        assert_eq!(
            e.unwrap_err().to_string(),
            "t.toml:11: tasks.goals.cells (2, 0) cannot be reached from agent 0's start"
        );
    }
}
