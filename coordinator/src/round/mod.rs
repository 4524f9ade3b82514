//! The decision round of the central compute block, free of I/O: the round's candidates in,
//! the decisions (and the global replans) out. The coordinator process wraps it in the
//! Waiter loop, the consensus log and the commit topic.
//!
//! The arbiter keeps each agent's last known row, moved on by its own decisions (`next <-`
//! the accepted cell) and, after a coordinator restart, rebuilt from the logged decisions
//! ([`Arbiter::replay`]). An agent missing from a round (late, dead, restarting) keeps its
//! cells, the one it was committed to included, and counts as standing still: a stable
//! position (type d) for the others, as the architecture says. Priorities come from the scenario, not from the
//! candidates, so a confused agent cannot promote itself.
//!
//! **Hybrid mode.** An agent that asked and was refused or held for `replan_after_rounds`
//! rounds in a row, or that reports a local extremum of its map, is replanned globally: Lazy
//! Theta* over the map with every other agent's held cells as obstacles (falling back to the
//! standing agents only when that finds nothing). The answer is one waypoint, the first
//! vertex of the any-angle path: it is in line of sight, so the agent's neural map toward it
//! leads straight there. When that vertex is the goal itself (the goal is in sight and the
//! agent is stuck anyway) the waypoint is A*'s cell a few steps ahead, which steers it around
//! the agent in the way.
//!
//! **Rules.** `[coordinator] rules` picks the round: the dissertation's [`Resolver`] with the
//! hybrid replanning above (`dissertation`), or [`Pibt`] (`pibt`), which may move an agent
//! other than it asked, also one that asked for nothing; such a decision is published only
//! when the agent moves. PIBT needs no replanning (its priorities rise until an agent gets
//! through), so none is made in that mode. [`Lacam`] (`lacam`) plans every robot's moves at
//! once and executes the plan, deciding like `pibt` (no replanning either).
//!
//! **Tasks** (`tasks.rs`). In a lifelong run (`[tasks]`) an agent that stands on its goal and
//! is not moved this round is given its next goal: a `task` decision, and a task record the
//! coordinator logs before the round's. The rules head for the new goal from the next round.
//!
//! **A changing world** (`world.rs`). With `[sensing]` the agents report the cells they saw
//! close or open; what differs from the arbiter's map is a map change, logged before the round
//! it is first decided in; from then on the rules and the global replans decide on the
//! changed map.

use hnav_runtime::consensus_log::{LoggedDecision, ReplanRecord, RoundRecord, Tally, TaskRecord};
use hnav_runtime::grid::{Cell, Direction, Grid};
use hnav_runtime::msg::{Candidate, CandidateFlags, Decision, Verdict, NO_CELL};
use hnav_runtime::rejected::Rejected;
use hnav_runtime::scenario::{Rules, Scenario, TaskStream};

use crate::conflict::{AgentMode, AgentRow, Lacam, Options, Outcome, Pibt, Resolver};
use crate::planner::{AStar, LazyTheta, Planner, PlannerConfig};

/// How many A* steps ahead the fallback waypoint lies.
const FALLBACK_STEPS: usize = 4;

/// The round of `[coordinator] rules`.
enum Round {
    Dissertation(Resolver),
    Pibt(Box<Pibt>),
    Lacam(Box<Lacam>),
}

/// The coordinator's round logic; see the [module docs](self).
pub struct Arbiter {
    grid: Grid,
    /// The scenario's blocked cells: what [`Arbiter::world`] tells the changes from.
    start: Vec<bool>,
    scratch: Grid,
    round: Round,
    rows: Vec<AgentRow>,
    flags: Vec<u32>,
    waiting: Vec<u32>,
    goals: Vec<Cell>,
    priorities: Vec<f64>,
    /// Per agent, the priority and speed its candidates carry (the scenario's, as `f32`).
    claims: Vec<(f32, f32)>,
    replan_after: u32,
    outcomes: Vec<Outcome>,
    decisions: Vec<Decision>,
    replans: Vec<ReplanRecord>,
    tally: Tally,
    lazy: LazyTheta,
    astar: AStar,
    /// A lifelong run's goals (`[tasks]`), `None` otherwise.
    tasks: Option<TaskStream>,
    /// The tasks given in the last round decided.
    assigned: Vec<TaskRecord>,
}

