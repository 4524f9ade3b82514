//! The hazard index `R` per cell and the route hazard `c = sum alpha * R` (seed 002, eq. 3.2).
//!
//! # How a route's hazard is split over its segments
//!
//! The planners need an additive cost per segment. A segment `a -> b` between cell centres
//! gets `R(a)/2 + R(b)/2 + sum alpha(chord) * R` over the cells it crosses strictly between
//! `a` and `b` (cells it only touches at a corner are not crossed). Summed over a route, each
//! waypoint the route turns in collects two halves, i.e. weight 1, which is also what the
//! thesis's rule gives it (its chord is two half-segments of at least 1/2 each, over the
//! threshold), and the start and goal collect one half each. [`HazardMap::route_hazard`] adds
//! the missing halves of the start and goal, so it reports the thesis's `c` with weight 1 on
//! the cells the robot stands in; the planners can leave them out because every route of a
//! query shares them.
//!
//! Worked example (the thesis's Fig. 3.1, see the tests): a route from the centre of cell
//! (1,1) to (3,2) and on to (4,3) (1-based column, row) crosses (2,1) and (2,2) with chords of
//! 0.56 each, so `c = R(1,1) + (R(2,1) + R(2,2))/2 + R(3,2) + R(4,3)`, as printed.

use hnav_runtime::grid::{Cell, CornerCutting, Grid, TerrainKind};

use super::params::TerrainParams;
use super::relief::TerrainFactors;
use crate::error::PlanError;
use crate::line_of_sight::{euclid, walk};

/// The chord length (in cells) below which a crossed cell counts half: half a cell diagonal,
/// `sqrt 2 / 2`, i.e. `(sqrt 2 / 2) e` in metres. \[thesis, threshold read dimensionally\]
pub const ALPHA_THRESHOLD: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// The weight `alpha` of a crossed cell from the route's chord in it, in cell units: 1/2 below
/// [`ALPHA_THRESHOLD`], 1 from it on (the thesis leaves equality open; we count it whole).
#[inline]
pub fn alpha(chord: f64) -> f64 {
    if chord < ALPHA_THRESHOLD {
        0.5
    } else {
        1.0
    }
}

/// Hazard of the segment `a -> b` as the planners count it (end cells half, crossed cells by
/// `alpha`), walking the cells; `None` if a crossed cell is blocked or a corner crossing
/// breaks `rule`. `r` is indexed like a grid of the given `width`.
#[inline]
pub(crate) fn walk_hazard(
    width: usize,
    r: &[f32],
    a: Cell,
    b: Cell,
    rule: CornerCutting,
    blocked: impl Fn(usize) -> bool,
) -> Option<f64> {
    let len = euclid(a, b);
    let (ia, ib) = (
        a.y as usize * width + a.x as usize,
        b.y as usize * width + b.x as usize,
    );
    let mut sum = 0.0;
    let clear = walk::<true>(width, a, b, rule, blocked, |i, t_in, t_out| {
        let weight = if i == ia || i == ib {
            0.5
        } else {
            alpha((t_out - t_in) * len)
        };
        sum += weight * f64::from(r[i]);
    });
    clear.then_some(sum)
}

/// The hazard index `R` of every cell (`>= 0`, infinite for impassable cells) and the weight
/// that turns hazard into cost.
#[derive(Clone, PartialEq, Debug)]
pub struct HazardMap {
    width: u32,
    height: u32,
    values: Vec<f32>,
    impassable: Vec<bool>,
    weight: f64,
}

