//! `[coordinator] rules = "lacam"`: PIBT made complete. The coordinator plans every robot's
//! moves at once with LaCAM ([`search`], Okumura, AAAI 2023), whose steps are PIBT steps, and
//! executes the plan as an action dependency graph (`schedule.rs`), so robots that drive at
//! their own pace and hold a cell until they have left it never meet and never wait for ever.
//!
//! Online PIBT ([`Pibt`]) decides one round at a time and is incomplete on these robots: its
//! reachability theorem needs the pusher to enter the vacated cell in the same step, and maps
//! with dead ends and corridors are outside it anyway (`docs/explanation/conflict-rules.md` gives the
//! robots it left away from home). LaCAM searches configurations until it has a plan to the
//! goals, and a plan found is a plan executed to the end.
//!
//! # When it plans
//!
//! In the first round in which every robot that takes part (active or on its goal, as for
//! PIBT) is at rest: at the start of a run, and again after the plan broke (a robot stopped,
//! went missing, is not where the plan has it, or a standing one takes part again). Robots
//! standing still are fixed obstacles of the plan. While robots are still driving toward a
//! replan, the others wait. A search that fails (its [`Budget`] is spent, or no plan exists,
//! or a robot's goal is cut off on the map) leaves the round to online PIBT for
//! [`RETRY_ROUNDS`] rounds before the next attempt.
//!
//! # What it costs
//!
//! The search allocates and may take a while (milliseconds for the benchmark's instances, see
//! `docs/explanation/conflict-rules.md`); it runs in the round that plans, once per plan. Every other round follows the
//! schedule without allocating. Its memory is its [`Budget`]'s: `8 n` bytes a configuration of
//! `n` robots, in one arena with a hash index (`arena.rs`), see [`search`].
//!
//! # The search alone
//!
//! [`standalone`] runs the same search on a MAPF instance without rounds, for the
//! search-only benchmark (`hnav-bench lacam`), with LaCAM*'s refinement under a wall-clock
//! deadline, which the rounds leave off (a lockstep run never reads the clock). LaCAM3's swap
//! in the generator (`swap.rs`) is on in both: without it the search of 1 000 robots on the
//! warehouse map ran out of its budget after 29 s in every attempt of a run (online PIBT
//! then drove, and the round stalled for the attempt every [`RETRY_ROUNDS`] rounds); with
//! it the search alone finds a plan in 0.08 s.

mod arena;
mod generator;
mod graph;
mod schedule;
pub mod search;
#[cfg(test)]
mod search_tests;
pub mod standalone;
mod swap;
#[cfg(test)]
mod tests;
mod tree;

use hnav_runtime::grid::{Cell, Grid};

use super::pibt::distance::UNREACHABLE;
use super::pibt::Pibt;
use super::shared_paths::{AgentMode, AgentRow, Options, Outcome};
use generator::Problem;
use graph::Graph;
use schedule::Schedule;
pub use search::{Budget, SearchError};

/// Rounds of online PIBT after a failed search before the next one.
pub const RETRY_ROUNDS: u64 = 1000;

/// What the round is doing.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Phase {
    /// Waiting for the robots to come to rest, to plan.
    Settling,
    /// Following a plan.
    Following,
    /// Online PIBT after a failed search, until the given round.
    Fallback(u64),
}

/// Counts of what the rounds did, for the log and the benchmark.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct Stats {
    /// Plans found.
    pub plans: u32,
    /// Searches that failed.
    pub failed: u32,
    /// Plans broken before their end.
    pub broken: u32,
    /// Steps (synchronous moves) of the last plan found.
    pub steps: u32,
    /// Configurations the last search visited.
    pub visited: u32,
    /// Moves of the last plan found, over all robots.
    pub moves: u32,
    /// Why the last failed search failed.
    pub last_error: Option<SearchError>,
}

/// LaCAM rounds for one map and one set of goals; see the [module docs](self).
#[derive(Clone, Debug)]
pub struct Lacam {
    width: u32,
    options: Options,
    graph: Graph,
    pibt: Pibt,
    goals: Vec<u32>,
    blocked: Vec<bool>,
    budget: Budget,
    schedule: Option<Schedule>,
    phase: Phase,
    round: u64,
    stats: Stats,
}

impl Lacam {
    /// Rounds on `grid` for agents heading for `goals` (`goals[i]` is agent `i`'s).
    pub fn new(grid: &Grid, goals: &[Cell], options: Options) -> Self {
        Lacam {
            width: grid.width(),
            options,
            graph: Graph::new(grid, options),
            pibt: Pibt::new(grid, goals, options),
            goals: goals.iter().map(|&g| grid.index(g) as u32).collect(),
            blocked: vec![false; grid.len()],
            budget: Budget::default(),
            schedule: None,
            phase: Phase::Settling,
            round: 0,
            stats: Stats::default(),
        }
    }

    /// Agent `agent` heads for `goal` from now on (a lifelong run's next task, on the `grid`
    /// these rounds were made for). The plan being followed led to the old goals: it is
    /// dropped, and the robots settle and are planned for again.
    pub fn set_goal(&mut self, grid: &Grid, agent: usize, goal: Cell) {
        if let Some(g) = self.goals.get_mut(agent) {
            *g = grid.index(goal) as u32;
        }
        self.pibt.set_goal(grid, agent, goal);
        if self.schedule.take().is_some() {
            self.phase = Phase::Settling;
        }
    }