impl Arbiter {
    /// An arbiter for the scenario's map and agents, every agent at rest on its start.
    pub fn new(scenario: &Scenario) -> Self {
        let grid = scenario.map.grid.clone();
        let n = scenario.agents.len();
        let options = Options {
            corner_cutting: scenario.map.corner_cutting,
            ..Options::default()
        };
        let config = PlannerConfig::new(scenario.map.corner_cutting);
        let goals: Vec<Cell> = scenario.agents.iter().map(|a| a.goal).collect();
        let round = match scenario.coordinator.rules {
            Rules::Dissertation => Round::Dissertation(Resolver::new(&grid, n, options)),
            Rules::Pibt => Round::Pibt(Box::new(Pibt::new(&grid, &goals, options))),
            Rules::Lacam => Round::Lacam(Box::new(Lacam::new(&grid, &goals, options))),
        };
        Arbiter {
            start: grid.blocked().to_vec(),
            scratch: grid.clone(),
            round,
            rows: scenario
                .agents
                .iter()
                .map(|a| AgentRow::at_rest(a.start, None, a.effective_priority()))
                .collect(),
            flags: vec![0; n],
            waiting: vec![0; n],
            goals,
            priorities: scenario
                .agents
                .iter()
                .map(|a| a.effective_priority())
                .collect(),
            claims: scenario
                .agents
                .iter()
                .map(|a| (a.effective_priority() as f32, a.speed as f32))
                .collect(),
            replan_after: scenario.coordinator.replan_after_rounds.max(1),
            outcomes: Vec::with_capacity(n),
            decisions: Vec::with_capacity(n),
            replans: Vec::new(),
            tally: Tally::new(
                scenario.agents.iter().map(|a| grid.index(a.start) as u32),
                grid.width(),
            ),
            lazy: LazyTheta::new(config.clone()),
            astar: AStar::new(config),
            tasks: scenario
                .tasks
                .as_ref()
                .map(|t| TaskStream::new(t, &scenario.agents, &grid, scenario.map.corner_cutting)),
            assigned: Vec::new(),
            grid,
        }
    }

    /// Agents in the run.
    pub fn agents(&self) -> usize {
        self.rows.len()
    }

    /// Checks what a candidate says against what its agent can truthfully say, apart from the
    /// round (which the caller knows): the agent index, the flag bits and reserved field, the
    /// priority and speed (exactly the scenario's, as the agent sends them) and the cells (on
    /// the map; `next` is `current` or a neighbour, `probable` is [`NO_CELL`] or a neighbour
    /// of `next` or `current`). Returns the first check that fails.
    pub fn check(&self, c: &Candidate) -> Result<(), Rejected> {
        let Some(&(priority, speed)) = self.claims.get(c.agent as usize) else {
            return Err(Rejected::Agent);
        };
        if c.flags & !CandidateFlags::ALL != 0 || c.reserved != 0 {
            return Err(Rejected::Flags);
        }
        // Bit equality: NaN never equals itself, and -0.0 is not what any agent sends.
        if c.priority.to_bits() != priority.to_bits() || c.speed.to_bits() != speed.to_bits() {
            return Err(Rejected::PrioritySpeed);
        }
        let cell = |v: u32| self.grid.cell_at(v as usize);
        let (Some(current), Some(next)) = (cell(c.current), cell(c.next)) else {
            return Err(Rejected::Cell);
        };
        let step = |a: Cell, b: Cell| Direction::between(a, b).is_some();
        if next != current && !step(current, next) {
            return Err(Rejected::Cell);
        }
        if c.probable != NO_CELL {
            match cell(c.probable) {
                Some(p) if step(next, p) || step(current, p) => {}
                _ => return Err(Rejected::Cell),
            }
        }
        Ok(())
    }

    /// Classifies a candidate when rounds up to `decided` are decided: [`Arbiter::check`],
    /// then its round, which must be the open one (`decided + 1`).
    pub fn classify(&self, c: &Candidate, decided: u64) -> Result<(), Rejected> {
        self.check(c)?;
        if c.round > decided.saturating_add(1) {
            Err(Rejected::FutureRound)
        } else if c.round <= decided {
            Err(Rejected::PastRound)
        } else {
            Ok(())
        }
    }

