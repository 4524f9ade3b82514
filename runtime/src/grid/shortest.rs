//! Single-agent octile shortest paths: the "free oracle".
//!
//! A plain A* with the octile heuristic and a binary heap, on unit move costs (1 straight,
//! `sqrt 2` diagonal; terrain is ignored). It exists to check things, not to be the fastest
//! planner: `.scen` optimal lengths, scenario sanity (`hnav check`), and tests of the real
//! planners. With [`CornerCutting::Forbidden`] its lengths equal the MovingAI optimal lengths.
//!
//! Also [`reachable_from`], a BFS flood used to place random agents in connected cells, and
//! [`components`], the connected components it finds.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, VecDeque};

use super::coord::{octile, Cell};
use super::neighbours::CornerCutting;
use super::Grid;

/// Heap entry ordered so that `BinaryHeap` (a max-heap) pops the smallest `f` first, and on
/// ties the largest `g` (the node closer to the goal), which keeps A* from fanning out.
#[derive(Clone, Copy, Debug)]
struct Open {
    f: f64,
    g: f64,
    index: usize,
}

impl PartialEq for Open {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Open {}
impl PartialOrd for Open {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Open {
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .f
            .total_cmp(&self.f)
            .then(self.g.total_cmp(&other.g))
            .then(other.index.cmp(&self.index))
    }
}

/// Runs A*; returns the goal's cost and the parent table (`usize::MAX` = none).
fn astar(grid: &Grid, start: Cell, goal: Cell, rule: CornerCutting) -> Option<(f64, Vec<usize>)> {
    if grid.is_blocked(start) || grid.is_blocked(goal) {
        return None;
    }
    let n = grid.len();
    let start_i = grid.index(start);
    let goal_i = grid.index(goal);
    let mut g = vec![f64::INFINITY; n];
    let mut parent = vec![usize::MAX; n];
    let mut closed = vec![false; n];
    let mut open = BinaryHeap::new();
    g[start_i] = 0.0;
    open.push(Open {
        f: octile(start, goal),
        g: 0.0,
        index: start_i,
    });
    while let Some(Open { g: cost, index, .. }) = open.pop() {
        if closed[index] {
            continue;
        }
        closed[index] = true;
        if index == goal_i {
            return Some((cost, parent));
        }
        let Some(cell) = grid.cell_at(index) else {
            continue;
        };
        for (dir, next) in grid.neighbours(cell, rule) {
            let ni = grid.index(next);
            let ng = cost + dir.cost();
            if !closed[ni] && ng < g[ni] {
                g[ni] = ng;
                parent[ni] = index;
                open.push(Open {
                    f: ng + octile(next, goal),
                    g: ng,
                    index: ni,
                });
            }
        }
    }
    None
}

/// Length of the shortest octile path from `start` to `goal` under `rule`, or `None` if
/// either end is blocked/outside the grid or the goal is unreachable. `start == goal` gives 0.
pub fn octile_shortest_path_len(
    grid: &Grid,
    start: Cell,
    goal: Cell,
    rule: CornerCutting,
) -> Option<f64> {
    astar(grid, start, goal, rule).map(|(len, _)| len)
}

/// A shortest octile path as its length and cells (`start` first, `goal` last), or `None`
/// like [`octile_shortest_path_len`].
pub fn octile_shortest_path(
    grid: &Grid,
    start: Cell,
    goal: Cell,
    rule: CornerCutting,
) -> Option<(f64, Vec<Cell>)> {
    let (len, parent) = astar(grid, start, goal, rule)?;
    let mut cells = vec![goal];
    let mut i = grid.index(goal);
    while parent[i] != usize::MAX {
        i = parent[i];
        cells.push(grid.cell_at(i)?);
    }
    cells.reverse();
    Some((len, cells))
}

/// Flags (indexed like the grid) of every cell reachable from `start` under `rule`; all
/// `false` if `start` is blocked or outside. Moves are symmetric under both rules, so this is
/// also the set of cells from which `start` is reachable.
pub fn reachable_from(grid: &Grid, start: Cell, rule: CornerCutting) -> Vec<bool> {
    let mut seen = vec![false; grid.len()];
    if grid.is_blocked(start) {
        return seen;
    }
    let mut queue = VecDeque::new();
    seen[grid.index(start)] = true;
    queue.push_back(start);
    while let Some(cell) = queue.pop_front() {
        for (_, next) in grid.neighbours(cell, rule) {
            let i = grid.index(next);
            if !seen[i] {
                seen[i] = true;
                queue.push_back(next);
            }
        }
    }
    seen
}

/// Connected-component label of every free cell under `rule` (`u32::MAX` for blocked
/// cells), numbered from 0 in row-major order of each component's first cell.
pub fn components(grid: &Grid, rule: CornerCutting) -> Vec<u32> {
    let mut label = vec![u32::MAX; grid.len()];
    let mut next = 0u32;
    for cell in grid.passable_cells() {
        if label[grid.index(cell)] != u32::MAX {
            continue;
        }
        for (i, reached) in reachable_from(grid, cell, rule).into_iter().enumerate() {
            if reached {
                label[i] = next;
            }
        }
        next += 1;
    }
    label
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Direction;

    fn grid(rows: &[&str]) -> Grid {
        Grid::from_rows(rows).unwrap()
    }

    #[test]
    fn open_grid_equals_octile() {
        let g = Grid::new(20, 10).unwrap();
        for (a, b) in [
            ((0, 0), (19, 9)),
            ((3, 7), (3, 7)),
            ((5, 1), (12, 1)),
            ((19, 0), (0, 9)),
        ] {
            let (a, b) = (Cell::new(a.0, a.1), Cell::new(b.0, b.1));
            let len = octile_shortest_path_len(&g, a, b, CornerCutting::Forbidden).unwrap();
            assert!((len - octile(a, b)).abs() < 1e-9, "{a} {b} {len}");
        }
    }

    #[test]
    fn corner_cutting_changes_length() {
        let g = grid(&[".@", "@."]);
        let (a, b) = (Cell::new(0, 0), Cell::new(1, 1));
        assert_eq!(
            octile_shortest_path_len(&g, a, b, CornerCutting::Forbidden),
            None
        );
        let len = octile_shortest_path_len(&g, a, b, CornerCutting::Allowed).unwrap();
        assert!((len - std::f64::consts::SQRT_2).abs() < 1e-12);
        // One blocked corner: forbidden goes around (2 straight moves).
        let g = grid(&["..", "@."]);
        assert_eq!(
            octile_shortest_path_len(&g, a, b, CornerCutting::Forbidden),
            Some(2.0)
        );
    }

    #[test]
    fn path_is_connected_and_matches_length() {
        let g = grid(&["......", ".@@@@.", ".@....", ".@.@@@", "......"]);
        let (a, b) = (Cell::new(2, 2), Cell::new(5, 4));
        let (len, path) = octile_shortest_path(&g, a, b, CornerCutting::Forbidden).unwrap();
        assert_eq!(path.first(), Some(&a));
        assert_eq!(path.last(), Some(&b));
        let mut sum = 0.0;
        for w in path.windows(2) {
            let d = Direction::between(w[0], w[1]).unwrap();
            assert!(g.can_move(w[0], d, CornerCutting::Forbidden));
            sum += d.cost();
        }
        assert!((sum - len).abs() < 1e-9);
    }

    #[test]
    fn blocked_or_outside_ends() {
        let g = grid(&[".@."]);
        assert_eq!(
            octile_shortest_path_len(&g, Cell::new(0, 0), Cell::new(1, 0), CornerCutting::Allowed),
            None
        );
        assert_eq!(
            octile_shortest_path_len(&g, Cell::new(0, 0), Cell::new(2, 0), CornerCutting::Allowed),
            None
        );
        assert_eq!(
            octile_shortest_path_len(&g, Cell::new(0, 0), Cell::new(9, 0), CornerCutting::Allowed),
            None
        );
        let r = reachable_from(&g, Cell::new(0, 0), CornerCutting::Allowed);
        assert_eq!(r, vec![true, false, false]);
        assert!(reachable_from(&g, Cell::new(1, 0), CornerCutting::Allowed)
            .iter()
            .all(|&b| !b));
    }
}
