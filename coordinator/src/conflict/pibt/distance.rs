//! Per-agent distance tables: the true octile distance from every cell to an agent's goal
//! over the static map, under the round's corner rule.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use hnav_runtime::grid::{Cell, CornerCutting, Direction, Grid};

/// A straight step in table units (a diagonal is [`DIAGONAL`]): integers keep the tables
/// compact and the comparisons exact.
pub const STRAIGHT: u32 = 1000;
/// A diagonal step in table units (`sqrt 2`, rounded).
pub const DIAGONAL: u32 = 1414;
/// A cell from which the goal cannot be reached.
pub const UNREACHABLE: u32 = u32::MAX;
/// Largest table size in entries (4 bytes each: 64 MiB), over all agents. Beyond it the
/// octile heuristic stands in for the tables: 256 agents get tables on maps of up to 65 536
/// cells (256 x 256).
pub const MAX_TABLE_ENTRIES: usize = 1 << 24;

/// Whether a robot may step from `from` in direction `d` on `blocked` (row-major, `width` x
/// `height`): the target free and, for a diagonal, the corner rule of
/// [`Options::corner_cutting`](super::super::Options::corner_cutting) (`Forbidden`: both side
/// cells free; `Allowed`: not both blocked). The same rule as the resolver's, and symmetric,
/// so a table from the goal is also the distance to it.
pub fn can_step(
    blocked: &[bool],
    width: u32,
    height: u32,
    rule: CornerCutting,
    from: Cell,
    d: Direction,
) -> Option<Cell> {
    let free = |c: Cell| c.x < width && c.y < height && !blocked[(c.y * width + c.x) as usize];
    let to = from.offset(d.dx(), d.dy())?;
    if !free(to) {
        return None;
    }
    if d.is_diagonal() {
        let (a, b) = (free(Cell::new(to.x, from.y)), free(Cell::new(from.x, to.y)));
        let ok = match rule {
            CornerCutting::Forbidden => a && b,
            CornerCutting::Allowed => a || b,
        };
        if !ok {
            return None;
        }
    }
    Some(to)
}

/// One goal's table: the distance from every cell of `grid` to `goal` under `rule`
/// (Dijkstra from the goal; the steps are symmetric). `table` reads [`UNREACHABLE`]
/// everywhere before.
fn fill(table: &mut [u32], grid: &Grid, rule: CornerCutting, goal: Cell) {
    let Some(g) = grid.checked_index(goal).filter(|&g| !grid.blocked()[g]) else {
        return;
    };
    let mut heap = BinaryHeap::new();
    table[g] = 0;
    heap.push(Reverse((0u32, g as u32)));
    while let Some(Reverse((dist, u))) = heap.pop() {
        if dist > table[u as usize] {
            continue;
        }
        let Some(from) = grid.cell_at(u as usize) else {
            continue;
        };
        for dir in Direction::ALL {
            let step = can_step(grid.blocked(), grid.width(), grid.height(), rule, from, dir);
            let Some(to) = step else { continue };
            let v = grid.index(to);
            let nd = dist
                + if dir.is_diagonal() {
                    DIAGONAL
                } else {
                    STRAIGHT
                };
            if nd < table[v] {
                table[v] = nd;
                heap.push(Reverse((nd, v as u32)));
            }
        }
    }
}

/// Distances to each agent's goal; see the [module docs](self).
#[derive(Clone, Debug)]
pub struct Distances {
    width: u32,
    cells: usize,
    goals: Vec<Cell>,
    /// `goals.len()` tables of `cells` entries, or empty when too large (octile instead).
    table: Vec<u32>,
}

impl Distances {
    /// Tables for `goals` on `grid` under `rule` (one Dijkstra per goal), or none when they
    /// would exceed [`MAX_TABLE_ENTRIES`].
    pub fn new(grid: &Grid, goals: &[Cell], rule: CornerCutting) -> Self {
        let cells = grid.len();
        let mut d = Distances {
            width: grid.width(),
            cells,
            goals: goals.to_vec(),
            table: Vec::new(),
        };
        if goals.len().saturating_mul(cells) > MAX_TABLE_ENTRIES {
            return d;
        }
        d.table = vec![UNREACHABLE; goals.len() * cells];
        for (i, &goal) in goals.iter().enumerate() {
            fill(&mut d.table[i * cells..(i + 1) * cells], grid, rule, goal);
        }
        d
    }

    /// Agent `agent` heads for `goal` from now on (a lifelong run's next task): its table is
    /// computed again on `grid` under `rule`, one Dijkstra.
    pub fn set_goal(&mut self, grid: &Grid, rule: CornerCutting, agent: usize, goal: Cell) {
        let Some(g) = self.goals.get_mut(agent) else {
            return;
        };
        *g = goal;
        let cells = self.cells;
        if let Some(table) = self.table.get_mut(agent * cells..(agent + 1) * cells) {
            table.fill(UNREACHABLE);
            fill(table, grid, rule, goal);
        }
    }

    /// Whether the exact tables were built (else the octile heuristic answers).
    pub fn exact(&self) -> bool {
        !self.table.is_empty() || self.goals.is_empty()
    }

    /// The distance from `cell` to agent `agent`'s goal in table units; [`UNREACHABLE`] for
    /// an agent without a goal or a cell off the map or cut off from the goal.
    pub fn get(&self, agent: usize, cell: Cell) -> u32 {
        let Some(&goal) = self.goals.get(agent) else {
            return UNREACHABLE;
        };
        let i = cell.y as usize * self.width as usize + cell.x as usize;
        if cell.x >= self.width || i >= self.cells {
            return UNREACHABLE;
        }
        if self.table.is_empty() {
            let (dx, dy) = (cell.x.abs_diff(goal.x), cell.y.abs_diff(goal.y));
            let (lo, hi) = (dx.min(dy), dx.max(dy));
            return lo
                .saturating_mul(DIAGONAL)
                .saturating_add((hi - lo).saturating_mul(STRAIGHT));
        }
        self.table[agent * self.cells + i]
    }

    /// The agent's goal.
    pub fn goal(&self, agent: usize) -> Option<Cell> {
        self.goals.get(agent).copied()
    }
}