    /// Decides one round. `candidates[i]` is agent `i`'s candidate (checked with
    /// [`Arbiter::check`]) or `None` if it is missing. Returns the decisions for the agents that
    /// asked for something (in agent order) and the replans made.
    pub fn decide(
        &mut self,
        round: u64,
        candidates: &[Option<Candidate>],
    ) -> (&[Decision], &[ReplanRecord]) {
        self.decide_with(round, candidates, &mut || {})
    }

    /// [`Arbiter::decide`], calling `tick` often while a long computation runs (LaCAM's
    /// search), so that the caller can keep its heartbeat going. A round is three steps: the
    /// candidates are read into the rows, the rows resolved by the run's rules, and each
    /// outcome answered (with a waypoint, when the rules replan and the agent is stuck).
    pub fn decide_with(
        &mut self,
        round: u64,
        candidates: &[Option<Candidate>],
        tick: &mut dyn FnMut(),
    ) -> (&[Decision], &[ReplanRecord]) {
        self.decisions.clear();
        self.replans.clear();
        self.assigned.clear();
        self.read(candidates);
        let replanning = self.resolve(tick);
        for i in 0..self.rows.len() {
            let answer = self.answer(round, i, replanning);
            if let Some(d) = self.give_task(round, i, answer) {
                // The tally counts what is published (and logged), so that a replay of the
                // log after a restart and the run summary arrive at the same numbers.
                self.tally.fold(&LoggedDecision::from(&d));
                self.decisions.push(d);
            }
        }
        for d in &self.decisions {
            if d.verdict == Verdict::Accept as u8 {
                if let (Some(row), Some(cell)) = (
                    self.rows.get_mut(d.agent as usize),
                    self.grid.cell_at(d.cell as usize),
                ) {
                    // `next <- cell`: an agent silent in the next round (late, or killed on
                    // its way) keeps the cell it was committed to.
                    row.next = cell;
                }
            }
        }
        (&self.decisions, &self.replans)
    }

    /// Takes the round's candidates into the rows: an agent missing from the round keeps its
    /// cells and stands.
    fn read(&mut self, candidates: &[Option<Candidate>]) {
        for (i, row) in self.rows.iter_mut().enumerate() {
            match candidates.get(i).copied().flatten() {
                Some(c) => {
                    let cell = |v: u32| self.grid.cell_at(v as usize);
                    row.current = cell(c.current).unwrap_or(row.current);
                    row.next = cell(c.next).unwrap_or(row.current);
                    row.probable = (c.probable != NO_CELL).then(|| cell(c.probable)).flatten();
                    row.mode = if c.flags & CandidateFlags::AT_GOAL != 0 {
                        AgentMode::Finished
                    } else if c.flags & (CandidateFlags::STANDING | CandidateFlags::NO_PATH) != 0 {
                        AgentMode::Standing
                    } else {
                        AgentMode::Active
                    };
                    self.flags[i] = c.flags;
                }
                None => {
                    row.probable = None;
                    row.mode = AgentMode::Standing;
                    self.flags[i] = 0;
                }
            }
            row.priority = self.priorities[i];
        }
    }

    /// Resolves the rows by the run's rules into `outcomes`; returns whether the rules
    /// replan (only the dissertation's do).
    fn resolve(&mut self, tick: &mut dyn FnMut()) -> bool {
        match &mut self.round {
            Round::Dissertation(r) => {
                r.resolve(&self.rows, &mut self.outcomes);
                true
            }
            Round::Pibt(p) => {
                p.resolve(&self.rows, &mut self.outcomes);
                false
            }
            Round::Lacam(l) => {
                l.resolve_with(&self.rows, &mut self.outcomes, tick);
                false
            }
        }
    }

    /// Agent `i`'s answer: its outcome as a decision, or a waypoint when it is stuck or has
    /// waited too long (`replanning` rules only); `None` when it asked for nothing, is not
    /// stuck and was not moved.
    fn answer(&mut self, round: u64, i: usize, replanning: bool) -> Option<Decision> {
        let row = self.rows[i];
        let o = self.outcomes[i];
        let stuck = replanning
            && self.flags[i] & CandidateFlags::LOCAL_EXTREMUM != 0
            && row.mode == AgentMode::Active
            && row.is_at_rest();
        if row.probable.is_none() && !stuck && !o.accepted() {
            return None;
        }
        let mut d = o.decision(i as u32, &self.grid);
        if row.probable.is_some() {
            if o.accepted() {
                self.waiting[i] = 0;
            } else {
                self.waiting[i] += 1;
                // The contested cell travels with a refusal: an agent blocked by a standing
                // one learns it as an obstacle.
                d.cell = o
                    .cell
                    .and_then(|c| self.grid.checked_index(c))
                    .map_or(NO_CELL, |c| c as u32);
            }
        }
        if replanning && (stuck || self.waiting[i] >= self.replan_after) {
            if let Some(waypoint) = self.replan(round, i) {
                self.waiting[i] = 0;
                return Some(Decision {
                    agent: i as u32,
                    verdict: Verdict::Replan as u8,
                    waypoint,
                    ..Decision::default()
                });
            }
        }
        Some(d)
    }