impl HazardMap {
    /// A map from raw values: finite and `>= 0`, or `f32::INFINITY` for an impassable cell.
    /// `weight` is the cost, in cell lengths, of one unit of hazard (`lambda / e`).
    pub fn new(width: u32, height: u32, values: Vec<f32>, weight: f64) -> Result<Self, PlanError> {
        let bad = |problem: String| Err(PlanError::BadTerrain { problem });
        if width == 0 || height == 0 || values.len() != width as usize * height as usize {
            return bad(format!(
                "{} hazard values for a {width}x{height} map",
                values.len()
            ));
        }
        if let Some(i) = values.iter().position(|v| v.is_nan() || *v < 0.0) {
            return bad(format!("hazard {} at index {i} is not >= 0", values[i]));
        }
        if !(weight.is_finite() && weight >= 0.0) {
            return bad(format!("hazard weight {weight} must be >= 0"));
        }
        let impassable = values.iter().map(|v| v.is_infinite()).collect();
        Ok(HazardMap {
            width,
            height,
            values,
            impassable,
            weight,
        })
    }

    /// `R` from terrain factors: infinite over a limit, else the weighted sum of the
    /// normalised factors (see the [module docs](super)).
    pub fn from_factors(
        factors: &TerrainFactors,
        params: &TerrainParams,
    ) -> Result<Self, PlanError> {
        params.validate()?;
        let w = params.weights;
        let wsum = w.slope + w.roughness + w.relief;
        let rho_span = params.roughness_scale() - 1.0;
        let values = factors
            .slope_deg()
            .iter()
            .zip(factors.roughness())
            .zip(factors.relief())
            .map(|((&slope, &rho), &relief)| {
                let too_rough = params.max_roughness.is_some_and(|m| rho > m);
                if slope > params.max_slope_deg || relief > params.max_relief || too_rough {
                    return f32::INFINITY;
                }
                let r = w.slope * slope / params.max_slope_deg
                    + w.roughness * ((rho - 1.0) / rho_span).clamp(0.0, 1.0)
                    + w.relief * relief / params.max_relief;
                (r / wsum) as f32
            })
            .collect();
        Self::new(
            factors.width(),
            factors.height(),
            values,
            params.hazard_weight / params.cell_size,
        )
    }

    /// `R` from a height map (one height per cell, metres).
    pub fn from_heights(
        width: u32,
        height: u32,
        heights: &[f32],
        params: &TerrainParams,
    ) -> Result<Self, PlanError> {
        params.validate()?;
        let f = TerrainFactors::from_heights(width, height, heights, params.cell_size)?;
        Self::from_factors(&f, params)
    }

    /// `R` from a grid's terrain layer: an elevation layer goes through the terrain factors,
    /// a cost layer of multipliers `m` becomes `R = max(0, m - 1)`.
    pub fn from_grid(grid: &Grid, params: &TerrainParams) -> Result<Self, PlanError> {
        params.validate()?;
        let Some(t) = grid.terrain() else {
            return Err(PlanError::BadTerrain {
                problem: "the grid has no terrain layer".into(),
            });
        };
        match t.kind() {
            TerrainKind::Elevation => {
                Self::from_heights(grid.width(), grid.height(), t.values(), params)
            }
            TerrainKind::Cost => Self::new(
                grid.width(),
                grid.height(),
                t.values().iter().map(|m| (m - 1.0).max(0.0)).collect(),
                params.hazard_weight / params.cell_size,
            ),
        }
    }

    /// Map width in cells.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Map height in cells.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// `R` per cell, row-major (infinite = impassable).
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// Impassable flags per cell, row-major.
    pub fn impassable(&self) -> &[bool] {
        &self.impassable
    }

    /// Cost (cell lengths) of one unit of hazard.
    pub fn weight(&self) -> f64 {
        self.weight
    }

    /// The same map with another weight (`0` turns hazard off but keeps impassable cells).
    pub fn with_weight(mut self, weight: f64) -> Result<Self, PlanError> {
        if !(weight.is_finite() && weight >= 0.0) {
            return Err(PlanError::BadTerrain {
                problem: format!("hazard weight {weight} must be >= 0"),
            });
        }
        self.weight = weight;
        Ok(self)
    }

    fn checked_index(&self, c: Cell) -> Option<usize> {
        (c.x < self.width && c.y < self.height)
            .then(|| c.y as usize * self.width as usize + c.x as usize)
    }

