//! One agent's decision-round logic, free of I/O: its row of the dissertation's
//! `shared_paths` (current, next, probable), its neural map toward the goal or the current
//! waypoint, and what it does with each of the coordinator's verdicts.
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
//!
//! A step that does not climb (every neighbour lower, e.g. the visited cells the path
//! constructor negates) is a local extremum: the agent says so in its candidate and stands,
//! and the coordinator replans it. Right after a block, a step down is allowed: that is the
//! sidestep of a yielding robot.

use hnav_runtime::grid::{reachable_from, Cell, CornerCutting, Direction, Grid};
use hnav_runtime::msg::{Candidate, CandidateFlags, ConflictKind, Decision, Verdict, NO_CELL};

use crate::error::Error;
use crate::neural_map::{
    ActivationField, BuildReport, NeuralDynamics, NeuralMap, Outcome, StopRule,
};
use crate::path_constructor::{DirectionMask, PathConstructor, PathOptions, Walker};
use crate::plan::{PlanOptions, PlanStop};

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
    /// The map was rebuilt (a new snapshot is due).
    pub map_rebuilt: bool,
}

/// The agent's row, map and target.
pub struct Navigator {
    task: Task,
    grid: Grid,
    corner_cutting: CornerCutting,
    target: Cell,
    map: NeuralMap,
    report: BuildReport,
    constructor: PathConstructor,
    walker: Walker,
    current: Cell,
    next: Cell,
    mask: DirectionMask,
    flags: u32,
    /// The goal is not in the robot's connected part of the map (walls only: robots the
    /// agent learns as obstacles move away again, so they never make a goal unreachable).
    unreachable: bool,
}

