//! Unit tests of the navigator: the climb's round logic and the route follower.

use super::*;
use crate::neural_map::ActivationField;

fn nav(grid: &Grid, start: Cell, goal: Cell) -> Navigator {
    let task = Task {
        index: 0,
        goal,
        priority: 1.0,
        speed: 1.0,
    };
    Navigator::new(
        grid,
        CornerCutting::Forbidden,
        task,
        (start, start, goal),
        Guidance::NeuralMap,
    )
    .unwrap()
}

fn accept(n: &Navigator, c: &Candidate) -> Decision {
    Decision {
        agent: n.task().index,
        verdict: Verdict::Accept as u8,
        cell: c.probable,
        ..Decision::default()
    }
}

/// The coordinator moves the agent to `to` out of another's way (PIBT).
fn pushed(grid: &Grid, to: Cell) -> Decision {
    Decision {
        verdict: Verdict::Accept as u8,
        kind: ConflictKind::Pushed as u8,
        cell: grid.index(to) as u32,
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
    let learned = grid.cell_at(c.probable as usize).unwrap();
    assert!(n.map().unwrap().is_blocked(learned));
    assert!(n.grid().is_blocked(learned));
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
        assert!(n.apply(&pushed(&grid, to)).unwrap().accepted);
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

fn follower(
    grid: &Grid,
    start: Cell,
    goal: Cell,
    planner: Box<dyn RoutePlanner + Send>,
) -> Navigator {
    let task = Task {
        index: 0,
        goal,
        priority: 1.0,
        speed: 1.0,
    };
    let rule = CornerCutting::Forbidden;
    Navigator::new(
        grid,
        rule,
        task,
        (start, start, goal),
        Guidance::Route(planner),
    )
    .unwrap()
}

fn ga() -> Box<dyn RoutePlanner + Send> {
    Box::new(crate::ga_fuzzy::GaPlanner::new(crate::ga_fuzzy::GaOptions::default()).unwrap())
}

fn pso(seed: u64) -> Box<dyn RoutePlanner + Send> {
    let options = crate::pso::PsoOptions::default();
    Box::new(crate::pso::PsoPlanner::new(options, CornerCutting::Forbidden, seed).unwrap())
}

/// Answers from a script, then "no route".
struct Scripted(Vec<Option<Vec<Cell>>>);

impl RoutePlanner for Scripted {
    fn name(&self) -> &'static str {
        "scripted"
    }
    fn route(&mut self, _: &Grid, _: Cell, _: Cell) -> Result<Option<Vec<Cell>>, Error> {
        Ok(if self.0.is_empty() {
            None
        } else {
            self.0.remove(0)
        })
    }
}

/// Accepts every candidate until the goal; returns the cells visited after the start.
fn walk(n: &mut Navigator, limit: u64) -> Vec<Cell> {
    let mut visited = Vec::new();
    let mut round = 0;
    while !n.at_goal() {
        let c = n.candidate(round);
        assert_ne!(
            c.probable,
            NO_CELL,
            "stuck at {:?} (flags {:#x})",
            n.current(),
            c.flags
        );
        assert!(n.apply(&accept(n, &c)).unwrap().accepted);
        n.arrived().unwrap();
        visited.push(n.current());
        round += 1;
        assert!(round <= limit, "no goal in {limit} rounds");
    }
    visited
}

#[test]
fn route_followers_walk_their_planners_routes_to_the_goal() {
    let grid = Grid::from_rows(&["........", ".@@@@@..", "........", "........"]).unwrap();
    let (start, goal) = (Cell::new(0, 0), Cell::new(7, 3));
    for planner in [ga(), pso(3)] {
        let name = planner.name();
        let mut n = follower(&grid, start, goal, planner);
        assert_eq!(n.planner(), name);
        assert!(n.map().is_none());
        let route = n.route().unwrap().to_vec();
        assert_eq!(
            (route.first(), route.last()),
            (Some(&start), Some(&goal)),
            "{name}"
        );
        assert_eq!(n.snapshot_kind(), ActivationKind::Route);
        let mut values = vec![0.0; grid.len()];
        n.write_snapshot(&mut values).unwrap();
        assert_eq!(values[grid.index(goal)], 1.0, "{name}");
        assert_eq!(
            values.iter().filter(|v| **v > 0.0).count(),
            route.len(),
            "{name}"
        );
        assert_eq!(walk(&mut n, 100), route[1..], "{name} follows its route");
    }
}

#[test]
fn a_standing_robot_on_the_route_is_routed_around_and_a_waypoint_reroutes() {
    let grid = Grid::new(8, 3).unwrap();
    let (start, goal) = (Cell::new(0, 1), Cell::new(7, 1));
    let mut n = follower(&grid, start, goal, ga());
    let c = n.candidate(1);
    let blocked = grid.cell_at(c.probable as usize).unwrap();
    let applied = n
        .apply(&Decision {
            verdict: Verdict::Block as u8,
            kind: ConflictKind::StableCell as u8,
            cell: c.probable,
            ..Decision::default()
        })
        .unwrap();
    assert!(applied.map_rebuilt);
    assert!(n.grid().is_blocked(blocked));
    assert!(!n.route().unwrap().contains(&blocked), "rerouted around it");
    let wp = Cell::new(3, 0);
    let applied = n
        .apply(&Decision {
            verdict: Verdict::Replan as u8,
            waypoint: grid.index(wp) as u32,
            ..Decision::default()
        })
        .unwrap();
    assert!(applied.map_rebuilt);
    assert_eq!(n.route().unwrap().last(), Some(&wp));
    let visited = walk(&mut n, 100);
    assert!(visited.contains(&wp), "through the waypoint");
    assert!(!visited.contains(&blocked));
}

#[test]
fn a_failed_query_is_an_extremum_and_is_asked_again() {
    let grid = Grid::new(4, 1).unwrap();
    let (start, goal) = (Cell::new(0, 0), Cell::new(3, 0));
    let line: Vec<Cell> = (0..4).map(|x| Cell::new(x, 0)).collect();
    let script = Scripted(vec![None, None, Some(line.clone())]);
    let mut n = follower(&grid, start, goal, Box::new(script));
    assert_eq!(n.route(), Some(&[][..]));
    let c = n.candidate(1);
    assert_eq!(c.probable, NO_CELL);
    assert_ne!(c.flags & CandidateFlags::LOCAL_EXTREMUM, 0);
    assert_eq!(
        c.flags & CandidateFlags::NO_PATH,
        0,
        "a failed query is not a proof"
    );
    assert!(n.take_replanned(), "a query ran");
    let c = n.candidate(2);
    assert_eq!(
        c.probable,
        grid.index(line[1]) as u32,
        "the third query succeeds"
    );
    assert!(n.take_replanned());
    assert!(!n.take_replanned());
}

#[test]
fn a_follower_pushed_off_its_route_replans_from_where_it_is() {
    let grid = Grid::new(6, 3).unwrap();
    let (start, goal) = (Cell::new(0, 1), Cell::new(5, 1));
    let mut n = follower(&grid, start, goal, ga());
    let off = Cell::new(0, 2);
    assert!(!n.route().unwrap().contains(&off));
    n.candidate(1);
    assert!(n.apply(&pushed(&grid, off)).unwrap().accepted);
    n.arrived().unwrap();
    let c = n.candidate(2);
    assert_ne!(c.probable, NO_CELL);
    assert!(n.take_replanned());
    assert_eq!(n.route().unwrap().first(), Some(&off));
    walk(&mut n, 100);
}
