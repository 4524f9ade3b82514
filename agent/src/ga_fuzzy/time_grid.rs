//! Seed 004's environment model: `N` Boolean matrices `Sx x Sy`, one per time quantum, 1 where
//! a cell is occupied at that tick (§B.3 of the notes).
//!
//! The static walls are the same in every layer, so they are kept once (the [`Grid`]); what
//! changes between layers is the moving obstacles (other robots whose motion is known for the
//! planning period), kept per tick as a short sorted list of cells. A layer past the last one
//! is the last one: the seed says `N` is the depth over which the obstacles' motion is known,
//! and it gives no rule for later ticks, so we keep the last known positions `\[inferred\]`.

use hnav_runtime::grid::{Cell, CornerCutting, Grid};

use crate::error::{check_inside, Error, Role};

/// The space-time occupancy grid a GA route is scored on.
#[derive(Clone, Debug)]
pub struct TimeGrid {
    grid: Grid,
    rule: CornerCutting,
    /// `moving[t]`: the row-major indices occupied by moving obstacles at tick `t`, sorted.
    moving: Vec<Vec<usize>>,
    depth: usize,
}

impl TimeGrid {
    /// The static model: every one of the `depth` layers is `grid` (what a route planner sees
    /// when nothing else moves). `depth` is the longest chromosome allowed, at least 2.
    pub fn fixed(grid: Grid, rule: CornerCutting, depth: usize) -> Result<TimeGrid, Error> {
        if depth < 2 {
            return Err(Error::option(
                "depth",
                format!("{depth}: needs at least 2 layers"),
            ));
        }
        Ok(TimeGrid {
            grid,
            rule,
            moving: Vec::new(),
            depth,
        })
    }

    /// Adds a moving obstacle that occupies `trajectory[t]` at tick `t` (and its last cell
    /// afterwards). A cell outside the grid is an error naming the tick.
    pub fn add_moving(&mut self, trajectory: &[Cell]) -> Result<(), Error> {
        let (w, h) = (self.grid.width(), self.grid.height());
        for (t, &c) in trajectory.iter().enumerate() {
            check_inside(c, Role::Obstacle, w, h)
                .map_err(|e| Error::option("trajectory", format!("tick {t}: {e}")))?;
        }
        if self.moving.len() < trajectory.len() {
            self.moving.resize(trajectory.len(), Vec::new());
        }
        let last = trajectory.last().map(|&c| self.grid.index(c));
        for t in 0..self.moving.len() {
            let i = trajectory.get(t).map(|&c| self.grid.index(c)).or(last);
            if let Some(i) = i {
                let layer = &mut self.moving[t];
                if let Err(at) = layer.binary_search(&i) {
                    layer.insert(at, i);
                }
            }
        }
        Ok(())
    }

    /// The static grid (walls).
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// The corner rule of the moves.
    pub fn rule(&self) -> CornerCutting {
        self.rule
    }

    /// Whether nothing moves (every layer is the walls).
    pub fn is_static(&self) -> bool {
        self.moving.iter().all(Vec::is_empty)
    }

    /// `N`, the number of layers: the longest chromosome allowed.
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// Whether a moving obstacle occupies `cell` at tick `t` (walls not included).
    pub fn moving_at(&self, t: usize, cell: Cell) -> bool {
        let Some(layer) = self.moving.get(t).or(self.moving.last()) else {
            return false;
        };
        layer.binary_search(&self.grid.index(cell)).is_ok()
    }

    /// The layer `t` element of `cell`: 1 (true) if a wall or a moving obstacle is there.
    pub fn occupied(&self, t: usize, cell: Cell) -> bool {
        self.grid.is_blocked(cell) || self.moving_at(t, cell)
    }

    /// Collisions of a route whose node `t` is held at tick `t`: nodes on an occupied cell,
    /// and swaps with a moving obstacle (it goes `b -> a` while the route goes `a -> b`).
    pub fn conflicts(&self, route: &[Cell]) -> usize {
        if self.moving.is_empty() {
            return 0;
        }
        let mut n = 0;
        for (t, &c) in route.iter().enumerate() {
            n += usize::from(self.moving_at(t, c));
            if let Some(&next) = route.get(t + 1) {
                let swap = next != c && self.moving_at(t, next) && self.moving_at(t + 1, c);
                n += usize::from(swap);
            }
        }
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_hold_walls_and_moving_obstacles() {
        let mut g = Grid::new(4, 3).unwrap();
        g.set_blocked(Cell::new(3, 0), true);
        let mut tg = TimeGrid::fixed(g, CornerCutting::Forbidden, 8).unwrap();
        tg.add_moving(&[Cell::new(0, 1), Cell::new(1, 1), Cell::new(2, 1)])
            .unwrap();
        assert!(tg.occupied(0, Cell::new(3, 0)) && tg.occupied(7, Cell::new(3, 0)));
        assert!(tg.occupied(1, Cell::new(1, 1)) && !tg.occupied(1, Cell::new(0, 1)));
        // Past its known motion the obstacle stays where it was last seen.
        assert!(tg.occupied(5, Cell::new(2, 1)));
        // A route through (1,1) at tick 1 collides once; a head-on swap counts too.
        let route = [Cell::new(0, 0), Cell::new(1, 1), Cell::new(1, 2)];
        assert_eq!(tg.conflicts(&route), 1);
        let swap = [Cell::new(1, 1), Cell::new(0, 1)];
        assert_eq!(tg.conflicts(&swap), 1);
    }

    #[test]
    fn bad_depth_and_trajectories_are_errors() {
        let g = Grid::new(2, 2).unwrap();
        assert!(TimeGrid::fixed(g.clone(), CornerCutting::Forbidden, 1).is_err());
        let mut tg = TimeGrid::fixed(g, CornerCutting::Forbidden, 4).unwrap();
        let e = tg
            .add_moving(&[Cell::new(0, 0), Cell::new(5, 0)])
            .unwrap_err();
        assert!(e.to_string().contains("tick 1"), "{e}");
    }
}
