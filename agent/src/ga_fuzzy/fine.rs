//! The switch between the coarse and the fine route at the coarse route's nodal points (seed
//! 004 §B.4: "the rule-base search runs at the nodal points of the coarse trajectory; if the
//! route found between nodal points is shorter than the distance along the coarse
//! trajectory, the robot follows the found route").
//!
//! The route "found" is the fuzzy controller's own: from a nodal point the robot is steered by
//! [`FuzzyRules`] towards a later nodal point, one grid move per step (its heading snapped to
//! the nearest of the eight directions, the free areas `A` read from the grid up to
//! [`SENSOR_CELLS`] cells). If it gets there along a shorter legal chain, that chain replaces
//! the coarse stretch. Filled in `\[inferred\]`: every node is a nodal point, the farthest
//! nodal point tried is [`LOOKAHEAD`] nodes ahead, the sensor range, and (with moving
//! obstacles) that a switch may not add a collision.

use hnav_runtime::grid::{Cell, Direction};

use super::fitness::route_length;
use super::fuzzy::{direction_angle, nearest_direction, FuzzyRules, DIRECTIONS};
use super::time_grid::TimeGrid;

/// Sensor range of the free areas, in cells `\[inferred\]`.
pub const SENSOR_CELLS: usize = 3;

/// How many nodes ahead the farthest nodal point tried lies `\[inferred\]`.
pub const LOOKAHEAD: usize = 10;

/// Free areas of `cell` in the eight directions: free cells in a row (legal moves under the
/// corner rule) up to [`SENSOR_CELLS`], over the range.
pub fn free_areas(tg: &TimeGrid, cell: Cell) -> [f64; DIRECTIONS] {
    let mut free = [0.0; DIRECTIONS];
    for (k, f) in free.iter_mut().enumerate() {
        let Some(dir) = Direction::from_index(k) else {
            continue;
        };
        let mut c = cell;
        let mut n = 0;
        while n < SENSOR_CELLS && tg.grid().can_move(c, dir, tg.rule()) {
            c = tg.grid().step(c, dir).unwrap_or(c);
            n += 1;
        }
        *f = n as f64 / SENSOR_CELLS as f64;
    }
    free
}

/// Steers from `from` to `to` with the fuzzy rules, at most `max_moves` moves, heading first
/// `heading`; the chain (both ends) in `out`. `false` if the robot does not get there (a
/// blocked move, or out of moves).
pub fn fuzzy_rollout(
    tg: &TimeGrid,
    rules: &FuzzyRules,
    from: Cell,
    to: Cell,
    heading: f64,
    max_moves: usize,
    out: &mut Vec<Cell>,
) -> bool {
    out.clear();
    out.push(from);
    let (mut c, mut h) = (from, heading);
    // Turning in place takes no move; bound the decisions as well as the moves.
    for _ in 0..4 * max_moves + 4 {
        if c == to {
            return true;
        }
        if out.len() > max_moves {
            return false;
        }
        let bearing = (f64::from(to.y) - f64::from(c.y)).atan2(f64::from(to.x) - f64::from(c.x));
        let o = rules.infer(&free_areas(tg, c), h, bearing);
        h += o.turn;
        if o.speed <= 0.0 {
            continue;
        }
        let k = nearest_direction(h);
        let Some(dir) = Direction::from_index(k) else {
            return false;
        };
        if !tg.grid().can_move(c, dir, tg.rule()) {
            return false;
        }
        c = tg.grid().step(c, dir).unwrap_or(c);
        h = direction_angle(k);
        out.push(c);
    }
    c == to
}

/// Applies the switch along `route` in place; returns how many stretches were replaced.
pub fn refine(
    tg: &TimeGrid,
    rules: &FuzzyRules,
    route: &mut Vec<Cell>,
    fine: &mut Vec<Cell>,
    trial: &mut Vec<Cell>,
) -> usize {
    let mut switched = 0;
    let mut i = 0;
    while i + 2 < route.len() {
        let last = (i + LOOKAHEAD).min(route.len() - 1);
        let heading = heading_of(route[i], route[i + 1]);
        for j in (i + 2..=last).rev() {
            let coarse = route_length(&route[i..=j]).unwrap_or(f64::INFINITY);
            if !fuzzy_rollout(tg, rules, route[i], route[j], heading, j - i, fine) {
                continue;
            }
            let found = route_length(fine).unwrap_or(f64::INFINITY);
            if found + 1e-9 >= coarse {
                continue;
            }
            trial.clear();
            trial.extend_from_slice(&route[..i]);
            trial.extend_from_slice(fine);
            trial.extend_from_slice(&route[j + 1..]);
            if tg.conflicts(trial) <= tg.conflicts(route) {
                std::mem::swap(route, trial);
                switched += 1;
                break;
            }
        }
        i += 1;
    }
    switched
}

fn heading_of(a: Cell, b: Cell) -> f64 {
    Direction::between(a, b).map_or(0.0, |d| direction_angle(d.index()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ga_fuzzy::chromosome::is_legal;
    use hnav_runtime::grid::{CornerCutting, Grid};

    #[test]
    fn a_detour_in_open_space_is_straightened() {
        let tg = TimeGrid::fixed(Grid::new(8, 5).unwrap(), CornerCutting::Forbidden, 64).unwrap();
        let c = Cell::new;
        // A zig-zag along row 2.
        let mut route = vec![
            c(0, 2),
            c(1, 1),
            c(2, 2),
            c(3, 3),
            c(4, 2),
            c(5, 1),
            c(6, 2),
        ];
        let before = route_length(&route).unwrap();
        let n = refine(
            &tg,
            &FuzzyRules::default(),
            &mut route,
            &mut Vec::new(),
            &mut Vec::new(),
        );
        assert!(n >= 1);
        assert!(is_legal(&tg, &route) && route[0] == c(0, 2) && *route.last().unwrap() == c(6, 2));
        assert!(route_length(&route).unwrap() < before);
        assert_eq!(route_length(&route).unwrap(), 6.0, "{route:?}");
    }

    #[test]
    fn the_rollout_never_crosses_a_wall() {
        let g = Grid::from_rows(&["......", "..@...", "..@...", "......"]).unwrap();
        let tg = TimeGrid::fixed(g, CornerCutting::Forbidden, 64).unwrap();
        let mut out = Vec::new();
        let ok = fuzzy_rollout(
            &tg,
            &FuzzyRules::default(),
            Cell::new(0, 1),
            Cell::new(5, 2),
            0.0,
            12,
            &mut out,
        );
        if ok {
            assert!(is_legal(&tg, &out), "{out:?}");
        }
        assert_eq!(free_areas(&tg, Cell::new(1, 1))[2], 0.0);
    }
}
