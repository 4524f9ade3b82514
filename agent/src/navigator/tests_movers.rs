//! Unit tests of the agent's rules for movers (`movers.rs`): never a map change, no step
//! near one, a step aside only for one standing next to the robot, no setting off into one.

use super::*;
use hnav_runtime::msg::View;
use hnav_runtime::scenario::RepairRule;

/// An 8 x 3 free corridor, the robot at (1, 1) heading for (6, 1).
fn corridor() -> (Grid, Navigator) {
    let grid = Grid::new(8, 3).unwrap();
    let task = Task {
        index: 0,
        goal: Cell::new(6, 1),
        priority: 1.0,
        speed: 1.0,
    };
    let start = Cell::new(1, 1);
    let n = Navigator::new(
        &grid,
        CornerCutting::Forbidden,
        task,
        (start, start, task.goal),
        Guidance::NeuralMap,
    )
    .unwrap();
    (grid, n)
}

/// A view of the whole corridor with a mover holding `held` (seen blocked and moving).
fn view(held: &[(u32, u32)]) -> View {
    let mut v = View::default();
    v.reset(0, 0, 8);
    for y in 0..3 {
        for x in 0..8 {
            v.mark(x, y, held.contains(&(x, y)));
        }
    }
    for &(x, y) in held {
        v.mark_moving(x, y);
    }
    v
}

fn probable(grid: &Grid, n: &mut Navigator) -> Option<Cell> {
    let c = n.candidate(1);
    (c.probable != NO_CELL).then(|| grid.cell_at(c.probable as usize).unwrap())
}

#[test]
fn a_mover_is_no_map_change_and_the_robot_waits_for_it_to_pass() {
    let (grid, mut n) = corridor();
    // Walking the leg (3, 1) -> (4, 1): no repair, nothing learned.
    assert_eq!(
        n.sense(&view(&[(3, 1), (4, 1)]), RepairRule::Auto).unwrap(),
        None
    );
    assert!(!n.grid().is_blocked(Cell::new(3, 1)));
    // (2, 1), the step up the map, is next to it: the robot asks for nothing.
    assert_eq!(probable(&grid, &mut n), None);
    // Gone: the step again.
    assert_eq!(n.sense(&view(&[]), RepairRule::Auto).unwrap(), None);
    assert_eq!(probable(&grid, &mut n), Some(Cell::new(2, 1)));
}

#[test]
fn a_mover_standing_next_to_the_robot_has_it_step_aside() {
    let (grid, mut n) = corridor();
    n.sense(&view(&[(2, 1)]), RepairRule::Auto).unwrap();
    let aside = probable(&grid, &mut n).expect("a step aside");
    let near = [(2, 1), (3, 1), (2, 0), (2, 2)].map(|(x, y)| Cell::new(x, y));
    assert!(!near.contains(&aside), "{aside:?}");
}

#[test]
fn a_robot_committed_to_a_cell_a_mover_holds_does_not_set_off() {
    let (_, mut n) = corridor();
    let c = n.candidate(1);
    n.apply(&accept_step(&n, &c)).unwrap();
    assert_eq!(n.next(), Cell::new(2, 1));
    assert!(!n.waits_for_mover(0.0));
    n.sense(&view(&[(2, 1), (3, 1)]), RepairRule::Auto).unwrap();
    assert!(n.waits_for_mover(0.0), "not set off: it waits");
    assert!(!n.waits_for_mover(SET_OFF_CELLS), "under way: it drives on");
    n.sense(&view(&[(3, 1)]), RepairRule::Auto).unwrap();
    assert!(
        !n.waits_for_mover(0.0),
        "next to a mover it sets off, and claims the cell"
    );
}

fn accept_step(n: &Navigator, c: &Candidate) -> Decision {
    Decision {
        agent: n.task().index,
        verdict: Verdict::Accept as u8,
        cell: c.probable,
        ..Decision::default()
    }
}