    /// `R` of a cell, `None` outside the map.
    pub fn hazard(&self, c: Cell) -> Option<f32> {
        self.checked_index(c).map(|i| self.values[i])
    }

    /// Whether a cell is impassable (outside counts as impassable).
    pub fn is_impassable(&self, c: Cell) -> bool {
        self.checked_index(c).is_none_or(|i| self.impassable[i])
    }

    /// Number of impassable cells.
    pub fn impassable_count(&self) -> usize {
        self.impassable.iter().filter(|&&b| b).count()
    }

    /// The route hazard `c` of a polyline through cell centres (thesis eq. 3.2): crossed
    /// cells weighted by [`alpha`] of their chord, cells the route starts, ends or turns in
    /// weighted 1. Obstacles are not checked. `None` if a cell is outside the map or the
    /// list is empty; infinite if the route touches impassable terrain.
    pub fn route_hazard(&self, cells: &[Cell]) -> Option<f64> {
        let (first, last) = (*cells.first()?, *cells.last()?);
        let mut sum = 0.0;
        for &c in cells {
            self.checked_index(c)?;
        }
        if cells.len() == 1 {
            return Some(f64::from(self.values[self.checked_index(first)?]));
        }
        for w in cells.windows(2) {
            sum += walk_hazard(
                self.width as usize,
                &self.values,
                w[0],
                w[1],
                CornerCutting::Allowed,
                |_| false,
            )?;
        }
        let end = |c: Cell| {
            self.checked_index(c)
                .map(|i| 0.5 * f64::from(self.values[i]))
        };
        Some(sum + end(first)? + end(last)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alpha_rule() {
        assert_eq!(alpha(0.1), 0.5);
        assert_eq!(alpha(0.70), 0.5);
        assert_eq!(alpha(ALPHA_THRESHOLD), 1.0);
        assert_eq!(alpha(0.75), 1.0);
        assert!((ALPHA_THRESHOLD - 2f64.sqrt() / 2.0).abs() < 1e-15);
    }

    /// The thesis's worked example on a 4x3 grid with distinct `R` values.
    #[test]
    fn thesis_worked_example() {
        // R(i, j) = 10 i + j with i the 1-based column and j the 1-based row, so every cell
        // is distinguishable in the sum.
        let values: Vec<f32> = (1..=3)
            .flat_map(|j| (1..=4).map(move |i| (10 * i + j) as f32))
            .collect();
        let hz = HazardMap::new(4, 3, values, 1.0).unwrap();
        let r = |i: u32, j: u32| f64::from(hz.hazard(Cell::new(i - 1, j - 1)).unwrap());
        // (1,1) -> (3,2) -> (4,3), 0-based.
        let route = [Cell::new(0, 0), Cell::new(2, 1), Cell::new(3, 2)];
        let c = hz.route_hazard(&route).unwrap();
        let want = r(1, 1) + 0.5 * (r(2, 1) + r(2, 2)) + r(3, 2) + r(4, 3);
        assert!((c - want).abs() < 1e-9, "{c} vs {want}");
        // The diagonal (3,2) -> (4,3) only touches (4,2) and (3,3) at a corner: not counted.
    }

    #[test]
    fn straight_route_counts_every_cell_once() {
        let hz = HazardMap::new(5, 1, vec![1.0, 2.0, 4.0, 8.0, 16.0], 1.0).unwrap();
        let c = hz
            .route_hazard(&[Cell::new(0, 0), Cell::new(4, 0)])
            .unwrap();
        assert_eq!(c, 31.0);
        // Turning in the middle does not change it.
        let c = hz
            .route_hazard(&[Cell::new(0, 0), Cell::new(2, 0), Cell::new(4, 0)])
            .unwrap();
        assert_eq!(c, 31.0);
        assert_eq!(hz.route_hazard(&[Cell::new(3, 0)]), Some(8.0));
        assert_eq!(hz.route_hazard(&[Cell::new(5, 0)]), None);
        assert_eq!(hz.route_hazard(&[]), None);
    }

    #[test]
    fn limits_make_cells_impassable() {
        // A 0.3 m step between columns 2 and 3 (over the 0.20 m limit).
        let step: Vec<f32> = (0..25)
            .map(|i| if i % 5 >= 3 { 0.3 } else { 0.0 })
            .collect();
        let hz = HazardMap::from_heights(5, 5, &step, &TerrainParams::default()).unwrap();
        assert!(hz.is_impassable(Cell::new(2, 2)) && hz.is_impassable(Cell::new(3, 2)));
        assert!(!hz.is_impassable(Cell::new(0, 2)));
        // The same step at 0.15 m passes (its slope of about 8.5 degrees too).
        let low: Vec<f32> = step.iter().map(|h| h / 2.0).collect();
        let hz = HazardMap::from_heights(5, 5, &low, &TerrainParams::default()).unwrap();
        assert_eq!(hz.impassable_count(), 0);
        // A configurable limit: 0.10 m makes it impassable again.
        let strict = TerrainParams {
            max_relief: 0.10,
            ..TerrainParams::default()
        };
        let hz = HazardMap::from_heights(5, 5, &low, &strict).unwrap();
        assert!(hz.is_impassable(Cell::new(2, 2)));
    }

    #[test]
    fn slope_limit_and_roughness_limit() {
        // Planes of 25 and 35 degrees along x (cell size 0.5 m).
        let plane = |deg: f64| -> Vec<f32> {
            let rise = deg.to_radians().tan() * 0.5;
            (0..49).map(|i| ((i % 7) as f64 * rise) as f32).collect()
        };
        let params = TerrainParams {
            cell_size: 0.5,
            ..TerrainParams::default()
        };
        let centre = Cell::new(3, 3);
        let gentle = HazardMap::from_heights(7, 7, &plane(25.0), &params).unwrap();
        let steep = HazardMap::from_heights(7, 7, &plane(35.0), &params).unwrap();
        assert!(!gentle.is_impassable(centre));
        assert!(steep.is_impassable(centre));
        // R grows with the slope: 25/30 of the slope weight plus the roughness term.
        let r = f64::from(gentle.hazard(centre).unwrap());
        assert!(r > 0.4 * 25.0 / 30.0 && r < 1.0, "{r}");
        // A roughness limit below 1/cos(25) blocks the gentle plane too.
        let rough = TerrainParams {
            max_roughness: Some(1.05),
            ..params
        };
        let hz = HazardMap::from_heights(7, 7, &plane(25.0), &rough).unwrap();
        assert!(hz.is_impassable(centre));
    }

    #[test]
    fn bad_values_and_params() {
        assert!(HazardMap::new(2, 1, vec![0.0, -1.0], 1.0).is_err());
        assert!(HazardMap::new(2, 1, vec![0.0, f32::NAN], 1.0).is_err());
        assert!(HazardMap::new(2, 1, vec![0.0], 1.0).is_err());
        assert!(HazardMap::new(2, 1, vec![0.0, 1.0], -1.0).is_err());
        let p = TerrainParams {
            max_slope_deg: 95.0,
            ..TerrainParams::default()
        };
        assert!(HazardMap::from_heights(1, 1, &[0.0], &p).is_err());
        let g = Grid::new(2, 2).unwrap();
        assert!(HazardMap::from_grid(&g, &TerrainParams::default()).is_err());
    }

    #[test]
    fn cost_layer_maps_to_excess_multiplier() {
        use hnav_runtime::grid::Terrain;
        let mut g = Grid::new(3, 1).unwrap();
        let t = Terrain::new(TerrainKind::Cost, vec![1.0, 3.0, 0.5]).unwrap();
        g.set_terrain(Some(t)).unwrap();
        let hz = HazardMap::from_grid(&g, &TerrainParams::default()).unwrap();
        assert_eq!(hz.values(), &[0.0, 2.0, 0.0]);
    }
}
