//! Properties of `conflict::Resolver` over random rounds: whatever the agents ask for, applying
//! the accepted moves never puts two agents on a common cell, never swaps two agents, and never
//! enters a blocked cell or cuts a blocked corner. Also: a round allocates nothing.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell as StdCell;

use hnav_coordinator::conflict::{side_cells, AgentMode, AgentRow, Options, Outcome, Resolver};
use hnav_runtime::grid::{Cell, CornerCutting, Direction, Grid};
use hnav_runtime::msg::{ConflictKind, Verdict};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Counts this thread's allocations (tests run on several threads).
struct Counting;

thread_local! {
    static ALLOCATIONS: StdCell<usize> = const { StdCell::new(0) };
}

fn count() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> usize {
    ALLOCATIONS.with(|c| c.get())
}

/// The cells of all rows, checked pairwise: `Err` names the first cell two rows share.
fn disjoint(rows: &[AgentRow], options: &Options) -> Result<(), String> {
    for (i, a) in rows.iter().enumerate() {
        for (j, b) in rows.iter().enumerate().skip(i + 1) {
            for ca in a.held(options).into_iter().flatten() {
                if b.held(options).into_iter().flatten().any(|cb| cb == ca) {
                    return Err(format!("agents {i} and {j} both hold {ca}: {a:?} {b:?}"));
                }
            }
        }
    }
    Ok(())
}

/// A random request from `row.current`: mostly a neighbour (possibly off-grid or blocked),
/// sometimes an invalid cell or nothing.
fn request(rng: &mut ChaCha8Rng, grid: &Grid, current: Cell) -> Option<Cell> {
    match rng.gen_range(0..20) {
        0 => None,
        1 => Some(current),
        2 => Some(Cell::new(
            rng.gen_range(0..grid.width() + 2),
            rng.gen_range(0..grid.height() + 2),
        )),
        _ => {
            let d = Direction::ALL[rng.gen_range(0..8)];
            current
                .offset(d.dx(), d.dy())
                .or(Some(Cell::new(u32::MAX, u32::MAX)))
        }
    }
}

struct World {
    grid: Grid,
    rows: Vec<AgentRow>,
    options: Options,
}

fn world(seed: u64, options: Options) -> World {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (w, h) = (rng.gen_range(3..11), rng.gen_range(3..11));
    let density = rng.gen_range(0.0..0.3);
    let blocked: Vec<bool> = (0..w * h).map(|_| rng.gen_bool(density)).collect();
    let grid = Grid::from_blocked(w, h, &blocked).unwrap();
    let mut free: Vec<Cell> = grid.passable_cells().collect();
    let n = rng.gen_range(2..13).min(free.len());
    let mut rows = Vec::new();
    for _ in 0..n {
        let cell = free.swap_remove(rng.gen_range(0..free.len()));
        rows.push(AgentRow::at_rest(cell, None, 1.0));
    }
    World {
        grid,
        rows,
        options,
    }
}

