//! Octile moves: the eight directions and the corner-cutting rule.
//!
//! The order of [`Direction::ALL`] is the dissertation's: clockwise from 12 o'clock, `N, NE, E,
//! SE, S, SW, W, NW`. North is `y - 1` because rows grow downwards. The index `0..8` of a
//! direction in that order is what the agent's direction masks and the wire messages use.
//!
//! # Corner cutting
//!
//! A diagonal move from `c` to `c + (dx, dy)` passes the corners of the two orthogonally
//! adjacent cells `c + (dx, 0)` and `c + (0, dy)`.
//!
//! * [`CornerCutting::Forbidden`] (the default, MovingAI's rule): the diagonal is refused if
//!   **either** of those two cells is blocked (or outside the grid). The optimal lengths in
//!   `.scen` files are computed this way, and a real robot of a cell's width would scrape the
//!   corner otherwise.
//! * [`CornerCutting::Allowed`] (the dissertation's neural-map tests): only the target cell has
//!   to be free; a diagonal may even squeeze between two blocked corners.

use std::fmt;

use super::coord::Cell;
use super::Grid;

/// One of the eight octile directions, in the dissertation's order.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, PartialOrd, Ord)]
#[repr(u8)]
pub enum Direction {
    /// Up, `(0, -1)`.
    N = 0,
    /// Up-right, `(1, -1)`.
    NE = 1,
    /// Right, `(1, 0)`.
    E = 2,
    /// Down-right, `(1, 1)`.
    SE = 3,
    /// Down, `(0, 1)`.
    S = 4,
    /// Down-left, `(-1, 1)`.
    SW = 5,
    /// Left, `(-1, 0)`.
    W = 6,
    /// Up-left, `(-1, -1)`.
    NW = 7,
}

/// `(dx, dy)` per direction, indexed by [`Direction::index`].
const DELTAS: [(i32, i32); 8] = [
    (0, -1),
    (1, -1),
    (1, 0),
    (1, 1),
    (0, 1),
    (-1, 1),
    (-1, 0),
    (-1, -1),
];

impl Direction {
    /// All directions, clockwise from north.
    pub const ALL: [Direction; 8] = [
        Direction::N,
        Direction::NE,
        Direction::E,
        Direction::SE,
        Direction::S,
        Direction::SW,
        Direction::W,
        Direction::NW,
    ];

    /// Position in [`Direction::ALL`], `0..8`.
    pub fn index(self) -> usize {
        self as usize
    }

    /// The direction with an index, or `None` if `index >= 8`.
    pub fn from_index(index: usize) -> Option<Direction> {
        Direction::ALL.get(index).copied()
    }

    /// Column change, `-1..=1`.
    pub fn dx(self) -> i32 {
        DELTAS[self.index()].0
    }

    /// Row change, `-1..=1` (negative is north).
    pub fn dy(self) -> i32 {
        DELTAS[self.index()].1
    }

    /// Whether both coordinates change.
    pub fn is_diagonal(self) -> bool {
        self.index() % 2 == 1
    }

    /// Length of the move: 1 straight, `sqrt 2` diagonal.
    pub fn cost(self) -> f64 {
        if self.is_diagonal() {
            std::f64::consts::SQRT_2
        } else {
            1.0
        }
    }

    /// The opposite direction.
    pub fn opposite(self) -> Direction {
        Direction::ALL[(self.index() + 4) % 8]
    }

    /// The direction of a single move from `from` to `to`, or `None` if they are not
    /// 8-neighbours (including when they are equal).
    pub fn between(from: Cell, to: Cell) -> Option<Direction> {
        let dx = i64::from(to.x) - i64::from(from.x);
        let dy = i64::from(to.y) - i64::from(from.y);
        Direction::ALL
            .into_iter()
            .find(|d| i64::from(d.dx()) == dx && i64::from(d.dy()) == dy)
    }
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self, f)
    }
}

/// Whether a diagonal move may pass a blocked corner; see the [module docs](self).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub enum CornerCutting {
    /// Diagonals need only a free target cell.
    Allowed,
    /// Diagonals also need both orthogonally adjacent cells free (MovingAI).
    #[default]
    Forbidden,
}

impl Grid {
    /// The neighbour of `cell` in direction `dir`, if it lies inside the grid (blocked or not).
    pub fn step(&self, cell: Cell, dir: Direction) -> Option<Cell> {
        cell.offset(dir.dx(), dir.dy())
            .filter(|&c| self.contains(c))
    }

    /// Whether a robot on `cell` may move one step in `dir` under `rule`: the target must be
    /// free and, for a forbidden corner cut, both orthogonal corners too. A blocked or outside
    /// origin is not checked, so the coordinator can ask about a robot standing on a cell that
    /// has just become blocked.
    pub fn can_move(&self, cell: Cell, dir: Direction, rule: CornerCutting) -> bool {
        let Some(target) = self.step(cell, dir) else {
            return false;
        };
        if self.is_blocked(target) {
            return false;
        }
        if dir.is_diagonal() && rule == CornerCutting::Forbidden {
            // Both corners are inside the grid because the diagonal target is.
            let side_x = Cell {
                x: target.x,
                y: cell.y,
            };
            let side_y = Cell {
                x: cell.x,
                y: target.y,
            };
            return !self.is_blocked(side_x) && !self.is_blocked(side_y);
        }
        true
    }

