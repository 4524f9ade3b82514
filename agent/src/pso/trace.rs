//! The swarm's trace ("след"): the cells its particles stood on, as a graph the robot can
//! follow, and the checks that find its gaps (notes §4.1, §5: a run that reaches the goal
//! with a broken trace is a failure).

use hnav_runtime::grid::{octile_shortest_path, Cell, CornerCutting, Grid};

use super::field::chebyshev;
use super::swarm::Particle;

/// Whether a trajectory has a gap: a step of more than one cell along a coordinate (Fig. 1
/// (a)). A step through a wall (Fig. 1 (b)) is such a jump too, since a particle only ever
/// lands on free cells, so one test finds both.
pub fn has_step_gap(trajectory: &[[i64; 2]]) -> bool {
    trajectory.windows(2).any(|w| chebyshev(w[0], w[1]) > 1)
}

/// The shortest route from `start` to `goal` through the cells the particles visited (and
/// `start`), 8-connected under `rule` on the true walls; `None` if the trace does not connect
/// them. This is "the swarm's best trace" the robot follows: loops and dead branches of the
/// particles' wanderings are dropped.
pub fn route_through(
    grid: &Grid,
    particles: &[Particle],
    start: Cell,
    goal: Cell,
    rule: CornerCutting,
) -> Option<Vec<Cell>> {
    let mut blocked = vec![true; grid.len()];
    let mut open = |c: Cell| {
        if !grid.is_blocked(c) {
            blocked[grid.index(c)] = false;
        }
    };
    open(start);
    for p in particles {
        for &q in &p.trajectory {
            if let Some(c) = grid.cell_checked(q[0], q[1]) {
                open(c);
            }
        }
    }
    let trace = Grid::from_blocked(grid.width(), grid.height(), &blocked).ok()?;
    octile_shortest_path(&trace, start, goal, rule).map(|(_, cells)| cells)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jumps_are_gaps_and_unit_steps_are_not() {
        let g = Grid::from_rows(&["....", ".@..", "...."]).unwrap();
        assert!(!has_step_gap(&[[0, 0], [1, 0], [2, 1], [2, 2], [2, 2]]));
        assert!(has_step_gap(&[[0, 0], [2, 0]]), "a two-cell jump");
        let route = route_through(
            &g,
            &[],
            Cell::new(0, 0),
            Cell::new(0, 0),
            CornerCutting::Allowed,
        );
        assert_eq!(route, Some(vec![Cell::new(0, 0)]));
        assert!(route_through(
            &g,
            &[],
            Cell::new(0, 0),
            Cell::new(3, 2),
            CornerCutting::Allowed
        )
        .is_none());
    }
}