    /// Plans agent `i` around the others; records the replan and returns the waypoint.
    fn replan(&mut self, round: u64, i: usize) -> Option<u32> {
        let start = self.rows[i].current;
        let goal = self.goals[i];
        if start == goal {
            return None;
        }
        let mut result = None;
        for only_stable in [false, true] {
            self.scratch.clone_from(&self.grid);
            for (j, r) in self.rows.iter().enumerate() {
                if j == i || (only_stable && r.mode == AgentMode::Active) {
                    continue;
                }
                for c in [r.current, r.next] {
                    if c != start && c != goal {
                        self.scratch.set_blocked(c, true);
                    }
                }
            }
            if let Ok(Some(path)) = self.lazy.plan(&self.scratch, start, goal) {
                let first = path.cells.get(1).copied().unwrap_or(goal);
                if first != goal {
                    result = Some(("lazy-theta", path.cells, first));
                    break;
                }
                if let Ok(Some(p)) = self.astar.plan(&self.scratch, start, goal) {
                    let k = FALLBACK_STEPS.min(p.cells.len() - 1);
                    let wp = p.cells[k];
                    result = Some(("astar", p.cells[..=k].to_vec(), wp));
                    break;
                }
            }
        }
        let (planner, cells, wp) = result?;
        let idx = |c: &Cell| self.grid.index(*c) as u32;
        self.replans.push(ReplanRecord {
            round,
            agent: i as u32,
            planner: planner.to_string(),
            found: true,
            waypoints: cells.iter().map(idx).collect(),
        });
        Some(idx(&wp))
    }

    /// Agents whose last candidate said they stand on their goal.
    pub fn at_goal(&self) -> u32 {
        self.flags
            .iter()
            .filter(|f| *f & CandidateFlags::AT_GOAL != 0)
            .count() as u32
    }

    /// Whether agent `i`'s last candidate said it stands on its goal.
    pub fn agent_at_goal(&self, i: usize) -> bool {
        self.flags
            .get(i)
            .is_some_and(|f| f & CandidateFlags::AT_GOAL != 0)
    }

    /// The tally of every decision made (and replayed) so far.
    pub fn tally(&self) -> &Tally {
        &self.tally
    }

    /// Takes `tally` as that of every decision so far (a replica that starts from a snapshot),
    /// and each row as standing on the cell of its agent's last accepted move: a snapshot
    /// keeps no other cell, so one of a robot stopped half-way is not held (only the log's
    /// rounds, [`Arbiter::replay`], give both).
    pub fn restore_tally(&mut self, tally: Tally) {
        for (row, &c) in self.rows.iter_mut().zip(tally.cells()) {
            if let Some(cell) = self.grid.cell_at(c as usize) {
                (row.current, row.next) = (cell, cell);
            }
        }
        self.tally = tally;
    }

    /// Adds a logged round's decisions to the tally and the rows, as if this arbiter had made
    /// them (after a coordinator restart). The log has no candidates, so a row is what the
    /// decisions say: an accept moves it on (`current <- next <- cell`: the robot may be
    /// anywhere between the two, so both are held), any other decision answered a request,
    /// which an agent makes only at rest (`current <- next`). An agent silent after the
    /// restart (down with the coordinator) thus holds the cells it was committed to, not its
    /// start.
    pub fn replay(&mut self, round: &RoundRecord) {
        self.tally.fold_round(round);
        for d in &round.decisions {
            let Some(row) = self.rows.get_mut(d.agent as usize) else {
                continue;
            };
            row.current = row.next;
            if d.verdict == Verdict::Accept as u8 {
                row.next = self.grid.cell_at(d.cell as usize).unwrap_or(row.next);
            }
        }
    }
}

mod tasks;
#[cfg(test)]
mod tests;
mod world;
