//! The changing warehouse one experiment setting runs in: its map, seeded robots, doors that
//! close and open on a schedule, and people who walk its aisles, written as a scenario.
//!
//! A door is an aisle cell: free, between two shelves (walls left and right, or above and
//! below), never a robot's start or goal and never on a walker's row, so closing it cuts an
//! aisle without trapping anybody for good. Door `i` closes at `DOOR_FIRST_S + i *
//! DOOR_EVERY_S` and opens again `DOOR_SHUT_S` later. A walker goes back and forth along the
//! longest free stretch of a random row without a robot's start or goal, from `WALKERS_AT_S`.

use std::fmt::Write as _;

use anyhow::{bail, Result};
use rand::seq::SliceRandom;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use hnav_runtime::grid::shortest::octile_shortest_path_len;
use hnav_runtime::grid::{Cell, CornerCutting, Grid};

/// When the first door closes, s of sim time.
const DOOR_FIRST_S: f64 = 4.0;
/// Between two doors' closing, s.
const DOOR_EVERY_S: f64 = 6.0;
/// How long a door stays shut, s.
const DOOR_SHUT_S: f64 = 15.0;
/// When the walkers appear, s.
const WALKERS_AT_S: f64 = 1.0;
/// A walker's speed, cells per second (a person among robots at 1 cell/s).
const WALKER_SPEED: f64 = 0.5;
/// The shortest stretch a walker walks, cells.
const WALKER_MIN_CELLS: u32 = 6;

/// What a setting asks of its world.
#[derive(Clone, Copy, Debug)]
pub struct Shape {
    /// Robots.
    pub robots: usize,
    /// Doors.
    pub doors: usize,
    /// Walkers.
    pub walkers: usize,
    /// The shortest start-to-goal distance, cells.
    pub min_len: f64,
}

/// A world drawn for one setting: the same for every variant that runs it.
#[derive(Clone, Debug)]
pub struct World {
    /// Each robot's (start, goal).
    pub robots: Vec<(Cell, Cell)>,
    /// The sum of the robots' octile shortest paths on the map at start.
    pub optimal_sum: f64,
    /// `[[agents]]` and `[[events]]`, as scenario text.
    pub toml: String,
}

/// Draws robots, doors and walkers on `grid` from `rng`.
pub fn draw(grid: &Grid, shape: Shape, rng: &mut ChaCha8Rng) -> Result<World> {
    let free: Vec<Cell> = cells(grid).filter(|&c| !grid.is_blocked(c)).collect();
    let (robots, optimal_sum) = robots(grid, &free, shape, rng)?;
    let used = |c: &Cell| robots.iter().any(|(s, g)| s == c || g == c);
    let mut events: Vec<(f64, String)> = Vec::new();
    let mut walker_rows = Vec::new();
    let mut rows: Vec<u32> = (0..grid.height()).collect();
    rows.shuffle(rng);
    for y in rows {
        if walker_rows.len() == shape.walkers {
            break;
        }
        // Neither a start nor a goal on a walker's way: a robot parked at its goal there
        // would hold a yielding walker for good (the first full run: walker 0 waited 900 s
        // at its end for robot 38 at its goal next to it, and robot 6 for the walker).
        let on_way = |c: Cell| robots.iter().any(|(s, g)| *s == c || *g == c);
        let stretch = longest_free_stretch(grid, y, &on_way);
        if let Some((x0, x1)) = stretch.filter(|(a, b)| b - a + 1 >= WALKER_MIN_CELLS) {
            let name = format!("walker-{}", walker_rows.len());
            let text = format!(
                "mover = {name:?}\npath = [[{x0}, {y}], [{x1}, {y}]]\nspeed = {WALKER_SPEED}\nrepeat = true"
            );
            events.push((WALKERS_AT_S, text));
            walker_rows.push(y);
        }
    }
    let mut doors: Vec<Cell> = free
        .iter()
        .copied()
        .filter(|c| is_doorway(grid, *c) && !used(c) && !walker_rows.contains(&c.y))
        .collect();
    doors.shuffle(rng);
    if doors.len() < shape.doors || walker_rows.len() < shape.walkers {
        bail!(
            "the map has room for {} doors and {} walkers, the setting wants {} and {}",
            doors.len(),
            walker_rows.len(),
            shape.doors,
            shape.walkers
        );
    }
    for (i, d) in doors.iter().take(shape.doors).enumerate() {
        let shut = DOOR_FIRST_S + i as f64 * DOOR_EVERY_S;
        events.push((shut, format!("close = [[{}, {}]]", d.x, d.y)));
        events.push((shut + DOOR_SHUT_S, format!("open = [[{}, {}]]", d.x, d.y)));
    }
    // The scenario wants its events in time order.
    events.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut toml = String::new();
    for (s, g) in &robots {
        let _ = writeln!(
            toml,
            "\n[[agents]]\nstart = [{}, {}]\ngoal = [{}, {}]",
            s.x, s.y, g.x, g.y
        );
    }
    for (at, what) in &events {
        let _ = writeln!(toml, "\n[[events]]\nat_s = {at:?}\n{what}");
    }
    Ok(World {
        robots,
        optimal_sum,
        toml,
    })
}

