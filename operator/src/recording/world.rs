//! The world as a finished run's recording shows it at a time: the map with the scenario's
//! closes and opens applied up to then, the movers where they were last recorded, and what
//! each robot's range sensor saw from its recorded pose.
//!
//! A run keeps no views (they are a function of the world's state), so a reader rebuilds
//! them with the sim's own line of sight ([`hnav_runtime::grid::sight`]). One difference from
//! the sim, by design of what is recorded: a mover blocks the sight through the cell of its
//! centre (the sim blocks every cell its disc overlaps), and it holds that cell. The playback
//! in `hnav top` and the report's sensed area read the world through this one type, so they
//! say the same of what a robot saw.

use hnav_runtime::grid::sight;
use hnav_runtime::grid::{Cell, Grid};
use hnav_runtime::msg::{MoverPlace, Pose, View};
use hnav_runtime::scenario::Scenario;

/// One close or open of the scenario's `[[events]]`.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldStep {
    /// When, ns of sim time.
    pub at_ns: u64,
    /// The cells (0-based row-major indices).
    pub cells: Vec<u32>,
    /// Whether they close (else they open).
    pub closed: bool,
}

/// The closes and opens of `scenario`'s `[[events]]` on `grid` (its map), in time order.
pub fn world_steps(scenario: &Scenario, grid: &Grid) -> Vec<WorldStep> {
    // Messages name cells by their 0-based row-major index, not the 1-based cell id.
    let id = |c| u32::try_from(grid.index(c)).unwrap_or(hnav_runtime::msg::NO_CELL);
    scenario
        .events
        .iter()
        .filter_map(|e| {
            let (cells, closed) = e.change.cells()?;
            Some(WorldStep {
                at_ns: (e.at_s * 1e9).round() as u64,
                cells: cells.iter().map(|&c| id(c)).collect(),
                closed,
            })
        })
        .collect()
}

/// Applies to `grid` the steps of `steps` from index `*applied` on that are due by `t_ns`,
/// moving `*applied` past them; whether any was. The one way a reader (the view's state, the
/// live Foxglove view, [`RecordedWorld`]) follows the scenario's closes and opens.
pub fn apply_due(grid: &mut Grid, steps: &[WorldStep], applied: &mut usize, t_ns: u64) -> bool {
    let before = *applied;
    while let Some(step) = steps.get(*applied).filter(|s| s.at_ns <= t_ns) {
        for &c in &step.cells {
            if let Some(cell) = grid.cell_at(c as usize) {
                grid.set_blocked(cell, step.closed);
            }
        }
        *applied += 1;
    }
    *applied != before
}

/// The world of a recorded run, moved forward in time by its reader.
#[derive(Debug, Clone)]
pub struct RecordedWorld {
    grid: Grid,
    steps: Vec<WorldStep>,
    applied: usize,
    movers: Vec<MoverPlace>,
    /// The cells of the movers' centres (row-major), kept beside `movers`.
    mover_cells: Vec<u32>,
    cell_size_m: f64,
}

impl RecordedWorld {
    /// The world at the start: `grid` (the scenario's map), to change by `steps`.
    pub fn new(grid: Grid, steps: Vec<WorldStep>, cell_size_m: f64) -> Self {
        RecordedWorld {
            grid,
            steps,
            applied: 0,
            movers: Vec::new(),
            mover_cells: Vec::new(),
            cell_size_m,
        }
    }

    /// Applies the closes and opens due by `t_ns`; whether any was.
    pub fn advance(&mut self, t_ns: u64) -> bool {
        apply_due(&mut self.grid, &self.steps, &mut self.applied, t_ns)
    }

    /// Mover `k` (in the order they appeared) is at `pose` now: it is on the floor.
    pub fn place_mover(&mut self, k: u32, pose: Pose) {
        let cell = self.cell_of(&pose).map_or(hnav_runtime::msg::NO_CELL, |c| {
            c.y * self.grid.width() + c.x
        });
        let place = MoverPlace {
            mover: k,
            reserved: 0,
            pose,
        };
        match self.movers.iter().position(|m| m.mover == k) {
            Some(i) => (self.movers[i], self.mover_cells[i]) = (place, cell),
            None => {
                self.movers.push(place);
                self.mover_cells.push(cell);
            }
        }
    }

    /// The movers on the floor, where they were last placed, in the order they came on.
    pub fn movers(&self) -> &[MoverPlace] {
        &self.movers
    }

    /// The map now.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// The cell a pose stands in, if it is on the map.
    pub fn cell_of(&self, pose: &Pose) -> Option<Cell> {
        let (x, y) = (
            (pose.x_m / self.cell_size_m).floor(),
            (pose.y_m / self.cell_size_m).floor(),
        );
        let (w, h) = (f64::from(self.grid.width()), f64::from(self.grid.height()));
        (x >= 0.0 && y >= 0.0 && x < w && y < h).then(|| Cell::new(x as u32, y as u32))
    }

    /// Fills `view` with what robot `agent` at `pose` sees within `range` cells now, as the
    /// sim's view of that time would have it (see the [module docs](self) for the one
    /// difference); nothing but the agent and time when the pose is off the map.
    pub fn fill_view(&self, agent: u32, pose: &Pose, range: u32, t_ns: u64, view: &mut View) {
        view.sim_time_ns = t_ns;
        view.agent = agent;
        let Some(at) = self.cell_of(pose) else {
            view.reset(0, 0, 0);
            return;
        };
        let w = self.grid.width();
        let blocked = |x: i64, y: i64| {
            let c = Cell::new(x as u32, y as u32);
            self.grid.is_blocked(c) || self.mover_cells.contains(&(c.y * w + c.x))
        };
        let dims = (w, self.grid.height());
        let from = (i64::from(at.x), i64::from(at.y));
        sight::fill_view(view, dims, from, range, blocked);
        for &c in &self.mover_cells {
            if c != hnav_runtime::msg::NO_CELL {
                view.mark_moving(c % w, c / w);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corridor() -> RecordedWorld {
        // 8 x 1 cells of 1 m; cell 4 closes at 1 s.
        let grid = Grid::new(8, 1).unwrap();
        let steps = vec![WorldStep {
            at_ns: 1_000_000_000,
            cells: vec![4],
            closed: true,
        }];
        RecordedWorld::new(grid, steps, 1.0)
    }

    fn seen(v: &View) -> Vec<u32> {
        v.cells().map(|(x, _, _)| x).collect()
    }

    #[test]
    fn a_closed_door_and_a_mover_hide_what_is_behind_them_from_their_time_on() {
        let mut w = corridor();
        let robot = Pose {
            x_m: 1.5,
            y_m: 0.5,
            theta_rad: 0.0,
        };
        let mut v = View::default();
        w.fill_view(0, &robot, 6, 0, &mut v);
        assert_eq!(seen(&v), (0..8).collect::<Vec<_>>());
        assert!(!w.advance(999_999_999));
        assert!(w.advance(1_000_000_000));
        w.fill_view(0, &robot, 6, 1_000_000_000, &mut v);
        assert_eq!(seen(&v), [0, 1, 2, 3, 4]);
        assert!(w.grid().is_blocked(Cell::new(4, 0)));
        // A mover at cell 3: seen, moving, and the door behind it hidden.
        w.place_mover(0, Pose { x_m: 3.5, ..robot });
        w.fill_view(0, &robot, 6, 1_000_000_000, &mut v);
        assert_eq!(seen(&v), [0, 1, 2, 3]);
        assert_eq!(v.moving_cells().collect::<Vec<_>>(), [(3, 0)]);
        assert_eq!(w.movers().len(), 1);
    }
}
