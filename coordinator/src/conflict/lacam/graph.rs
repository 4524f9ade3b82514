//! The moves of the static map as the search and the schedule see them: cells as row-major
//! indices, each with its moves under the round's corner rule and, for a diagonal whose robot
//! sweeps its corners ([`Options::sweep`]), the two side cells it holds while driving.

use hnav_runtime::grid::{Direction, Grid};

use crate::conflict::pibt::distance::can_step;
use crate::conflict::shared_paths::{side_cells, Options};

/// "No cell" / "no agent" in the search's tables.
pub(super) const NONE: u32 = u32::MAX;

/// One move out of a cell.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) struct Move {
    /// The cell it enters (the cell it leaves for a stay).
    pub to: u32,
    /// The side cells a diagonal holds, [`NONE`] for a straight move, a stay, or without
    /// sweeping.
    pub sides: [u32; 2],
}

/// The moves of every free cell, in compressed rows.
#[derive(Clone, Debug)]
pub(super) struct Graph {
    moves: Vec<Move>,
    /// `moves[first[c]..first[c + 1]]` are cell `c`'s moves.
    first: Vec<u32>,
}

impl Graph {
    /// The moves of `grid` under `options` (walls have none).
    pub fn new(grid: &Grid, options: Options) -> Self {
        let mut moves = Vec::new();
        let mut first = Vec::with_capacity(grid.len() + 1);
        for i in 0..grid.len() {
            first.push(moves.len() as u32);
            let Some(from) = grid.cell_at(i) else {
                continue;
            };
            if grid.blocked()[i] {
                continue;
            }
            for d in Direction::ALL {
                let step = can_step(
                    grid.blocked(),
                    grid.width(),
                    grid.height(),
                    options.corner_cutting,
                    from,
                    d,
                );
                let Some(to) = step else { continue };
                let sides = side_cells(from, to)
                    .filter(|_| options.sweep)
                    .map_or([NONE; 2], |[a, b]| {
                        [grid.index(a) as u32, grid.index(b) as u32]
                    });
                moves.push(Move {
                    to: grid.index(to) as u32,
                    sides,
                });
            }
        }
        first.push(moves.len() as u32);
        Graph { moves, first }
    }

    /// Cells of the map.
    pub fn cells(&self) -> usize {
        self.first.len() - 1
    }

    /// The moves out of `cell` (not the stay).
    pub fn moves(&self, cell: u32) -> &[Move] {
        let c = cell as usize;
        &self.moves[self.first[c] as usize..self.first[c + 1] as usize]
    }

    /// The move `from -> to`: a stay when equal, `None` when `to` is no move of `from`.
    pub fn step(&self, from: u32, to: u32) -> Option<Move> {
        if from == to {
            return Some(Move {
                to,
                sides: [NONE; 2],
            });
        }
        self.moves(from).iter().find(|m| m.to == to).copied()
    }
}