    /// The map changed: `grid` has the shape these rounds were made for. The plan being
    /// followed may cross a cell that closed (or miss a shorter way that opened): it is
    /// dropped, and the robots settle and are planned for again on the new map.
    pub fn set_map(&mut self, grid: &Grid) {
        self.graph = Graph::new(grid, self.options);
        self.pibt.set_map(grid);
        if self.schedule.take().is_some() {
            self.phase = Phase::Settling;
        }
    }

    /// Sets the search budget.
    pub fn set_budget(&mut self, budget: Budget) {
        self.budget = budget;
    }

    /// What the rounds are doing.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// What the rounds did so far.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// The distance from `cell` to agent `agent`'s goal (see [`Pibt::distance`]).
    pub fn distance(&self, agent: usize, cell: Cell) -> u32 {
        self.pibt.distance(agent, cell)
    }

    /// Decides one round: `out[i]` is the outcome for `rows[i]`. `out` is cleared first.
    pub fn resolve(&mut self, rows: &[AgentRow], out: &mut Vec<Outcome>) {
        self.resolve_with(rows, out, &mut || {});
    }

    /// [`Lacam::resolve`], calling `tick` often while a search runs (the coordinator beats its
    /// heartbeat there: a search of seconds is not a hang).
    pub fn resolve_with(
        &mut self,
        rows: &[AgentRow],
        out: &mut Vec<Outcome>,
        tick: &mut dyn FnMut(),
    ) {
        self.round += 1;
        if self.phase == Phase::Following
            && !self.schedule.as_ref().is_some_and(|s| s.follows(rows))
        {
            self.stats.broken += u32::from(!self.schedule.as_ref().is_some_and(|s| s.done()));
            self.schedule = None;
            self.phase = Phase::Settling;
        }
        if let Phase::Fallback(until) = self.phase {
            if self.round >= until {
                self.phase = Phase::Settling;
            }
        }
        if self.phase == Phase::Settling {
            if !rows
                .iter()
                .all(|r| r.mode == AgentMode::Standing || r.is_at_rest())
            {
                // Nobody starts a move until the others have arrived.
                out.clear();
                out.resize(rows.len(), Outcome::default());
                return;
            }
            self.plan(rows, tick);
        }
        match (&mut self.schedule, self.phase) {
            (Some(s), Phase::Following) => s.decide(rows, out),
            _ => self.pibt.resolve(rows, out),
        }
    }

    /// Searches a plan from the rows (all at rest or standing) and follows it, or falls back.
    fn plan(&mut self, rows: &[AgentRow], tick: &mut dyn FnMut()) {
        let index = |c: Cell| c.y * self.width + c.x;
        self.blocked.fill(false);
        let mut members = Vec::new();
        let mut starts = Vec::new();
        let mut goals = Vec::new();
        for (i, row) in rows.iter().enumerate() {
            if row.mode == AgentMode::Standing || i >= self.goals.len() {
                for c in row.held(&self.options).into_iter().flatten() {
                    if let Some(b) = self.blocked.get_mut(index(c) as usize) {
                        *b = true;
                    }
                }
                continue;
            }
            members.push(i as u32);
            starts.push(index(row.current));
            goals.push(self.goals[i]);
        }
        // The clock is only reported, never decides: a lockstep run plans the same way
        // everywhere.
        let started = std::time::Instant::now();
        let cut_off = members
            .iter()
            .zip(&starts)
            .any(|(&a, &s)| self.pibt.distance(a as usize, self.cell(s)) == UNREACHABLE);
        let result = if cut_off {
            Err(SearchError::NoPlan)
        } else {
            let pibt = &self.pibt;
            let (width, members_ref) = (self.width, &members);
            let distance = move |k: usize, c: u32| {
                pibt.distance(members_ref[k] as usize, Cell::new(c % width, c / width))
            };
            let problem = Problem {
                graph: &self.graph,
                fixed: &self.blocked,
                goals: &goals,
                distance: &distance,
                swap: true,
            };
            search::solve(&problem, &starts, self.budget, None, tick)
        };
        let took = started.elapsed();
        match result {
            Ok(plan) => {
                tracing::info!(
                    round = self.round,
                    robots = starts.len(),
                    steps = plan.configs.len().saturating_sub(1),
                    configurations = plan.visited,
                    seconds = took.as_secs_f64(),
                    "lacam: plan found"
                );
                self.stats.plans += 1;
                self.stats.steps = plan.configs.len().saturating_sub(1) as u32;
                self.stats.visited = plan.visited as u32;
                let s = Schedule::new(&self.graph, self.width, members, &plan.configs);
                self.stats.moves = s.moves() as u32;
                self.schedule = Some(s);
                self.phase = Phase::Following;
            }
            Err(e) => {
                tracing::warn!(
                    round = self.round,
                    robots = starts.len(),
                    seconds = took.as_secs_f64(),
                    "lacam: {e}; online PIBT for {RETRY_ROUNDS} rounds"
                );
                self.stats.failed += 1;
                self.stats.last_error = Some(e);
                self.schedule = None;
                self.phase = Phase::Fallback(self.round + RETRY_ROUNDS);
            }
        }
    }

    fn cell(&self, index: u32) -> Cell {
        Cell::new(index % self.width, index / self.width)
    }
}
