//! One agent's decision-round logic, free of I/O: its row of the dissertation's
//! `shared_paths` (current, next, probable), its guide toward the goal or the current
//! waypoint, and what it does with each of the coordinator's verdicts.
//!
//! The guide is the agent's planner (`[[agents]] planner`): the dissertation's neural map
//! climbed by the path constructor (`climb.rs`, `"hnav"`), or a route of one of the seeds'
//! route planners followed cell by cell (`follow.rs`, `"pso"`, `"ga-fuzzy"`). The rules below
//! are the neural map's; a route follower keeps the row, the verdicts and the waypoints the
//! same way, asks for its next route cell (again after a refusal), replans the route when a
//! learned obstacle cuts it, when it is pushed off it or when the target changes, and reports
//! a failed route query as a local extremum.
//!
//! - **Candidate.** At rest (current == next) and not at the goal, the agent climbs its map
//!   one step from `current` with the directions the coordinator refused last round masked
//!   out; while driving to `next` it asks for nothing (the coordinator still hears from it:
//!   every live agent sends one candidate per round, which doubles as its heartbeat).
//! - **Accept**: `next <- cell`; the wheel controller drives there and the agent sets
//!   `current <- next` on arrival, which frees the old cell for others. The cell is usually
//!   the probable step; under `[coordinator] rules = "pibt"` it may be another neighbour
//!   ([`ConflictKind::Pushed`], [`ConflictKind::Redirected`]), also from the goal. The agent
//!   then forgets the cells it has left, so the climb starts afresh from the new cell: a
//!   robot pushed off its goal, whose goal is a left (negated) cell, climbs straight back.
//! - **Block**: the refused directions are masked for the next candidate (the dissertation's
//!   `grad_d = -1` "virtual obstacle", §3.3.2). A block by a standing or finished agent (type
//!   d) also makes that cell an obstacle of the map, as the dissertation prescribes, so the
//!   ascent goes around it instead of returning to it.
//! - **Hold**: wait and ask again.
//! - **Replan**: the coordinator's global planner answered with a waypoint; the map is rebuilt
//!   toward it, and toward the goal again once it is reached (hybrid mode).
//! - **Task** (lifelong runs, `[tasks]`): the waypoint is the agent's next goal. The robots it
//!   learned as obstacles are forgotten (they have moved on) and the map is rebuilt toward it.
//!
//! A mover (`[[events]] mover`, seen with `[sensing]`) is a transient obstacle, never a map
//! change: the agent does not ask for a cell a mover holds or one next to it, nor set off
//! into a held one (`movers.rs`).
//!
//! A step that does not climb (every neighbour lower, e.g. the visited cells the path
//! constructor negates) is a local extremum: the agent says so in its candidate and stands,
//! and the coordinator replans it. Right after a block, a step down is allowed: that is the
//! sidestep of a yielding robot.

mod climb;
mod follow;
mod movers;
mod sense;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_movers;

use hnav_runtime::grid::{reachable_from, Cell, CornerCutting, Direction, Grid};
use hnav_runtime::msg::{
    ActivationKind, Candidate, CandidateFlags, ConflictKind, Decision, Verdict, NO_CELL,
};

use crate::error::Error;
use crate::neural_map::NeuralMap;
use crate::route::RoutePlanner;
use climb::Climb;
use follow::Follow;
pub use movers::SET_OFF_CELLS;
pub use sense::{Repair, RepairKind, PARTIAL_SWEEPS};

/// What the agent is told at start.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Task {
    /// Agent index.
    pub index: u32,
    /// Goal cell.
    pub goal: Cell,
    /// Conflict priority (larger wins).
    pub priority: f64,
    /// Nominal speed in cells/s.
    pub speed: f64,
}

/// What a commit changed for this agent.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct Applied {
    /// A move was accepted (`next` changed).
    pub accepted: bool,
    /// The map (or route) was rebuilt: a new snapshot is due.
    pub map_rebuilt: bool,
}

