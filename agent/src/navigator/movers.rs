//! Movers (a person, a forklift: `[[events]] mover`) as the agent sees them: transient
//! obstacles, kept apart from what changed in the map.
//!
//! The view marks the cells a mover holds or is about to enter (`moving`). The agent keeps
//! only the newest view's, and never learns them into its grid: a mover is not a map change,
//! so it neither repairs the neural map nor counts among the cells that closed or opened
//! (`sense.rs`). What it does with them:
//!
//! - **Propose**: at rest it never asks for a moving cell. A neural-map climb treats the
//!   directions into one as refused (the step down of a yielding robot is then allowed: it
//!   sidesteps, and a mover waiting for it can pass); a route follower asks for nothing.
//! - **Set off**: the coordinator may have committed (or, under PIBT, pushed) the robot to a
//!   cell marked since; the robot does not set off into it while it is marked
//!   ([`Navigator::waits_for_mover`]). Once under way it drives on: the cell ahead is then
//!   claimed, and a mover that yields waits for it (the sim's rule, `sim/src/world/changes.rs`).
//!
//! Why the cell a mover is about to enter too: a robot sets off on the view of the period
//! before, and in that period a mover may have stepped into the cell. Marking the cell
//! beyond the one it enters covers that period and more (a mover walks a cell in far more
//! than a control period).

use hnav_runtime::grid::{Cell, Direction};
use hnav_runtime::msg::View;

use super::Navigator;

/// How far from its cell's centre a robot counts as not yet set off, in cells: beyond the
/// arrival tolerance (0.05 cell), short of the 0.275 cell at which a robot of the default
/// body (0.36 cell radius) would touch a mover at the next cell's centre.
pub const SET_OFF_CELLS: f64 = 0.15;

impl Navigator {
    /// Takes the cells `view` marks moving, in place of the last view's.
    pub(super) fn note_movers(&mut self, view: &View) {
        self.movers.clear();
        self.movers
            .extend(view.moving_cells().map(|(x, y)| Cell::new(x, y)));
    }

    /// Whether the newest view marks cell `c` moving.
    pub fn mover_in(&self, c: Cell) -> bool {
        self.movers.contains(&c)
    }

    /// The directions from the robot's cell into a moving cell (bit `d` = direction `d`).
    pub(super) fn mover_directions(&self) -> u8 {
        if self.movers.is_empty() {
            return 0;
        }
        Direction::ALL
            .iter()
            .filter(|&&d| self.grid.step(self.current, d).is_some_and(|c| self.mover_in(c)))
            .fold(0, |mask, d| mask | 1 << d.index())
    }

    /// Whether the robot, committed to `next` and `from_centre` cells from its cell's centre,
    /// must not set off (or go on) now: a mover holds `next` or is about to enter it, and
    /// the robot has not set off yet.
    pub fn waits_for_mover(&self, from_centre: f64) -> bool {
        self.is_moving() && from_centre < SET_OFF_CELLS && self.mover_in(self.next)
    }
}
