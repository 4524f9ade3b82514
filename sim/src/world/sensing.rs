//! What each robot's range sensor sees (an emulated LiDAR, seed 000 §3.1.1): the cells
//! within `range` of the robot's cell whose centres it sees in a straight line, free or
//! blocked (a wall, a closed cell, a cell a mover's disc covers), as the truth has them now,
//! and of those the cells a mover holds (moving: the cell it stands in, or the two of the leg
//! it walks; `changes.rs`).
//!
//! Line of sight runs from the robot's cell to the cell's, over the cells a Bresenham line
//! crosses: any blocked cell strictly between hides it (the first blocked cell on a line is
//! seen, what is behind it is not). Other robots are not part of the view: the agents learn
//! of each other through the decision round. A view is a function of the world's state
//! alone, so a lockstep run's views are as reproducible as its truth.

use hnav_runtime::grid::Cell;
use hnav_runtime::msg::{View, VIEW_EDGE};

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
        let range = range.min((VIEW_EDGE as u32 - 1) / 2);
        let (w, h) = (i64::from(self.grid.width()), i64::from(self.grid.height()));
        let (cx, cy) = (
            ((p.x / cell).floor() as i64).clamp(0, w - 1),
            ((p.y / cell).floor() as i64).clamp(0, h - 1),
        );
        let r = i64::from(range);
        let (x0, y0) = ((cx - r).max(0), (cy - r).max(0));
        view.sim_time_ns = self.time_ns();
        view.period = period;
        view.agent = agent;
        view.reset(x0 as u32, y0 as u32, 2 * range + 1);
        for y in (cy - r).max(0)..=(cy + r).min(h - 1) {
            for x in (cx - r).max(0)..=(cx + r).min(w - 1) {
                let (dx, dy) = (x - cx, y - cy);
                if dx * dx + dy * dy > r * r || !self.in_sight((cx, cy), (x, y)) {
                    continue;
                }
                view.mark(x as u32, y as u32, self.blocked_now(x, y));
            }
        }
        for c in self.changes.moving_cells() {
            view.mark_moving(c.x, c.y);
        }
    }

    /// Whether no blocked cell lies strictly between `from` and `to` on the Bresenham line.
    fn in_sight(&self, from: (i64, i64), to: (i64, i64)) -> bool {
        let (mut x, mut y) = from;
        let (dx, dy) = ((to.0 - x).abs(), -(to.1 - y).abs());
        let (sx, sy) = ((to.0 - x).signum(), (to.1 - y).signum());
        let mut err = dx + dy;
        loop {
            if (x, y) == to {
                return true;
            }
            if (x, y) != from && self.blocked_now(x, y) {
                return false;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x += sx;
            }
            if e2 <= dx {
                err += dx;
                y += sy;
            }
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