/// How an agent finds its steps: the `[[agents]] planner` of its scenario, built.
pub enum Guidance {
    /// The dissertation's neural map and path constructor.
    NeuralMap,
    /// A route planner's routes, followed cell by cell.
    Route(Box<dyn RoutePlanner + Send>),
}

/// A guide's answer for one candidate.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Proposal {
    /// Ask for this neighbour.
    Step(Cell),
    /// No step leads on (a local extremum, a failed route query): stand, and say so.
    Extremum,
    /// Ask for nothing this round.
    Wait,
}

enum Guide {
    Climb(Box<Climb>),
    Follow(Follow),
}

/// The agent's row, guide and target.
pub struct Navigator {
    task: Task,
    grid: Grid,
    corner_cutting: CornerCutting,
    target: Cell,
    guide: Guide,
    current: Cell,
    next: Cell,
    flags: u32,
    /// The goal is not in the robot's connected part of the map (walls only: robots the
    /// agent learns as obstacles move away again, so they never make a goal unreachable).
    unreachable: bool,
    /// The route changed while proposing (a follower off its route): a snapshot is due.
    replanned: bool,
    /// The cells learned as obstacles (standing robots), forgotten at a new task.
    learned: Vec<Cell>,
    /// The cells the newest view marks moving (`movers.rs`): kept out of, never learned.
    movers: movers::Movers,
}

impl Navigator {
    /// An agent at rest in `current` (its start, or where a restarted agent's robot stands)
    /// with `next` committed, heading for `target` (the goal, or a waypoint on the way),
    /// guided as `guidance` says.
    pub fn new(
        grid: &Grid,
        corner_cutting: CornerCutting,
        task: Task,
        (current, next, target): (Cell, Cell, Cell),
        guidance: Guidance,
    ) -> Result<Self, Error> {
        let unreachable = grid.contains(task.goal)
            && !reachable_from(grid, current, corner_cutting)[grid.index(task.goal)];
        let guide = match guidance {
            Guidance::NeuralMap => {
                Guide::Climb(Box::new(Climb::new(grid, corner_cutting, next, target)?))
            }
            Guidance::Route(p) => Guide::Follow(Follow::new(p, corner_cutting, grid, next, target)),
        };
        Ok(Navigator {
            task,
            grid: grid.clone(),
            corner_cutting,
            target,
            guide,
            current,
            next,
            flags: 0,
            unreachable,
            replanned: false,
            learned: Vec::new(),
            movers: movers::Movers::default(),
        })
    }

    /// The agent's task.
    pub fn task(&self) -> &Task {
        &self.task
    }

    /// The cell the robot is in.
    pub fn current(&self) -> Cell {
        self.current
    }

    /// The committed cell the robot drives to (== current at rest).
    pub fn next(&self) -> Cell {
        self.next
    }

    /// The guide's target: the goal, or the coordinator's waypoint.
    pub fn target(&self) -> Cell {
        self.target
    }

