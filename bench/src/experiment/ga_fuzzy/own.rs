//! Seed 004's own setting, rebuilt: one robot of a group plans across a coarse grid while the
//! other robots of the group move along routes known for the planning period (notes §B.3:
//! "N matrices Sx x Sy ... the period over which the motion of obstacles (other robots) is
//! known"). The seed gives no map, size, obstacle layout, group size or depth, so every
//! number here is `\[inferred\]`, chosen so that the moving robots matter:
//!
//! * the map: [`SIDE`] x [`SIDE`] (the MovingAI random maps' size), [`RECTANGLES`] random
//!   rectangles with sides 1..=[`MAX_RECT`], clipped at the border;
//! * the group: [`ROBOTS`] other robots, each on a shortest octile path between two random
//!   free cells, one cell per tick, then standing on its goal (the [`TimeGrid`]'s rule for
//!   ticks past the known motion);
//! * the task: a random start and goal at least [`MIN_DISTANCE`] apart (octile), neither of
//!   them another robot's start or goal, the goal reachable;
//! * the depth: `N` = [`DEPTH`] layers.

use anyhow::Result;
use hnav_agent::ga_fuzzy::{GaOptions, TimeGrid};
use hnav_runtime::grid::{octile_shortest_path, Cell, CornerCutting, Grid};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::planners::{answer, PLANNERS};
use super::Task;

/// Side of the square map, cells.
pub const SIDE: u32 = 32;
/// Random rectangles per map.
pub const RECTANGLES: usize = 12;
/// Longest side of a rectangle, cells.
pub const MAX_RECT: u32 = 4;
/// The other robots of the group (the moving obstacles).
pub const ROBOTS: usize = 20;
/// Shortest octile distance between the task's start and goal.
pub const MIN_DISTANCE: f64 = 16.0;
/// `N`, the time layers: the depth of the plan and the longest route.
pub const DEPTH: usize = 4 * SIDE as usize;

const RULE: CornerCutting = CornerCutting::Forbidden;

/// One generated task: the walls, the other robots' motion and our endpoints.
#[derive(Clone, Debug)]
pub struct World {
    /// The time layers (walls and the other robots).
    pub layers: TimeGrid,
    /// Our start and goal.
    pub endpoints: (Cell, Cell),
    /// The shortest octile length between them on the walls alone.
    pub optimal: f64,
    /// The other robots' routes, tick by tick.
    pub robots: Vec<Vec<Cell>>,
}

fn random_map(rng: &mut ChaCha8Rng) -> Grid {
    super::super::pso_tasks::random_rectangles(rng, SIDE, RECTANGLES, MAX_RECT)
}

fn free_cell(grid: &Grid, taken: &[Cell], rng: &mut ChaCha8Rng) -> Option<Cell> {
    (0..1000).find_map(|_| {
        let c = Cell::new(rng.gen_range(0..SIDE), rng.gen_range(0..SIDE));
        (!grid.is_blocked(c) && !taken.contains(&c)).then_some(c)
    })
}

/// One world drawn from `rng`; `None` if the draw failed (a blocked-in cell, an unreachable
/// goal), and the caller draws again.
pub fn world(rng: &mut ChaCha8Rng) -> Option<World> {
    let grid = random_map(rng);
    let mut taken = Vec::with_capacity(2 * ROBOTS + 2);
    let mut robots = Vec::with_capacity(ROBOTS);
    while robots.len() < ROBOTS {
        let s = free_cell(&grid, &taken, rng)?;
        let g = free_cell(&grid, &taken, rng).filter(|&g| g != s)?;
        if let Some((_, cells)) = octile_shortest_path(&grid, s, g, RULE) {
            taken.extend([s, g]);
            robots.push(cells);
        }
    }
    let start = free_cell(&grid, &taken, rng)?;
    let goal =
        free_cell(&grid, &taken, rng).filter(|&g| g != start && start.octile(g) >= MIN_DISTANCE)?;
    let (optimal, _) = octile_shortest_path(&grid, start, goal, RULE)?;
    let mut layers = TimeGrid::fixed(grid, RULE, DEPTH).ok()?;
    for r in &robots {
        layers.add_moving(r).ok()?;
    }
    Some(World {
        layers,
        endpoints: (start, goal),
        optimal,
        robots,
    })
}

/// `n` worlds from `seed`, every planner on each.
pub fn run(n: usize, ga: GaOptions, seed: u64) -> Result<Vec<Task>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let Some(w) = world(&mut rng) else { continue };
        let (start, goal) = w.endpoints;
        let answers = PLANNERS
            .iter()
            .map(|&p| answer(p, ga, &w.layers, start, goal))
            .collect::<Result<Vec<_>>>()?;
        out.push(Task {
            label: format!("world {}", out.len()),
            endpoints: w.endpoints,
            optimal: w.optimal,
            answers,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn worlds_are_seeded_and_keep_their_promises() {
        let draw = |seed| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            (0..200)
                .filter_map(|_| world(&mut rng))
                .take(3)
                .collect::<Vec<_>>()
        };
        let (a, b) = (draw(5), draw(5));
        assert_eq!(a.len(), 3);
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.endpoints, y.endpoints);
            assert_eq!(x.robots, y.robots);
            let (s, g) = x.endpoints;
            assert!(s.octile(g) >= MIN_DISTANCE && x.optimal >= s.octile(g) - 1e-9);
            assert_eq!(x.robots.len(), ROBOTS);
            // Nobody starts on our start or parks on our goal.
            assert!(!x.layers.moving_at(0, s) && !x.layers.moving_at(DEPTH, g));
        }
    }
}