    /// The free neighbours of `cell` reachable in one move under `rule`, in
    /// [`Direction::ALL`] order. Does not allocate.
    pub fn neighbours(&self, cell: Cell, rule: CornerCutting) -> Neighbours<'_> {
        Neighbours {
            grid: self,
            cell,
            rule,
            next: 0,
        }
    }
}

/// Iterator over `(Direction, Cell)` pairs returned by [`Grid::neighbours`].
#[derive(Clone, Debug)]
pub struct Neighbours<'a> {
    grid: &'a Grid,
    cell: Cell,
    rule: CornerCutting,
    next: usize,
}

impl Iterator for Neighbours<'_> {
    type Item = (Direction, Cell);

    fn next(&mut self) -> Option<Self::Item> {
        while let Some(dir) = Direction::from_index(self.next) {
            self.next += 1;
            if self.grid.can_move(self.cell, dir, self.rule) {
                if let Some(c) = self.grid.step(self.cell, dir) {
                    return Some((dir, c));
                }
            }
        }
        None
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (0, Some(8usize.saturating_sub(self.next)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(rows: &[&str]) -> Grid {
        Grid::from_rows(rows).unwrap()
    }

    #[test]
    fn order_is_clockwise_from_north() {
        let d: Vec<(i32, i32)> = Direction::ALL.iter().map(|d| (d.dx(), d.dy())).collect();
        assert_eq!(d, DELTAS.to_vec());
        assert_eq!(Direction::N.dy(), -1);
        assert_eq!(Direction::E.dx(), 1);
        for (i, d) in Direction::ALL.iter().enumerate() {
            assert_eq!(d.index(), i);
            assert_eq!(Direction::from_index(i), Some(*d));
            assert_eq!(d.is_diagonal(), d.dx() != 0 && d.dy() != 0);
            assert_eq!(d.opposite().opposite(), *d);
            assert_eq!((d.opposite().dx(), d.opposite().dy()), (-d.dx(), -d.dy()));
        }
        assert_eq!(Direction::from_index(8), None);
        assert_eq!(Direction::SE.cost(), std::f64::consts::SQRT_2);
        assert_eq!(Direction::S.cost(), 1.0);
    }

    #[test]
    fn between_finds_single_moves() {
        let c = Cell::new(3, 3);
        for d in Direction::ALL {
            let n = c.offset(d.dx(), d.dy()).unwrap();
            assert_eq!(Direction::between(c, n), Some(d));
        }
        assert_eq!(Direction::between(c, c), None);
        assert_eq!(Direction::between(c, Cell::new(5, 3)), None);
    }

    #[test]
    fn open_centre_has_eight_and_corner_three() {
        let g = Grid::new(3, 3).unwrap();
        let all: Vec<_> = g
            .neighbours(Cell::new(1, 1), CornerCutting::Forbidden)
            .collect();
        assert_eq!(all.len(), 8);
        assert_eq!(all[0], (Direction::N, Cell::new(1, 0)));
        assert_eq!(all[7], (Direction::NW, Cell::new(0, 0)));
        let corner: Vec<_> = g
            .neighbours(Cell::new(0, 0), CornerCutting::Forbidden)
            .map(|(d, _)| d)
            .collect();
        assert_eq!(corner, vec![Direction::E, Direction::SE, Direction::S]);
    }

    #[test]
    fn corner_cutting_rules() {
        let g = grid(&[".@.", "...", "..."]);
        // From (0,1) NE is (1,0), blocked: never allowed.
        assert!(!g.can_move(Cell::new(0, 1), Direction::NE, CornerCutting::Allowed));
        // From (0,0) SE to (1,1): corners (1,0) blocked, (0,1) free.
        assert!(!g.can_move(Cell::new(0, 0), Direction::SE, CornerCutting::Forbidden));
        assert!(g.can_move(Cell::new(0, 0), Direction::SE, CornerCutting::Allowed));
        // Between two blocked corners.
        let g = grid(&[".@", "@."]);
        assert!(g.can_move(Cell::new(0, 0), Direction::SE, CornerCutting::Allowed));
        assert!(!g.can_move(Cell::new(0, 0), Direction::SE, CornerCutting::Forbidden));
        assert_eq!(
            g.neighbours(Cell::new(0, 0), CornerCutting::Forbidden)
                .count(),
            0
        );
        assert_eq!(
            g.neighbours(Cell::new(1, 1), CornerCutting::Allowed)
                .count(),
            1
        );
    }

    #[test]
    fn never_leaves_grid() {
        let g = Grid::new(1, 1).unwrap();
        assert_eq!(
            g.neighbours(Cell::new(0, 0), CornerCutting::Allowed)
                .count(),
            0
        );
        assert_eq!(g.step(Cell::new(0, 0), Direction::N), None);
        assert!(!g.can_move(Cell::new(5, 5), Direction::S, CornerCutting::Allowed));
    }
}