    /// The grid as the agent knows it: the walls and the standing robots it has learned.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// The planner's name: `"hnav"`, or the route planner's (`"pso"`, `"ga-fuzzy"`).
    pub fn planner(&self) -> &'static str {
        match &self.guide {
            Guide::Climb(_) => "hnav",
            Guide::Follow(f) => f.name(),
        }
    }

    /// The neural map, for an agent guided by one.
    pub fn map(&self) -> Option<&NeuralMap> {
        match &self.guide {
            Guide::Climb(c) => Some(c.map()),
            Guide::Follow(_) => None,
        }
    }

    /// The remaining route, the robot's cell first, for a route follower (empty while it has
    /// none); `None` for a neural-map agent.
    pub fn route(&self) -> Option<&[Cell]> {
        match &self.guide {
            Guide::Climb(_) => None,
            Guide::Follow(f) => Some(f.remaining()),
        }
    }

    /// Whether the goal cannot be reached from the robot's cell through free cells: the
    /// agent then reports [`CandidateFlags::NO_PATH`] and stands still.
    pub fn goal_unreachable(&self) -> bool {
        self.unreachable
    }

    /// The snapshot header's `iterations`: the map's sweeps, or the route's length.
    pub fn snapshot_iterations(&self) -> u32 {
        match &self.guide {
            Guide::Climb(c) => c.iterations(),
            Guide::Follow(f) => f.remaining().len() as u32,
        }
    }

    /// The snapshot header's `activation`.
    pub fn snapshot_kind(&self) -> ActivationKind {
        match &self.guide {
            Guide::Climb(c) => c.kind(),
            Guide::Follow(_) => ActivationKind::Route,
        }
    }

    /// Writes the snapshot's values (one per cell) into `out`, which reads 0 everywhere.
    pub fn write_snapshot(&self, out: &mut [f32]) -> Result<(), Error> {
        match &self.guide {
            Guide::Climb(c) => c.write(out),
            Guide::Follow(f) => {
                f.write(&self.grid, out);
                Ok(())
            }
        }
    }

    /// Whether the guide changed since the last call (a follower replanned while proposing).
    pub fn take_replanned(&mut self) -> bool {
        std::mem::take(&mut self.replanned)
    }

    /// Whether the robot is driving to `next`.
    pub fn is_moving(&self) -> bool {
        self.current != self.next
    }

    /// Whether the robot stands on its goal.
    pub fn at_goal(&self) -> bool {
        !self.is_moving() && self.current == self.task.goal
    }

    /// Marks the next candidate as the first after a restart.
    pub fn mark_restarted(&mut self) {
        self.flags |= CandidateFlags::RESTARTED;
    }

    /// The robot has reached the centre of `next`: it has left `current`, which is freed.
    /// Returns whether the map was rebuilt (a waypoint was reached and the goal is the
    /// target again).
    pub fn arrived(&mut self) -> Result<bool, Error> {
        self.current = self.next;
        if self.current == self.target && self.target != self.task.goal {
            self.retarget(self.task.goal)?;
            return Ok(true);
        }
        Ok(false)
    }

    /// This round's candidate.
    pub fn candidate(&mut self, round: u64) -> Candidate {
        let mut flags = std::mem::take(&mut self.flags);
        let mut probable = NO_CELL;
        if self.at_goal() {
            flags |= CandidateFlags::AT_GOAL | CandidateFlags::STANDING;
        } else if self.unreachable || self.guide_sees_no_path() {
            flags |= CandidateFlags::NO_PATH | CandidateFlags::STANDING;
        } else if !self.is_moving() {
            let proposal = self.propose_clear_of_movers();
            match proposal {
                Proposal::Step(c) => probable = self.grid.index(c) as u32,
                Proposal::Extremum => flags |= CandidateFlags::LOCAL_EXTREMUM,
                Proposal::Wait => {}
            }
        }
        Candidate {
            round,
            agent: self.task.index,
            current: self.grid.index(self.current) as u32,
            next: self.grid.index(self.next) as u32,
            probable,
            priority: self.task.priority as f32,
            speed: self.task.speed as f32,
            flags,
            reserved: 0,
        }
    }

    /// The guide's proposal from the robot's cell (movers aside).
    fn guide_propose(&mut self) -> Proposal {
        match &mut self.guide {
            Guide::Climb(c) => c.propose(&self.grid, self.current),
            Guide::Follow(f) => {
                let (p, replanned) = f.propose(&self.grid, self.current, self.target);
                self.replanned |= replanned;
                p
            }
        }
    }

    /// Whether the guide itself says the target cannot be reached (a neural map whose wave
    /// never got to the robot); a route follower never does: a failed query is an extremum.
    fn guide_sees_no_path(&self) -> bool {
        match &self.guide {
            Guide::Climb(c) => c.no_path(),
            Guide::Follow(_) => false,
        }
    }

    /// Applies this agent's decision of a commit.
    pub fn apply(&mut self, d: &Decision) -> Result<Applied, Error> {
        let mut applied = Applied::default();
        let cell = (d.cell != NO_CELL)
            .then(|| self.grid.cell_at(d.cell as usize))
            .flatten();
        match Verdict::from_u8(d.verdict) {
            Some(Verdict::Accept) => {
                let dir = cell.and_then(|c| Direction::between(self.current, c));
                if let (Some(c), Some(dir), false) = (cell, dir, self.is_moving()) {
                    let chosen = matches!(
                        ConflictKind::from_u8(d.kind),
                        Some(ConflictKind::Pushed | ConflictKind::Redirected)
                    );
                    if let Guide::Climb(climb) = &mut self.guide {
                        climb.accepted(dir, chosen);
                    }
                    self.next = c;
                    applied.accepted = true;
                }
            }
            Some(Verdict::Block) => {
                let stable = ConflictKind::from_u8(d.kind) == Some(ConflictKind::StableCell);
                if let Guide::Climb(climb) = &mut self.guide {
                    climb.refused(d.refused);
                }
                if let (true, Some(c)) = (stable, cell) {
                    applied.map_rebuilt = self.learn_obstacle(c)?;
                }
            }
            Some(Verdict::Replan) => {
                let wp = (d.waypoint != NO_CELL)
                    .then(|| self.grid.cell_at(d.waypoint as usize))
                    .flatten();
                if let Some(wp) = wp {
                    self.retarget(wp)?;
                    applied.map_rebuilt = true;
                }
            }
            Some(Verdict::Task) => {
                let goal = (d.waypoint != NO_CELL)
                    .then(|| self.grid.cell_at(d.waypoint as usize))
                    .flatten();
                if let Some(goal) = goal.filter(|&g| g != self.task.goal) {
                    self.new_goal(goal)?;
                    applied.map_rebuilt = true;
                }
            }
            Some(Verdict::Hold) | None => {}
        }
        Ok(applied)
    }

    /// A standing or finished robot blocks `cell` (type d): it becomes an obstacle of the
    /// agent's grid, as the dissertation prescribes, so the guide goes around it instead of
    /// returning to it. Returns whether the guide changed.
    fn learn_obstacle(&mut self, c: Cell) -> Result<bool, Error> {
        if c == self.target || self.grid.is_blocked(c) {
            return Ok(false);
        }
        self.grid.set_blocked(c, true);
        self.learned.push(c);
        match &mut self.guide {
            Guide::Climb(climb) => climb.learn_obstacle(c, self.target)?,
            Guide::Follow(f) if f.crosses(c) => {
                f.plan(&self.grid, self.next, self.target);
            }
            Guide::Follow(_) => return Ok(false),
        }
        Ok(true)
    }

    /// A lifelong run's next task: `goal` is the goal from now on. The robots the agent
    /// learned as obstacles on the way to the last one have moved on since: its grid is the
    /// walls again, and the guide is rebuilt toward the new goal.
    fn new_goal(&mut self, goal: Cell) -> Result<(), Error> {
        self.task.goal = goal;
        self.unreachable = false;
        let walls: Vec<Cell> = self.learned.drain(..).collect();
        for c in walls {
            self.grid.set_blocked(c, false);
        }
        self.retarget(goal)
    }

    /// Points the guide at `target` from `next`: a new map and climb, or a new route.
    fn retarget(&mut self, target: Cell) -> Result<(), Error> {
        self.target = target;
        match &mut self.guide {
            Guide::Climb(c) => c.retarget(&self.grid, self.next, target)?,
            Guide::Follow(f) => {
                f.plan(&self.grid, self.next, target);
            }
        }
        Ok(())
    }

    /// The corner rule the agent plans with.
    pub fn corner_cutting(&self) -> CornerCutting {
        self.corner_cutting
    }
}
