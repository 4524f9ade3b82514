//! One planning query: build a neural map towards the goal and climb it from the start. This
//! is what `hnav-bench plan` calls; the answer is the runtime's [`PlanResult`], the type every
//! planner answers with, and serialises to the bench's JSON line (`planner`, `found`, `steps`,
//! `length`, `iterations`, `path` as `[x, y]` pairs, `time_us`).
//!
//! The corner rule applies to both halves: with [`CornerCutting::Forbidden`] (MovingAI's rule)
//! no diagonal link passes a blocked corner, in propagation or in the path; with
//! [`CornerCutting::Allowed`] every diagonal exists, as in the dissertation's reproductions.

use std::time::Instant;

use hnav_runtime::grid::{Cell, CornerCutting, Grid};
use hnav_runtime::plan::PlanResult;
use serde::{Deserialize, Serialize};

use crate::error::{check_inside, Error, Role};
use crate::neural_map::{
    Activation, NeuralDynamics, NeuralMap, NeuralMapOptions, Outcome, StopRule, Weights,
};
use crate::path_constructor::{PathConstructor, PathOptions};

/// When the map of a query stops growing.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlanStop {
    /// Every reachable neuron is on (Fig. 2-18a).
    Full,
    /// The start's neuron is on (Fig. 2-18b, Appendix A): fewer sweeps, same ascent.
    #[default]
    Partial,
}

/// The options of a query.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct PlanOptions {
    /// The activation function.
    pub activation: Activation,
    /// The stop rule.
    pub stop: PlanStop,
    /// Whether diagonals may pass blocked corners, in propagation and in the path.
    pub corner_cutting: CornerCutting,
}

impl PlanOptions {
    /// The neural-map options a query runs with: the activation and corner rule asked for,
    /// Appendix A's denominator, seed 001's self weight 1 and the wave-front on-threshold.
    ///
    /// Of the documented variants this pair gives the shortest paths on random maps (the
    /// `path_quality` example: 2000 maps of 8..64 cells a side with 0-30 % obstacles, corner
    /// cutting forbidden, partial activation, tanh: 82 % optimal, path length / octile
    /// shortest mean 1.005, p95 1.037, max 1.11; with Chapter 2's obstacles-as-zeros
    /// denominator instead 67 %, 1.016, 1.078, 1.24). Both are in the dissertation's family:
    /// eq. 3.3 with Appendix A's averaging and seed 001's self-connection.
    pub fn map_options(&self) -> NeuralMapOptions {
        NeuralMapOptions {
            activation: self.activation,
            diagonals: self.corner_cutting.into(),
            weights: Weights {
                self_weight: 1.0,
                ..Weights::default()
            },
            ..NeuralMapOptions::default()
        }
    }
}

/// A planner for many queries on one grid: the map's buffers are allocated once.
#[derive(Clone, Debug)]
pub struct Planner {
    map: NeuralMap,
    stop: PlanStop,
    path: PathConstructor,
}

impl Planner {
    /// A planner for `grid`.
    pub fn new(grid: &Grid, options: &PlanOptions) -> Result<Planner, Error> {
        Self::with_options(
            grid,
            options.map_options(),
            options.stop,
            PathOptions::default(),
        )
    }

    /// A planner with every option of the map and the path constructor.
    pub fn with_options(
        grid: &Grid,
        map: NeuralMapOptions,
        stop: PlanStop,
        path: PathOptions,
    ) -> Result<Planner, Error> {
        Ok(Planner {
            map: NeuralMap::new(grid, map)?,
            stop,
            path: PathConstructor::new(path)?,
        })
    }

    /// The map of the last query.
    pub fn map(&self) -> &NeuralMap {
        &self.map
    }

    /// Plans from `start` to `goal`; `time_us` covers the map build and the path. The answer's
    /// planner is `"hnav"` and its iterations are the map's sweeps.
    pub fn query(&mut self, start: Cell, goal: Cell) -> Result<PlanResult, Error> {
        let t0 = Instant::now();
        let (w, h) = (
            crate::neural_map::ActivationField::width(&self.map),
            crate::neural_map::ActivationField::height(&self.map),
        );
        check_inside(start, Role::Start, w, h)?;
        check_inside(goal, Role::Goal, w, h)?;
        for (cell, role) in [(start, Role::Start), (goal, Role::Goal)] {
            if crate::neural_map::ActivationField::is_blocked(&self.map, cell) {
                return Err(Error::Blocked { role, cell });
            }
        }
        let stop = match self.stop {
            PlanStop::Full => StopRule::FullActivation,
            PlanStop::Partial => StopRule::PartialActivation { start },
        };
        let report = self.map.build(goal, stop)?;
        let mut result = PlanResult {
            planner: "hnav".to_string(),
            found: false,
            steps: 0,
            length: 0.0,
            iterations: u64::from(report.sweeps),
            path: Vec::new(),
            time_us: 0.0,
            los_checks: None,
            optimal: None,
        };
        if !matches!(report.outcome, Outcome::Unreachable | Outcome::SweepLimit) {
            let path = self.path.trace(&self.map, start)?;
            if path.reached() {
                result.found = true;
                result.steps = path.steps;
                result.length = path.length;
                result.path = path.cells;
            }
        }
        result.time_us = t0.elapsed().as_secs_f64() * 1e6;
        Ok(result)
    }
}

/// Plans one query on `grid` from `start` to `goal`. `time_us` covers everything, including
/// allocating the map; use [`Planner`] to amortise that over many queries.
pub fn plan_query(
    grid: &Grid,
    start: Cell,
    goal: Cell,
    options: &PlanOptions,
) -> Result<PlanResult, Error> {
    let t0 = Instant::now();
    let mut planner = Planner::new(grid, options)?;
    let mut result = planner.query(start, goal)?;
    result.time_us = t0.elapsed().as_secs_f64() * 1e6;
    Ok(result)
}
