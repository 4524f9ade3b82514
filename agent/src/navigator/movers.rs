//! Movers (a person, a forklift: `[[events]] mover`) as the agent sees them: transient
//! obstacles, kept apart from what changed in the map.
//!
//! The view marks the cells a mover holds (`moving`: the cell it stands in, or the two of the
//! leg it walks). The agent keeps only the newest view's, and never learns them into its
//! grid: a mover is not a map change, so it neither repairs the neural map nor counts among
//! the cells that closed or opened (`sense.rs`). What it does with them:
//!
//! - **Propose**: at rest it never asks for a cell a mover holds or one next to it (along a
//!   row or a column, where a mover goes next), nor for a diagonal past one (the diagonal
//!   passes 0.71 cell from the corner cells' centres, less than two default body radii,
//!   0.725 cell). When its step is one of those it asks for nothing and waits for the mover
//!   to pass, unless a mover stands still next to it (holds one cell, not two: it waits at a
//!   cell centre, likely for this robot, in its way): then a neural-map climb treats those
//!   directions as refused, and the step down of a yielding robot is allowed: it sidesteps
//!   and the mover can pass. Stepping aside for every passing mover instead sends a climbing
//!   robot wandering (the cells it left are negated), far from its goal.
//! - **Set off**: the coordinator may have committed (or, under PIBT, pushed) the robot to a
//!   cell a mover entered since; the robot does not set off on that move while a mover holds
//!   a cell of it ([`Navigator::waits_for_mover`]). Next to a mover it does set off: in
//!   motion it claims the cell it enters, and a mover that yields waits for it (the sim's
//!   rule, `sim/src/world/changes.rs`). Waiting there instead would let the mover step in
//!   and, if the robot's cell is the mover's next, leave both waiting for each other.
//!
//! Why the cells next to a mover too: a robot sets off on the view of the period before,
//! and in that period a mover standing at a cell centre may have set off into the next cell.
//! A mover walks a cell in far more than a control period, so one cell of margin covers it.

use hnav_runtime::grid::{Cell, Direction};
use hnav_runtime::msg::View;

use super::{Guide, Navigator, Proposal};

/// How far from its cell's centre a robot counts as not yet set off, in cells: beyond the
/// arrival tolerance (0.05 cell), short of the 0.275 cell at which a robot of the default
/// body (0.36 cell radius) would touch a mover at the next cell's centre.
pub const SET_OFF_CELLS: f64 = 0.15;

/// The movers as the agent knows them.
#[derive(Debug, Default)]
pub(super) struct Movers {
    /// The cells the newest view marks moving.
    held: Vec<Cell>,
    /// The last proposal waited for a mover.
    waiting: bool,
}

/// Which cells a move must keep clear of.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Margin {
    /// The cells movers hold.
    Held,
    /// Those and the cells next to them.
    Near,
}

impl Navigator {
    /// Takes the cells `view` marks moving, in place of the last view's.
    pub(super) fn note_movers(&mut self, view: &View) {
        self.movers.held.clear();
        (self.movers.held).extend(view.moving_cells().map(|(x, y)| Cell::new(x, y)));
    }

    /// Whether the newest view marks cell `c` held by a mover.
    pub fn mover_in(&self, c: Cell) -> bool {
        self.movers.held.contains(&c)
    }

    /// Whether a mover holds cell `c` or one next to it along a row or a column.
    fn mover_near(&self, c: Cell) -> bool {
        self.mover_in(c) || neighbours(c).any(|n| self.mover_in(n))
    }

    /// Whether the move from `from` in direction `d` comes within `margin` of a mover: its
    /// cell, or for a diagonal either corner cell.
    fn meets_mover(&self, from: Cell, d: Direction, margin: Margin) -> bool {
        [(d.dx(), d.dy()), (d.dx(), 0), (0, d.dy())]
            .iter()
            .filter(|&&step| step != (0, 0))
            .filter_map(|&(dx, dy)| from.offset(dx, dy))
            .any(|c| match margin {
                Margin::Held => self.mover_in(c),
                Margin::Near => self.mover_near(c),
            })
    }

    /// The guide's proposal, kept clear of movers: a step that comes near one is no step
    /// (wait), unless a mover stands next to the robot: then a climb steps aside.
    pub(super) fn propose_clear_of_movers(&mut self) -> Proposal {
        let near = self.mover_directions();
        if near == 0 {
            self.movers.waiting = false;
            return self.guide_propose();
        }
        if self.mover_stands_next() {
            if let Guide::Climb(c) = &mut self.guide {
                c.refused(near);
            }
        }
        let p = match self.guide_propose() {
            Proposal::Step(c)
                if Direction::between(self.current, c)
                    .is_some_and(|d| near & 1 << d.index() != 0) =>
            {
                Proposal::Wait
            }
            p => p,
        };
        self.note_kept_clear(p == Proposal::Wait);
        p
    }

    /// Logs the start of each wait for a mover (once, not every round of it).
    fn note_kept_clear(&mut self, waits: bool) {
        if waits && !self.movers.waiting {
            tracing::info!(
                agent = self.task.index,
                x = self.current.x,
                y = self.current.y,
                "waits for a mover"
            );
        }
        self.movers.waiting = waits;
    }

    /// Whether a mover stands still next to the robot's cell: a held cell there with no
    /// held cell next to it (a mover walking a leg holds two).
    fn mover_stands_next(&self) -> bool {
        neighbours(self.current)
            .any(|c| self.mover_in(c) && !neighbours(c).any(|n| self.mover_in(n)))
    }

    /// The directions from the robot's cell it must not ask for (bit `d` = direction `d`).
    fn mover_directions(&self) -> u8 {
        if self.movers.held.is_empty() {
            return 0;
        }
        Direction::ALL
            .iter()
            .filter(|&&d| self.meets_mover(self.current, d, Margin::Near))
            .fold(0, |mask, d| mask | 1 << d.index())
    }

    /// Whether the robot, committed to `next` and `from_centre` cells from its cell's centre,
    /// must not set off now: a mover holds a cell of the move, and the robot has not set off
    /// yet.
    pub fn waits_for_mover(&self, from_centre: f64) -> bool {
        self.is_moving()
            && from_centre < SET_OFF_CELLS
            && Direction::between(self.current, self.next)
                .is_some_and(|d| self.meets_mover(self.current, d, Margin::Held))
    }
}

/// The cells next to `c` along its row and its column.
fn neighbours(c: Cell) -> impl Iterator<Item = Cell> {
    [(1, 0), (-1, 0), (0, 1), (0, -1)]
        .into_iter()
        .filter_map(move |(dx, dy)| c.offset(dx, dy))
}