/// Runs `rounds` random rounds and checks every property after each.
fn run(seed: u64, options: Options, rounds: usize) -> Result<(), TestCaseError> {
    let World {
        grid,
        mut rows,
        options,
    } = world(seed, options);
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
    let mut resolver = Resolver::new(&grid, rows.len(), options);
    let mut out: Vec<Outcome> = Vec::with_capacity(rows.len());
    prop_assert!(disjoint(&rows, &options).is_ok());
    for round in 0..rounds {
        // Arrivals, modes, priorities and requests.
        for row in rows.iter_mut() {
            if !row.is_at_rest() && rng.gen_bool(0.5) {
                row.current = row.next;
            }
            row.mode = match rng.gen_range(0..30) {
                0 => AgentMode::Standing,
                1 => AgentMode::Finished,
                2..=4 => AgentMode::Active,
                _ => row.mode,
            };
            row.priority = f64::from(rng.gen_range(1..4u8));
            row.probable = request(&mut rng, &grid, row.current);
        }
        let before = rows.clone();
        resolver.resolve(&rows, &mut out);
        prop_assert_eq!(out.len(), rows.len());
        for (i, (o, row)) in out.iter().zip(&before).enumerate() {
            let asks = row.mode == AgentMode::Active && row.is_at_rest() && row.probable.is_some();
            if !asks {
                prop_assert_eq!(*o, Outcome::default(), "round {} agent {}", round, i);
                continue;
            }
            let p = row.probable.unwrap();
            let d = Direction::between(row.current, p);
            match o.verdict {
                Verdict::Hold => prop_assert_eq!(o.refused, 0),
                Verdict::Block if o.kind != ConflictKind::Invalid => {
                    prop_assert_eq!(o.refused, 1u8 << d.unwrap().index());
                }
                Verdict::Block => {}
                Verdict::Accept => prop_assert_eq!((o.refused, o.kind), (0, ConflictKind::None)),
                Verdict::Replan | Verdict::Task => {
                    prop_assert!(false, "the resolver never replans nor gives tasks")
                }
            }
            if o.verdict == Verdict::Block {
                prop_assert!(o.kind != ConflictKind::None);
            }
            if o.verdict != Verdict::Accept {
                continue;
            }
            prop_assert_eq!(o.cell, Some(p));
            prop_assert!(d.is_some(), "accepted a non-neighbour");
            prop_assert!(grid.is_passable(p), "accepted a blocked cell {}", p);
            if let Some([a, b]) = side_cells(row.current, p) {
                let cut = match options.corner_cutting {
                    CornerCutting::Forbidden => grid.is_blocked(a) || grid.is_blocked(b),
                    CornerCutting::Allowed => grid.is_blocked(a) && grid.is_blocked(b),
                };
                prop_assert!(!cut, "accepted a corner cut {} -> {}", row.current, p);
            }
            // No swap: nobody else moves into this agent's cell, and it enters no cell
            // another agent held before the round.
            for (j, other) in before.iter().enumerate() {
                if j == i {
                    continue;
                }
                prop_assert!(
                    other.held(&options).into_iter().flatten().all(|c| c != p),
                    "round {}: agent {} enters {} held by {}",
                    round,
                    i,
                    p,
                    j
                );
            }
            rows[i].next = p;
        }
        if let Err(e) = disjoint(&rows, &options) {
            return Err(TestCaseError::fail(format!("round {round}: {e}")));
        }
        // A swap would need two accepted agents each entering the other's cell.
        for (i, a) in rows.iter().enumerate() {
            for b in rows.iter().skip(i + 1) {
                prop_assert!(!(a.next == b.current && b.next == a.current && a.next != a.current));
            }
        }
    }
    Ok(())
}

fn options() -> impl Strategy<Value = Options> {
    (any::<bool>(), any::<bool>()).prop_map(|(forbid, sweep)| Options {
        corner_cutting: if forbid {
            CornerCutting::Forbidden
        } else {
            CornerCutting::Allowed
        },
        sweep,
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, rng_seed: proptest::test_runner::RngSeed::Fixed(hnav_runtime::hash::test_seed(0xc0f1)), ..ProptestConfig::default() })]

    #[test]
    fn accepted_moves_never_collide(seed in any::<u64>(), options in options()) {
        run(seed, options, 50)?;
    }
}

#[test]
fn crowded_small_grids() {
    // Dense crowds on tiny maps exercise every rule at once.
    for seed in 0..200 {
        run(seed, Options::default(), 50).unwrap();
    }
}

#[test]
fn a_round_allocates_nothing() {
    let World { grid, rows, .. } = world(7, Options::default());
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut rows = rows;
    for row in rows.iter_mut() {
        row.probable = request(&mut rng, &grid, row.current);
        row.priority = f64::from(rng.gen_range(1..3u8));
    }
    let mut resolver = Resolver::new(&grid, rows.len(), Options::default());
    let mut out = Vec::with_capacity(rows.len());
    resolver.resolve(&rows, &mut out);
    let before = allocations();
    for _ in 0..100 {
        resolver.resolve(&rows, &mut out);
    }
    assert_eq!(allocations(), before, "resolve allocated");
}
