//! The terrain model's limits and weights ([`TerrainParams`]), the thesis's numbers by default.

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
