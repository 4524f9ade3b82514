//! What the sim measures of each robot for the run summary's criteria: the energy its
//! motors draw (the model of [`hnav_runtime::criteria::energy`], priced every physics step
//! from the wheel speeds the motor model gives) and when its true pose first ended a control
//! period in its goal cell. Kept in the restart checkpoint, written to
//! `DIR/sim-criteria.json` at exit.

use hnav_runtime::criteria::energy::{MotorModel, WheelEnergy};
use hnav_runtime::criteria::{RobotCriteria, SimCriteria};
use hnav_runtime::grid::Cell;
use nalgebra::Point2;

/// Per robot: energy so far, goal cell, first time at it.
#[derive(Debug, Clone)]
pub(crate) struct Meter {
    pub(crate) wheel: WheelEnergy,
    pub(crate) energy_j: Vec<f64>,
    goals: Vec<Option<Cell>>,
    pub(crate) goal_at_ns: Vec<Option<u64>>,
}

impl Meter {
    /// A meter of `robots` robots with wheels of `wheel_radius_m` stepped every `dt_s`; no
    /// goals until [`Meter::set_goals`].
    pub(crate) fn new(robots: usize, wheel_radius_m: f64, dt_s: f64) -> Self {
        Meter {
            wheel: WheelEnergy::new(&MotorModel::S_BOT, wheel_radius_m, dt_s),
            energy_j: vec![0.0; robots],
            goals: vec![None; robots],
            goal_at_ns: vec![None; robots],
        }
    }

    /// The robots' goal cells, in index order.
    pub(crate) fn set_goals(&mut self, goals: impl IntoIterator<Item = Cell>) {
        for (g, c) in self.goals.iter_mut().zip(goals) {
            *g = Some(c);
        }
    }

    /// Notes, at sim time `now_ns`, which robots at `pos` (cells `cell_m` wide) stand in
    /// their goal cells for the first time.
    pub(crate) fn note_goals(&mut self, pos: &[Point2<f64>], cell_m: f64, now_ns: u64) {
        for ((at, goal), p) in self.goal_at_ns.iter_mut().zip(&self.goals).zip(pos) {
            let Some(g) = goal.filter(|_| at.is_none()) else {
                continue;
            };
            if (p.x / cell_m).floor() == f64::from(g.x) && (p.y / cell_m).floor() == f64::from(g.y)
            {
                *at = Some(now_ns);
            }
        }
    }

    /// The figures for the summary.
    pub(crate) fn criteria(&self) -> SimCriteria {
        SimCriteria {
            robots: self
                .energy_j
                .iter()
                .zip(&self.goal_at_ns)
                .map(|(&energy_j, at)| RobotCriteria {
                    energy_j,
                    // Divided, not multiplied by 1e-9 (inexact): 20 880 000 000 ns is 20.88 s, not
                    // 20.880000000000003.
                    goal_at_s: at.map(|ns| ns as f64 / 1e9),
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_robot_is_at_its_goal_from_the_first_period_it_ends_in_the_cell() {
        let mut m = Meter::new(2, 0.02, 1e-3);
        m.set_goals([Cell::new(2, 1), Cell::new(0, 0)]);
        let cell = 0.16;
        // Robot 0 a hair short of cell (2, 1), robot 1 in cell (1, 0).
        let mut pos = [
            Point2::new(2.0 * cell - 1e-6, 1.5 * cell),
            Point2::new(0.2, 0.05),
        ];
        m.note_goals(&pos, cell, 10_000_000);
        assert_eq!(m.goal_at_ns, [None, None]);
        pos[0].x = 2.0 * cell + 1e-6;
        m.note_goals(&pos, cell, 20_000_000);
        // It leaves again: the first arrival stands.
        pos[0].x = 3.5 * cell;
        m.note_goals(&pos, cell, 30_000_000);
        let c = m.criteria();
        assert_eq!(c.robots[0].goal_at_s, Some(0.02));
        assert_eq!(c.robots[1].goal_at_s, None);
        assert_eq!(c.robots[0].energy_j, 0.0);
    }
}
