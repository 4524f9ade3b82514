//! What the swarm knows of the map: the grid's cells it senses, plus its own virtual
//! obstacles (a separate layer, persistent for the run, never removed: notes §3.4, §6.1).
//!
//! Sensing (notes §1, \[A\]): the paper gives no radius, only that a particle senses "a local
//! region". The swarm reads the grid in exactly two places, both local: a particle reads the
//! one cell it is about to move to (at most `v_max + r_max` cells away per coordinate), and
//! the local-minimum analysis reads the 24 cells of the 5 x 5 window around the swarm's best,
//! each only if some particle stands within the sensing radius (Chebyshev, default 2) of it;
//! an unsensed window cell counts as free. Nothing else of the map is ever read.

use hnav_runtime::grid::{Cell, Grid};

/// The grid as the swarm sees it, with the virtual-obstacle layer.
#[derive(Clone, Debug, Default)]
pub struct Field {
    width: i64,
    height: i64,
    /// Virtual obstacles, indexed like the grid.
    virtual_obstacles: Vec<bool>,
    /// How many virtual obstacles the run has placed.
    placed: usize,
}

impl Field {
    /// Clears the layer for a new run on a `grid`-sized map (reusing the buffer).
    pub fn reset(&mut self, grid: &Grid) {
        self.width = i64::from(grid.width());
        self.height = i64::from(grid.height());
        self.virtual_obstacles.clear();
        self.virtual_obstacles.resize(grid.len(), false);
        self.placed = 0;
    }

    /// The cell at `p`, if inside the map.
    pub fn cell(&self, p: [i64; 2]) -> Option<Cell> {
        let inside = (0..self.width).contains(&p[0]) && (0..self.height).contains(&p[1]);
        inside.then(|| Cell::new(p[0] as u32, p[1] as u32))
    }

    fn index(&self, c: Cell) -> usize {
        c.y as usize * self.width as usize + c.x as usize
    }

    /// Whether a particle may stand on `p`: inside, not a wall, not a virtual obstacle.
    pub fn free(&self, grid: &Grid, p: [i64; 2]) -> bool {
        self.cell(p)
            .is_some_and(|c| !grid.is_blocked(c) && !self.virtual_obstacles[self.index(c)])
    }

    /// Whether `p` holds a virtual obstacle.
    pub fn is_virtual(&self, p: [i64; 2]) -> bool {
        self.cell(p)
            .is_some_and(|c| self.virtual_obstacles[self.index(c)])
    }

    /// Places a virtual obstacle on `p` (inside the map); false if one was there already.
    pub fn place(&mut self, p: [i64; 2]) -> bool {
        let Some(c) = self.cell(p) else { return false };
        let i = self.index(c);
        let new = !self.virtual_obstacles[i];
        self.virtual_obstacles[i] = true;
        self.placed += usize::from(new);
        new
    }

    /// How many virtual obstacles the run has placed (non-decreasing).
    pub fn placed(&self) -> usize {
        self.placed
    }

    /// The virtual-obstacle cells, in row-major order.
    pub fn virtual_cells(&self) -> impl Iterator<Item = Cell> + '_ {
        let w = self.width.max(1) as usize;
        self.virtual_obstacles
            .iter()
            .enumerate()
            .filter(|(_, &v)| v)
            .map(move |(i, _)| Cell::new((i % w) as u32, (i / w) as u32))
    }
}

/// Chebyshev distance between two points.
pub fn chebyshev(a: [i64; 2], b: [i64; 2]) -> i64 {
    (a[0] - b[0]).abs().max((a[1] - b[1]).abs())
}
