//! Terrain relief and hazard, after seed 002 (Hrytsenko 2024, "Lazy Theta* for s-bot motion
//! taking terrain relief into account").
//!
//! | module | concept |
//! |---|---|
//! | [`TerrainParams`], [`HazardWeights`] (here) | the limits and weights, with the thesis's defaults |
//! | [`relief`] | [`TerrainFactors`]: slope, roughness and relief amplitude per cell from a height map |
//! | [`hazard`] | [`HazardMap`]: the hazard index `R` per cell, the chord weight [`alpha`], route hazard `c` |
//!
//! # What is the thesis's and what is filled in
//!
//! Labels as in the seed notes: **\[thesis\]** is stated in the thesis, **\[inferred\]** is our
//! choice where the thesis is silent.
//!
//! * **\[thesis\]** A square grid of step `e` whose cells carry slope and height; vertices at
//!   cell centres, 8-connected. Default `e = 1 m` ([`TerrainParams::cell_size`]).
//! * **\[thesis\]** Three factors: slope angle, roughness = 3-D surface area / projected area,
//!   relief amplitude = max - min height along the motion. Limits: **30°** slope and
//!   **0.20 m** amplitude; a cell over either cannot be crossed. Both are configurable.
//! * **\[inferred\]** How the factors are computed from one height per cell: Horn's 3x3
//!   gradient for the slope, Jenness's eight-triangle surface-area ratio for the roughness,
//!   and for the amplitude the largest *step* along the four lines through the cell (the
//!   change of rise between the two halves of the line, so a steady slope adds nothing: it
//!   has its own limit). See [`relief`].
//! * **\[thesis\]** A hazard index `R(i, j)` per cell. **\[inferred\]** Its formula (the thesis has
//!   none): `R = inf` over a limit, else
//!   `(w_s * slope/max_slope + w_r * (rho - 1)/(rho_max - 1) + w_h * amplitude/max_amplitude)
//!   / (w_s + w_r + w_h)`, so `R` is in `[0, 1]` (default weights 0.4 / 0.2 / 0.4; roughness
//!   weighs less because on a height map it mostly repeats the slope). An optional roughness
//!   limit is off by default (the thesis gives none).
//! * **\[thesis\]** Route hazard `c = sum alpha * R` over the cells the route crosses, with
//!   `alpha = 1/2` if the route's chord in the cell is shorter than half a cell diagonal and
//!   `1` if longer (threshold printed as `sqrt2/(2e)`, read as `(sqrt2/2) e`). **\[inferred\]**:
//!   a chord equal to the threshold counts 1; the cells a route starts, ends or turns in
//!   count 1 (the robot stands in them; the thesis's worked example gives its start and goal
//!   cells weight 1); a cell touched only at a corner is not crossed; a cell crossed by two
//!   segments counts twice. See [`hazard`].
//! * **\[thesis\]** Evaluation `f = g + h + c` (eq. 3.1), `h` Euclidean. **\[inferred\]** To keep the
//!   search consistent, `c` is folded into the edge cost: a segment costs its length plus
//!   `lambda * (its share of c)`, with `lambda` ([`TerrainParams::hazard_weight`]) in metres
//!   per hazard unit, 1 by default, which is the thesis's sum taken literally.
//! * **\[inferred\]** A grid whose terrain layer is a *cost* layer (multipliers, see
//!   [`hnav_runtime::grid::TerrainKind::Cost`]) maps to `R = max(0, value - 1)`: crossing a
//!   whole cell then costs about `value` times its length, like the runtime defines it.

pub mod hazard;
pub mod relief;

pub use hazard::{alpha, HazardMap, ALPHA_THRESHOLD};
pub use relief::TerrainFactors;

use crate::error::PlanError;

/// How much each factor contributes to a passable cell's hazard index. \[inferred\]
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct HazardWeights {
    /// Weight of `slope / max_slope`.
    pub slope: f64,
    /// Weight of the normalised roughness `(rho - 1) / (rho_max - 1)`, capped at 1.
    pub roughness: f64,
    /// Weight of `amplitude / max_amplitude`.
    pub relief: f64,
}

impl Default for HazardWeights {
    fn default() -> Self {
        HazardWeights {
            slope: 0.4,
            roughness: 0.2,
            relief: 0.4,
        }
    }
}

/// Limits and weights of the terrain model; the defaults are the thesis's numbers.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct TerrainParams {
    /// Grid step `e` in metres (1.0). \[thesis\]
    pub cell_size: f64,
    /// Steepest passable slope in degrees (30). \[thesis\]
    pub max_slope_deg: f64,
    /// Highest passable relief amplitude in metres (0.20). \[thesis\]
    pub max_relief: f64,
    /// Roughest passable cell (surface-area ratio), or `None` for no limit (the default; the
    /// thesis gives none).
    pub max_roughness: Option<f64>,
    /// The roughness that counts as fully rough in `R`; `None` takes the roughness of a plane
    /// at the slope limit, `1 / cos(max_slope)` (1.1547 for 30°). \[inferred\]
    pub roughness_scale: Option<f64>,
    /// Weights of the factors in `R`. \[inferred\]
    pub weights: HazardWeights,
    /// `lambda`: metres of detour one unit of hazard is worth (1.0). \[inferred\]
    pub hazard_weight: f64,
}

impl Default for TerrainParams {
    fn default() -> Self {
        TerrainParams {
            cell_size: 1.0,
            max_slope_deg: 30.0,
            max_relief: 0.20,
            max_roughness: None,
            roughness_scale: None,
            weights: HazardWeights::default(),
            hazard_weight: 1.0,
        }
    }
}

impl TerrainParams {
    /// Checks that every number is finite and in range: positive cell size and limits,
    /// non-negative weights summing to more than 0, a roughness scale above 1.
    pub fn validate(&self) -> Result<(), PlanError> {
        let bad = |problem: String| Err(PlanError::BadTerrain { problem });
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let w = self.weights;
        if !positive(self.cell_size) {
            return bad(format!("cell size {} must be > 0", self.cell_size));
        }
        if !(positive(self.max_slope_deg) && self.max_slope_deg < 90.0) {
            return bad(format!(
                "slope limit {}° must be in (0, 90)",
                self.max_slope_deg
            ));
        }
        if !positive(self.max_relief) {
            return bad(format!("relief limit {} m must be > 0", self.max_relief));
        }
        if let Some(r) = self.max_roughness {
            if !(r.is_finite() && r >= 1.0) {
                return bad(format!("roughness limit {r} must be >= 1"));
            }
        }
        if let Some(r) = self.roughness_scale {
            if !(r.is_finite() && r > 1.0) {
                return bad(format!("roughness scale {r} must be > 1"));
            }
        }
        let ws = [w.slope, w.roughness, w.relief];
        if ws.iter().any(|v| !(v.is_finite() && *v >= 0.0)) || ws.iter().sum::<f64>() <= 0.0 {
            return bad(format!("hazard weights {w:?} must be >= 0, not all 0"));
        }
        if !(self.hazard_weight.is_finite() && self.hazard_weight >= 0.0) {
            return bad(format!("hazard weight {} must be >= 0", self.hazard_weight));
        }
        Ok(())
    }

    /// The roughness that counts as fully rough in `R`.
    pub fn roughness_scale(&self) -> f64 {
        self.roughness_scale
            .unwrap_or_else(|| 1.0 / self.max_slope_deg.to_radians().cos())
    }
}