impl Navigator {
    /// An agent at rest in `current` (its start, or where a restarted agent's robot stands)
    /// with `next` committed, heading for `target` (the goal, or a waypoint on the way).
    pub fn new(
        grid: &Grid,
        corner_cutting: CornerCutting,
        task: Task,
        current: Cell,
        next: Cell,
        target: Cell,
    ) -> Result<Self, Error> {
        let options = PlanOptions {
            stop: PlanStop::Full,
            corner_cutting,
            ..PlanOptions::default()
        };
        let unreachable = grid.contains(task.goal)
            && !reachable_from(grid, current, corner_cutting)[grid.index(task.goal)];
        let mut map = NeuralMap::new(grid, options.map_options())?;
        let report = map.build(target, StopRule::FullActivation)?;
        let constructor = PathConstructor::new(PathOptions {
            heading_bonus: true,
            ..PathOptions::default()
        })?;
        Ok(Navigator {
            task,
            grid: grid.clone(),
            corner_cutting,
            target,
            map,
            report,
            constructor,
            walker: Walker::new(grid.width(), grid.height(), next),
            current,
            next,
            mask: DirectionMask::default(),
            flags: 0,
            unreachable,
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

    /// The map's target: the goal, or the coordinator's waypoint.
    pub fn target(&self) -> Cell {
        self.target
    }

    /// The neural map.
    pub fn map(&self) -> &NeuralMap {
        &self.map
    }

    /// Whether the goal cannot be reached from the robot's cell through free cells: the
    /// agent then reports [`CandidateFlags::NO_PATH`] and stands still.
    pub fn goal_unreachable(&self) -> bool {
        self.unreachable
    }

    /// The last build of the map.
    pub fn report(&self) -> &BuildReport {
        &self.report
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
        } else if self.unreachable
            || matches!(
                self.report.outcome,
                Outcome::Unreachable | Outcome::SweepLimit
            )
        {
            flags |= CandidateFlags::NO_PATH | CandidateFlags::STANDING;
        } else if !self.is_moving() {
            let mask = std::mem::take(&mut self.mask);
            let (dir, g) = self.walker.propose(&self.constructor, &self.map, mask);
            match dir {
                Some(d) if g.values[d.index()] > 0.0 || mask.0 != 0 => {
                    if let Some(c) = self.grid.step(self.current, d) {
                        probable = self.grid.index(c) as u32;
                    }
                }
                _ => flags |= CandidateFlags::LOCAL_EXTREMUM,
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
                    self.walker.advance(dir);
                    let chosen = matches!(
                        ConflictKind::from_u8(d.kind),
                        Some(ConflictKind::Pushed | ConflictKind::Redirected)
                    );
                    if chosen {
                        self.walker.forget_visited();
                    }
                    self.next = c;
                    applied.accepted = true;
                }
            }
            Some(Verdict::Block) => {
                self.mask = DirectionMask(self.mask.0 | d.refused);
                let stable = ConflictKind::from_u8(d.kind) == Some(ConflictKind::StableCell);
                if let (true, Some(c)) = (stable, cell) {
                    if c != self.target && !self.map.is_blocked(c) {
                        self.grid.set_blocked(c, true);
                        self.map.add_obstacles(&[c])?;
                        self.report = self.map.build(self.target, StopRule::FullActivation)?;
                        applied.map_rebuilt = true;
                    }
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
            Some(Verdict::Hold) | None => {}
        }
        Ok(applied)
    }

    /// Rebuilds the map toward `target` and forgets the visited cells (a new climb).
    fn retarget(&mut self, target: Cell) -> Result<(), Error> {
        self.target = target;
        self.map = NeuralMap::new(&self.grid, *self.map.options())?;
        self.report = self.map.build(target, StopRule::FullActivation)?;
        self.walker = Walker::new(self.grid.width(), self.grid.height(), self.next);
        self.mask = DirectionMask::default();
        Ok(())
    }

    /// The corner rule the agent plans with.
    pub fn corner_cutting(&self) -> CornerCutting {
        self.corner_cutting
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nav(grid: &Grid, start: Cell, goal: Cell) -> Navigator {
        let task = Task {
            index: 0,
            goal,
            priority: 1.0,
            speed: 1.0,
        };
        Navigator::new(grid, CornerCutting::Forbidden, task, start, start, goal).unwrap()
    }

    fn accept(n: &Navigator, c: &Candidate) -> Decision {
        Decision {
            agent: n.task().index,
            verdict: Verdict::Accept as u8,
            cell: c.probable,
            ..Decision::default()
        }
    }

    #[test]
    fn accepted_steps_walk_to_the_goal() {
        let grid = Grid::new(8, 8).unwrap();
        let mut n = nav(&grid, Cell::new(0, 0), Cell::new(5, 3));
        let mut steps = 0;
        while !n.at_goal() {
            let c = n.candidate(steps);
            assert_ne!(c.probable, NO_CELL, "stuck at {:?}", n.current());
            assert!(n.apply(&accept(&n, &c)).unwrap().accepted);
            assert!(n.is_moving());
            // A moving agent asks for nothing.
            assert_eq!(n.candidate(steps).probable, NO_CELL);
            n.arrived().unwrap();
            steps += 1;
        }
        assert_eq!(steps, 5);
        let c = n.candidate(99);
        assert_eq!(c.probable, NO_CELL);
        assert_ne!(c.flags & CandidateFlags::AT_GOAL, 0);
    }

    #[test]
    fn a_blocked_direction_is_masked_once() {
        let grid = Grid::new(8, 8).unwrap();
        let mut n = nav(&grid, Cell::new(0, 0), Cell::new(7, 0));
        let c = n.candidate(1);
        let first = c.probable;
        let d = Direction::between(n.current(), grid.cell_at(first as usize).unwrap()).unwrap();
        n.apply(&Decision {
            verdict: Verdict::Block as u8,
            refused: 1 << d.index(),
            kind: ConflictKind::Crossing as u8,
            cell: first,
            ..Decision::default()
        })
        .unwrap();
        let second = n.candidate(2).probable;
        assert_ne!(second, NO_CELL);
        assert_ne!(second, first);
        assert_eq!(n.candidate(3).probable, first, "the mask lasts one round");
    }

    #[test]
    fn a_standing_agent_becomes_an_obstacle_and_a_waypoint_retargets() {
        let grid = Grid::new(8, 3).unwrap();
        let mut n = nav(&grid, Cell::new(0, 1), Cell::new(7, 1));
        let c = n.candidate(1);
        let applied = n
            .apply(&Decision {
                verdict: Verdict::Block as u8,
                refused: 1 << Direction::E.index(),
                kind: ConflictKind::StableCell as u8,
                cell: c.probable,
                ..Decision::default()
            })
            .unwrap();
        assert!(applied.map_rebuilt);
        assert!(n
            .map()
            .is_blocked(grid.cell_at(c.probable as usize).unwrap()));
        let wp = grid.index(Cell::new(3, 0)) as u32;
        let applied = n
            .apply(&Decision {
                verdict: Verdict::Replan as u8,
                waypoint: wp,
                ..Decision::default()
            })
            .unwrap();
        assert!(applied.map_rebuilt);
        assert_eq!(n.target(), Cell::new(3, 0));
    }

    #[test]
    fn garbage_decisions_change_nothing() {
        let grid = Grid::new(4, 4).unwrap();
        let mut n = nav(&grid, Cell::new(0, 0), Cell::new(3, 3));
        for d in [
            Decision {
                verdict: 9,
                ..Decision::default()
            },
            Decision {
                verdict: Verdict::Accept as u8,
                cell: 15,
                ..Decision::default()
            },
            Decision {
                verdict: Verdict::Accept as u8,
                cell: u32::MAX - 1,
                ..Decision::default()
            },
            Decision {
                verdict: Verdict::Replan as u8,
                waypoint: 1000,
                ..Decision::default()
            },
        ] {
            assert_eq!(n.apply(&d).unwrap(), Applied::default());
        }
        assert!(!n.is_moving());
    }

    #[test]
    fn an_agent_pushed_off_its_goal_climbs_back() {
        let grid = Grid::new(6, 3).unwrap();
        let goal = Cell::new(3, 1);
        let mut n = nav(&grid, Cell::new(1, 1), goal);
        let mut round = 0;
        while !n.at_goal() {
            let c = n.candidate(round);
            n.apply(&accept(&n, &c)).unwrap();
            n.arrived().unwrap();
            round += 1;
        }
        // Two pushes away from the goal, then the agent climbs back on its own.
        for to in [Cell::new(3, 2), Cell::new(4, 2)] {
            let c = n.candidate(round);
            assert_eq!(c.probable == NO_CELL, n.at_goal(), "asks only off the goal");
            let pushed = Decision {
                verdict: Verdict::Accept as u8,
                kind: ConflictKind::Pushed as u8,
                cell: grid.index(to) as u32,
                ..Decision::default()
            };
            assert!(n.apply(&pushed).unwrap().accepted);
            n.arrived().unwrap();
            assert_eq!(n.current(), to);
            round += 1;
        }
        let mut back = 0;
        while !n.at_goal() {
            let c = n.candidate(round);
            assert_ne!(c.probable, NO_CELL, "stuck at {:?}", n.current());
            assert_eq!(c.flags & CandidateFlags::LOCAL_EXTREMUM, 0);
            n.apply(&accept(&n, &c)).unwrap();
            n.arrived().unwrap();
            round += 1;
            back += 1;
            assert!(back <= 2, "not the shortest way back: at {:?}", n.current());
        }
    }
}
