//! A PIBT round allocates nothing: after a warm-up round, rounds of a dense 64-agent
//! instance are counted by a global allocator. Nor does a LaCAM round that follows its plan
//! (the round that plans does allocate).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use hnav_coordinator::conflict::lacam::Phase;
use hnav_coordinator::conflict::{AgentMode, AgentRow, Lacam, Options, Outcome, Pibt};
use hnav_runtime::grid::{Cell, Grid};
use hnav_runtime::msg::Verdict;

/// Counts every allocation of the process (this binary has one test, so one thread).
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The rounds under test.
trait Rounds {
    fn resolve(&mut self, rows: &[AgentRow], out: &mut Vec<Outcome>);
    fn distance(&self, agent: usize, cell: Cell) -> u32;
}

impl Rounds for Pibt {
    fn resolve(&mut self, rows: &[AgentRow], out: &mut Vec<Outcome>) {
        Pibt::resolve(self, rows, out)
    }
    fn distance(&self, agent: usize, cell: Cell) -> u32 {
        Pibt::distance(self, agent, cell)
    }
}

impl Rounds for Lacam {
    fn resolve(&mut self, rows: &[AgentRow], out: &mut Vec<Outcome>) {
        Lacam::resolve(self, rows, out)
    }
    fn distance(&self, agent: usize, cell: Cell) -> u32 {
        Lacam::distance(self, agent, cell)
    }
}

/// One round of a discrete-time world: drivers arrive, accepted rows start driving, every
/// agent at rest off its goal asks for the neighbour closest to it (no allocation here
/// either, so that the count is the round's).
fn advance(p: &impl Rounds, rows: &mut [AgentRow], goals: &[Cell], out: &[Outcome]) {
    for (i, (row, o)) in rows.iter_mut().zip(out).enumerate() {
        if !row.is_at_rest() {
            row.current = row.next;
        } else if o.verdict == Verdict::Accept {
            row.next = o.cell.unwrap();
        }
        let home = row.is_at_rest() && row.current == goals[i];
        row.mode = if home {
            AgentMode::Finished
        } else {
            AgentMode::Active
        };
        row.probable = None;
        if row.is_at_rest() && !home {
            let here = p.distance(i, row.current);
            let mut best = None;
            for dx in -1i32..=1 {
                for dy in -1i32..=1 {
                    let Some(c) = row.current.offset(dx, dy).filter(|c| c.x < 16 && c.y < 16)
                    else {
                        continue;
                    };
                    let d = p.distance(i, c);
                    if d < here && best.is_none_or(|(bd, _)| d < bd) {
                        best = Some((d, c));
                    }
                }
            }
            row.probable = best.map(|(_, c)| c);
        }
    }
}

#[test]
fn pibt_and_lacam_rounds_allocate_nothing() {
    // One test for both: the allocation counter is global, and tests run in parallel.
    let (grid, starts, goals) = instance();
    for swap in [false, true] {
        let mut p = Pibt::new(&grid, &goals, Options::default());
        p.set_swap(swap);
        rounds_allocate_nothing(&mut p, &starts, &goals);
    }
    let mut l = Lacam::new(&grid, &goals, Options::default());
    rounds_allocate_nothing(&mut l, &starts, &goals);
    assert_eq!(l.phase(), Phase::Following, "{:?}", l.stats());
}

/// A dense instance and its goals.
fn instance() -> (Grid, Vec<Cell>, Vec<Cell>) {
    // 64 agents on a 16x16 room with a wall across (25 % of the free cells): the first 64
    // cells go to the last 64, so every agent crosses the others.
    let mut grid = Grid::new(16, 16).unwrap();
    for x in 2..14 {
        grid.set_blocked(Cell::new(x, 8), true);
    }
    let free: Vec<Cell> = (0..grid.len())
        .filter(|&i| !grid.blocked()[i])
        .map(|i| grid.cell_at(i).unwrap())
        .collect();
    let starts = free[..64].to_vec();
    let goals: Vec<Cell> = free[free.len() - 64..].iter().rev().copied().collect();
    (grid, starts, goals)
}

fn rounds_allocate_nothing(p: &mut impl Rounds, starts: &[Cell], goals: &[Cell]) {
    let mut rows: Vec<AgentRow> = starts
        .iter()
        .map(|&s| AgentRow::at_rest(s, None, 1.0))
        .collect();
    let mut out = Vec::with_capacity(rows.len());
    advance(p, &mut rows, goals, &out);
    p.resolve(&rows, &mut out);
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let mut moves = 0;
    for _ in 0..200 {
        advance(p, &mut rows, goals, &out);
        p.resolve(&rows, &mut out);
        moves += out.iter().filter(|o| o.accepted()).count();
    }
    let allocated = ALLOCATIONS.load(Ordering::Relaxed) - before;
    assert!(moves > 64, "the rounds did something: {moves} moves");
    assert_eq!(allocated, 0, "allocations in 200 rounds");
}
