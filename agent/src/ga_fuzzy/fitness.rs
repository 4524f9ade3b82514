//! Seed 004's fitness functional `F = sum_k alpha_k S_k` (§B.3 of the notes; the equation
//! images are lost, only their descriptions survive).
//!
//! * `S1`, the length criterion: the route length with step `d = 1` to a horizontal or
//!   vertical neighbour and `d = sqrt 2` on a diagonal (the diagonal value is lost in the
//!   text: `sqrt 2` `\[inferred\]`, the centre-to-centre distance). A wait (the same cell
//!   twice) has `d = 0`. Normalised `\[inferred\]` as `octile(start, goal) / length`, so the
//!   straight line scores 1 and longer routes less.
//! * `S2`, the time criterion, uses `N_p`, the chromosome length: normalised `\[inferred\]` as
//!   `(chebyshev(start, goal) + 1) / N_p`, the fewest nodes any route needs over `N_p`. A
//!   route with waits is as short as without them but takes longer, which is what "choosing
//!   the route independently of the robot's speed along it" asks the pair to separate.
//! * `alpha_k = const in [0, 1]` (the seed); `0.5, 0.5` by default `\[inferred\]`.
//! * Collisions with the time layers are not in the seed (its operators presumably keep
//!   routes feasible); we divide `F` by `1 + conflicts` `\[inferred\]` so a colliding route can
//!   survive as a parent but never beats a clean one of similar quality.

use hnav_runtime::grid::Cell;

use super::time_grid::TimeGrid;
use crate::error::Error;

/// The step length `d(x_i, x_{i+1}, y_i, y_{i+1})`: 1 orthogonal, `sqrt 2` diagonal, 0 for a
/// wait; `None` for cells that are not 8-neighbours.
pub fn step_length(a: Cell, b: Cell) -> Option<f64> {
    match (a.x.abs_diff(b.x), a.y.abs_diff(b.y)) {
        (0, 0) => Some(0.0),
        (1, 0) | (0, 1) => Some(1.0),
        (1, 1) => Some(std::f64::consts::SQRT_2),
        _ => None,
    }
}

/// The length of a route (sum of [`step_length`]); `None` if two nodes are not neighbours.
pub fn route_length(route: &[Cell]) -> Option<f64> {
    route.windows(2).map(|w| step_length(w[0], w[1])).sum()
}

/// The weights `alpha_1` (length) and `alpha_2` (time).
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Weights {
    /// `alpha_1`, the length criterion's weight.
    pub length: f64,
    /// `alpha_2`, the time criterion's weight.
    pub time: f64,
}

impl Default for Weights {
    fn default() -> Self {
        Weights {
            length: 0.5,
            time: 0.5,
        }
    }
}

impl Weights {
    /// Checks `alpha_k in [0, 1]` (the seed's domain) and that not both are 0.
    pub fn validate(&self) -> Result<(), Error> {
        for (name, a) in [("alpha_length", self.length), ("alpha_time", self.time)] {
            if !(0.0..=1.0).contains(&a) {
                return Err(Error::option(name, format!("{a}: must be in [0, 1]")));
            }
        }
        if self.length + self.time == 0.0 {
            return Err(Error::option("alpha", "both weights are 0"));
        }
        Ok(())
    }
}

/// A scored route.
#[derive(Clone, Copy, PartialEq, Debug, Default)]
pub struct Score {
    /// `F`, larger is better.
    pub fitness: f64,
    /// `S1`.
    pub s_length: f64,
    /// `S2`.
    pub s_time: f64,
    /// Route length in cells.
    pub length: f64,
    /// Collisions with moving obstacles.
    pub conflicts: usize,
}

/// Scores `route` (start first, goal last, 8-neighbour steps) on `tg`.
pub fn score(route: &[Cell], tg: &TimeGrid, w: Weights) -> Score {
    let (Some(&s), Some(&g)) = (route.first(), route.last()) else {
        return Score::default();
    };
    let length = route_length(route).unwrap_or(f64::INFINITY);
    let best = s.octile(g);
    let s_length = if length > 0.0 { best / length } else { 1.0 };
    let cheb = s.x.abs_diff(g.x).max(s.y.abs_diff(g.y)) as f64;
    let s_time = (cheb + 1.0) / route.len() as f64;
    let conflicts = tg.conflicts(route);
    let fitness = (w.length * s_length + w.time * s_time) / (1 + conflicts) as f64;
    Score {
        fitness,
        s_length,
        s_time,
        length,
        conflicts,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::grid::{CornerCutting, Grid};

    #[test]
    fn step_lengths_are_the_seeds() {
        // The seed: d = 1 to a horizontal or vertical neighbour.
        assert_eq!(step_length(Cell::new(3, 3), Cell::new(4, 3)), Some(1.0));
        assert_eq!(step_length(Cell::new(3, 3), Cell::new(3, 2)), Some(1.0));
        // Lost in the text; sqrt 2 [inferred].
        assert_eq!(
            step_length(Cell::new(3, 3), Cell::new(2, 2)),
            Some(std::f64::consts::SQRT_2)
        );
        assert_eq!(step_length(Cell::new(3, 3), Cell::new(3, 3)), Some(0.0));
        assert_eq!(step_length(Cell::new(3, 3), Cell::new(5, 3)), None);
    }

    #[test]
    fn straight_routes_score_one_and_waits_cost_time_not_length() {
        let tg = TimeGrid::fixed(Grid::new(6, 6).unwrap(), CornerCutting::Forbidden, 20).unwrap();
        let straight: Vec<Cell> = (0..4).map(|x| Cell::new(x, 0)).collect();
        let s = score(&straight, &tg, Weights::default());
        assert_eq!(
            (s.s_length, s.s_time, s.fitness, s.length),
            (1.0, 1.0, 1.0, 3.0)
        );
        let mut wait = straight.clone();
        wait.insert(2, Cell::new(1, 0));
        let sw = score(&wait, &tg, Weights::default());
        assert_eq!((sw.s_length, sw.s_time), (1.0, 0.8));
        assert!(sw.fitness < s.fitness);
        // A detour costs length (and time).
        let detour = [
            Cell::new(0, 0),
            Cell::new(1, 1),
            Cell::new(2, 1),
            Cell::new(3, 0),
        ];
        let sd = score(&detour, &tg, Weights::default());
        assert!((sd.length - (1.0 + 2.0 * std::f64::consts::SQRT_2)).abs() < 1e-12);
        assert!(sd.s_length < 1.0 && sd.s_time == 1.0);
    }

    #[test]
    fn weights_outside_the_unit_interval_are_refused() {
        assert!(Weights::default().validate().is_ok());
        let bad = Weights {
            length: 1.5,
            time: 0.0,
        };
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("alpha_length"));
        assert!(Weights {
            length: 0.0,
            time: 0.0
        }
        .validate()
        .is_err());
        assert!(Weights {
            length: f64::NAN,
            time: 0.5
        }
        .validate()
        .is_err());
    }
}
