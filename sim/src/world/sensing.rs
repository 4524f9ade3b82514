//! What each robot's range sensor sees (an emulated LiDAR, seed 000 §3.1.1): the cells
//! within `range` of the robot's cell whose centres it sees in a straight line, free or
//! blocked (a wall, a closed cell, a cell a mover's disc covers), as the truth has them now,
//! and of those the cells a mover holds (moving: the cell it stands in, or the two of the leg
//! it walks; `changes.rs`).
//!
//! Line of sight is [`hnav_runtime::grid::sight`]'s (a Bresenham line: the first blocked
//! cell on it is seen, what is behind it is not), which the operator's tools share. Other robots are not part of the view: the agents learn
//! of each other through the decision round. A view is a function of the world's state
//! alone, so a lockstep run's views are as reproducible as its truth.

use hnav_runtime::grid::sight;
use hnav_runtime::grid::Cell;
use hnav_runtime::msg::View;

use super::World;
use crate::collision::disc_overlaps_cell;

impl World {
    /// Fills `view` with what robot `agent` sees at the end of control period `period`
    /// within `range` cells (at most 15); nothing for an unknown robot.
    pub fn fill_view(&self, agent: u32, period: u64, range: u32, view: &mut View) {
        let Some(p) = self.position(agent) else {
            return;
        };
        let cell = self.model.cell_size_m;
        let (w, h) = (self.grid.width(), self.grid.height());
        let (cx, cy) = (
            ((p.x / cell).floor() as i64).clamp(0, i64::from(w) - 1),
            ((p.y / cell).floor() as i64).clamp(0, i64::from(h) - 1),
        );
        view.sim_time_ns = self.time_ns();
        view.period = period;
        view.agent = agent;
        sight::fill_view(view, (w, h), (cx, cy), range, |x, y| self.blocked_now(x, y));
        for c in self.changes.moving_cells() {
            view.mark_moving(c.x, c.y);
        }
    }

    /// Whether cell (`x`, `y`) of the map is blocked now: a wall, closed, or covered by a
    /// mover's disc.
    fn blocked_now(&self, x: i64, y: i64) -> bool {
        let c = Cell::new(x as u32, y as u32);
        if self.grid.is_blocked(c) {
            return true;
        }
        let (r, cell) = (self.model.body_radius_m, self.model.cell_size_m);
        self.changes
            .movers()
            .any(|(_, at)| disc_overlaps_cell(&at, r, x, y, cell))
    }
}
