//! The dense weight-matrix builder of Table 2-2.
//!
//! The sweeps never build a matrix: every neuron has the same 3x3 stencil, so they use the
//! weights directly. The dense matrix exists to show the network's structure and the
//! stability rule of §2.8.3 (symmetric, zero diagonal), and to reproduce Table 2-2.

use hnav_runtime::grid::{Direction, Grid};

use super::topology::Topology;
use super::weights::Weights;
use super::DiagonalRule;
use crate::error::Error;

/// A dense, row-major `n x n` weight matrix; neuron `i` is the grid index `row * cols + col`.
#[derive(Clone, PartialEq, Debug)]
pub struct WeightMatrix {
    n: usize,
    data: Vec<f64>,
}

impl WeightMatrix {
    /// Most neurons a dense matrix may have (a 64 x 64 grid: 128 MiB of `f64`).
    pub const MAX_NEURONS: usize = 4096;

    /// The 8-neighbour lattice of `rows x cols` neurons without obstacles. With
    /// [`Weights::table_2_2`] and a 3 x 4 lattice this is Table 2-2.
    pub fn lattice(rows: u32, cols: u32, weights: &Weights) -> Result<WeightMatrix, Error> {
        let grid = Grid::new(cols, rows).map_err(|e| Error::option("rows/cols", e.to_string()))?;
        Self::for_grid(&grid, weights, DiagonalRule::Always)
    }

    /// The weights of a grid with obstacles: an obstacle neuron is "switched off" (its row and
    /// column are 0), and cut diagonals have weight 0. The self weight sits on the diagonal
    /// of every free neuron.
    pub fn for_grid(
        grid: &Grid,
        weights: &Weights,
        rule: DiagonalRule,
    ) -> Result<WeightMatrix, Error> {
        weights.validate()?;
        let n = grid.len();
        if n > Self::MAX_NEURONS {
            return Err(Error::TooLarge {
                cells: n,
                max: Self::MAX_NEURONS,
            });
        }
        let topo = Topology::new(grid, rule);
        let mut data = vec![0.0; n * n];
        for i in 0..n {
            if topo.blocked[i] {
                continue;
            }
            let cell = topo.cell(i);
            data[i * n + i] = weights.gain * weights.self_weight;
            for d in Direction::ALL {
                if topo.linked(cell, d) {
                    if let Some(j) = topo.step(cell, d) {
                        data[i * n + topo.index(j)] = weights.link(d);
                    }
                }
            }
        }
        Ok(WeightMatrix { n, data })
    }

    /// Number of neurons.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the matrix has no neurons (never: a grid has at least one cell).
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// `w_ij`, or `None` outside the matrix.
    pub fn get(&self, i: usize, j: usize) -> Option<f64> {
        (i < self.n && j < self.n).then(|| self.data[i * self.n + j])
    }

    /// Row `i`, or `None` outside the matrix.
    pub fn row(&self, i: usize) -> Option<&[f64]> {
        (i < self.n).then(|| &self.data[i * self.n..(i + 1) * self.n])
    }

    /// `w_ij == w_ji` for all `i, j`.
    pub fn is_symmetric(&self) -> bool {
        (0..self.n).all(|i| (0..i).all(|j| self.data[i * self.n + j] == self.data[j * self.n + i]))
    }

    /// Every `w_ii` is 0 (no self-connections).
    pub fn has_zero_diagonal(&self) -> bool {
        (0..self.n).all(|i| self.data[i * self.n + i] == 0.0)
    }

    /// §2.8.3's stability rule: symmetric with a zero diagonal.
    pub fn is_stable_by_hopfield_rule(&self) -> bool {
        self.is_symmetric() && self.has_zero_diagonal()
    }
}
