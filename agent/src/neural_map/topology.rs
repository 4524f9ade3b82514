//! Which neurons are linked and what each denominator is: the one definition both the
//! reference and the fast path build from, so they cannot disagree about the network.

use hnav_runtime::grid::{Cell, Direction, Grid};

use super::{Denominator, DiagonalRule, Weights};

/// Blocked flags plus the diagonal rule of one map (unpadded, row-major like [`Grid`]).
#[derive(Clone, Debug)]
pub(crate) struct Topology {
    pub width: u32,
    pub height: u32,
    pub blocked: Vec<bool>,
    pub rule: DiagonalRule,
}

impl Topology {
    pub fn new(grid: &Grid, rule: DiagonalRule) -> Self {
        Topology {
            width: grid.width(),
            height: grid.height(),
            blocked: grid.blocked().to_vec(),
            rule,
        }
    }

    pub fn len(&self) -> usize {
        self.blocked.len()
    }

    pub fn index(&self, cell: Cell) -> usize {
        cell.y as usize * self.width as usize + cell.x as usize
    }

    pub fn cell(&self, index: usize) -> Cell {
        let w = self.width as usize;
        // index < width * height <= 2^26, so both fit in u32.
        Cell::new((index % w) as u32, (index / w) as u32)
    }

    pub fn contains(&self, cell: Cell) -> bool {
        cell.x < self.width && cell.y < self.height
    }

    /// Blocked or outside.
    pub fn is_blocked(&self, cell: Cell) -> bool {
        !self.contains(cell) || self.blocked[self.index(cell)]
    }

    /// The in-grid neighbour of `cell` in direction `d`.
    pub fn step(&self, cell: Cell, d: Direction) -> Option<Cell> {
        cell.offset(d.dx(), d.dy()).filter(|&c| self.contains(c))
    }

    /// Whether the link from free `cell` towards `d` exists: the neighbour is inside and
    /// free and, for a diagonal, the corner rule allows it.
    pub fn linked(&self, cell: Cell, d: Direction) -> bool {
        let Some(n) = self.step(cell, d) else {
            return false;
        };
        if self.blocked[self.index(n)] {
            return false;
        }
        if d.is_diagonal() {
            let a = self.is_blocked(Cell::new(n.x, cell.y));
            let b = self.is_blocked(Cell::new(cell.x, n.y));
            return self.rule.allows(a, b);
        }
        true
    }

    /// Bit `d` set when the link towards direction `d` exists.
    pub fn links(&self, cell: Cell) -> u8 {
        Direction::ALL
            .iter()
            .filter(|&&d| self.linked(cell, d))
            .fold(0u8, |acc, d| acc | (1 << d.index()))
    }

    /// `D_i` of eq. 3.3 (self weight included, gain applied) for a free cell.
    pub fn denominator(&self, cell: Cell, weights: &Weights, policy: Denominator) -> f64 {
        let w = |d: Direction| {
            if d.is_diagonal() {
                weights.diagonal
            } else {
                weights.straight
            }
        };
        let sum: f64 = match policy {
            Denominator::LinkedOnly => Direction::ALL
                .iter()
                .filter(|&&d| self.linked(cell, d))
                .map(|&d| w(d))
                .sum(),
            Denominator::InGrid => Direction::ALL
                .iter()
                .filter(|&&d| self.step(cell, d).is_some())
                .map(|&d| w(d))
                .sum(),
            Denominator::OffGridAsZero => Direction::ALL
                .iter()
                .filter(|&&d| self.linked(cell, d) || self.step(cell, d).is_none())
                .map(|&d| w(d))
                .sum(),
            Denominator::AllEight => 4.0 * weights.straight + 4.0 * weights.diagonal,
        };
        weights.gain * (weights.self_weight + sum)
    }
}