fn cells(grid: &Grid) -> impl Iterator<Item = Cell> + '_ {
    (0..grid.height()).flat_map(move |y| (0..grid.width()).map(move |x| Cell::new(x, y)))
}

/// `shape.robots` distinct starts and distinct goals at least `min_len` apart (octile, no
/// corner cutting) and connected; with the sum of their shortest lengths.
fn robots(
    grid: &Grid,
    free: &[Cell],
    shape: Shape,
    rng: &mut ChaCha8Rng,
) -> Result<(Vec<(Cell, Cell)>, f64)> {
    let (mut out, mut sum) = (Vec::new(), 0.0);
    let mut tries = 0;
    while out.len() < shape.robots {
        tries += 1;
        if tries > 100_000 || free.is_empty() {
            bail!("could not place {} robots on the map", shape.robots);
        }
        let s = free[rng.gen_range(0..free.len())];
        let g = free[rng.gen_range(0..free.len())];
        let taken = out
            .iter()
            .any(|&(a, b)| a == s || b == g || a == g || b == s);
        if taken || s == g {
            continue;
        }
        match octile_shortest_path_len(grid, s, g, CornerCutting::Forbidden) {
            Some(len) if len >= shape.min_len => {
                out.push((s, g));
                sum += len;
            }
            _ => {}
        }
    }
    Ok((out, sum))
}

/// A free cell between two walls, left and right or above and below: an aisle of one cell.
fn is_doorway(grid: &Grid, c: Cell) -> bool {
    let wall = |dx: i64, dy: i64| {
        let (x, y) = (i64::from(c.x) + dx, i64::from(c.y) + dy);
        let on = x >= 0 && y >= 0 && x < i64::from(grid.width()) && y < i64::from(grid.height());
        on && grid.is_blocked(Cell::new(x as u32, y as u32))
    };
    (wall(-1, 0) && wall(1, 0)) || (wall(0, -1) && wall(0, 1))
}

/// The longest run of free cells of row `y` none of which `avoid` holds, as (x0, x1).
fn longest_free_stretch(grid: &Grid, y: u32, avoid: &dyn Fn(Cell) -> bool) -> Option<(u32, u32)> {
    let (mut best, mut from): (Option<(u32, u32)>, Option<u32>) = (None, None);
    for x in 0..=grid.width() {
        let ok = x < grid.width() && {
            let c = Cell::new(x, y);
            !grid.is_blocked(c) && !avoid(c)
        };
        match (ok, from) {
            (true, None) => from = Some(x),
            (false, Some(x0)) => {
                let len = |r: (u32, u32)| r.1 - r.0;
                if best.is_none_or(|b| len(b) < x - 1 - x0) {
                    best = Some((x0, x - 1));
                }
                from = None;
            }
            _ => {}
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn a_drawn_world_has_its_doors_in_aisles_and_its_events_in_time_order() {
        let grid = super::super::mini_warehouse();
        let shape = Shape {
            robots: 6,
            doors: 2,
            walkers: 1,
            min_len: 8.0,
        };
        let w = draw(&grid, shape, &mut ChaCha8Rng::seed_from_u64(1)).unwrap();
        assert_eq!(w.robots.len(), 6);
        assert!(w.optimal_sum >= 6.0 * 8.0);
        let times: Vec<f64> = w
            .toml
            .lines()
            .filter_map(|l| l.strip_prefix("at_s = ")?.parse().ok())
            .collect();
        assert_eq!(times.len(), 1 + 2 * 2, "{}", w.toml);
        assert!(times.windows(2).all(|t| t[0] <= t[1]), "{times:?}");
        let again = draw(&grid, shape, &mut ChaCha8Rng::seed_from_u64(1)).unwrap();
        assert_eq!(again.toml, w.toml, "the same seed, the same world");
    }
}
