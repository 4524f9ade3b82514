//! Terrain factors from a height map: slope, roughness and relief amplitude per cell.
//!
//! Input: one height per cell, in metres, sampled at the cell centre (the runtime's
//! [`TerrainKind::Elevation`] layer), and the cell size `e`. Every factor of a cell is
//! computed from its 3x3 neighbourhood; at the map border missing neighbours take the
//! centre's height (the map is extended flat), which is the usual GIS edge treatment.
//!
//! * **Slope** (degrees): Horn's (1981) weighted 3x3 gradient, as `gdaldem slope` computes it,
//!   `atan(|grad h|)`. \[inferred method\]
//! * **Roughness**: the surface-area ratio of Jenness (2004): the eight triangles joining the
//!   centre to each pair of adjacent neighbours, each cut to the part inside the cell (a
//!   quarter of its area), summed and divided by `e^2`. It is `>= 1`, `1` on a flat cell and
//!   `1 / cos(slope)` on an inclined plane: exactly the thesis's definition, 3-D area over
//!   projected area. \[thesis definition, inferred method\]
//! * **Relief amplitude** (metres): along each of the four lines through the cell (W-E, N-S
//!   and the two diagonals) with neighbours `p`, `n` on both sides, the change of rise
//!   `| |h(n) - h(c)| - |h(c) - h(p)| |`; the largest over the lines. A steady slope (equal
//!   rises) gives 0 (the slope limit handles it), a step of height `H` between two cells
//!   gives `H` on both of them, a ledge on a slope gives the ledge. Lines that leave the map
//!   are skipped, so a cell on the border only sees steps parallel to the border; its inner
//!   neighbour sees the others. [inferred: the thesis's "max - min height along the motion",
//!   with the steady slope removed because one height per cell cannot tell a step from a
//!   slope otherwise]
//!
//! A single height per cell cannot show obstacles smaller than a cell; feed a finer grid (a
//! smaller `e`) when the robot's 0.20 m step matters at that scale.

use hnav_runtime::grid::{Grid, TerrainKind};

use crate::error::PlanError;

/// Slope, roughness and relief amplitude of every cell, row-major like the grid.
#[derive(Clone, PartialEq, Debug)]
pub struct TerrainFactors {
    width: u32,
    height: u32,
    slope_deg: Vec<f64>,
    roughness: Vec<f64>,
    relief: Vec<f64>,
}

impl TerrainFactors {
    /// Computes the factors of a `width x height` height map (`heights.len()` must be
    /// `width * height`, values finite) with cell size `cell_size` metres.
    pub fn from_heights(
        width: u32,
        height: u32,
        heights: &[f32],
        cell_size: f64,
    ) -> Result<TerrainFactors, PlanError> {
        let n = width as usize * height as usize;
        let bad = |problem: String| Err(PlanError::BadTerrain { problem });
        if n == 0 || heights.len() != n {
            return bad(format!(
                "{} heights for a {width}x{height} map",
                heights.len()
            ));
        }
        if let Some(i) = heights.iter().position(|h| !h.is_finite()) {
            return bad(format!("height {} at index {i} is not finite", heights[i]));
        }
        if !(cell_size.is_finite() && cell_size > 0.0) {
            return bad(format!("cell size {cell_size} must be > 0"));
        }
        let (w, h) = (width as i64, height as i64);
        let mut out = TerrainFactors {
            width,
            height,
            slope_deg: Vec::with_capacity(n),
            roughness: Vec::with_capacity(n),
            relief: Vec::with_capacity(n),
        };
        for y in 0..h {
            for x in 0..w {
                // z[dy + 1][dx + 1]: the 3x3 window, border cells extended flat.
                let centre = f64::from(heights[(y * w + x) as usize]);
                let mut z = [[centre; 3]; 3];
                let mut inside = [[false; 3]; 3];
                for (dy, row) in (-1..=1_i64).zip(z.iter_mut()) {
                    for (dx, v) in (-1..=1_i64).zip(row.iter_mut()) {
                        let (nx, ny) = (x + dx, y + dy);
                        if (0..w).contains(&nx) && (0..h).contains(&ny) {
                            *v = f64::from(heights[(ny * w + nx) as usize]);
                            inside[(dy + 1) as usize][(dx + 1) as usize] = true;
                        }
                    }
                }
                out.slope_deg.push(horn_slope_deg(&z, cell_size));
                out.roughness.push(surface_ratio(&z, cell_size));
                out.relief.push(step_amplitude(&z, &inside));
            }
        }
        Ok(out)
    }

    /// The factors of a grid's elevation layer.
    pub fn from_grid(grid: &Grid, cell_size: f64) -> Result<TerrainFactors, PlanError> {
        match grid.terrain() {
            Some(t) if t.kind() == TerrainKind::Elevation => {
                Self::from_heights(grid.width(), grid.height(), t.values(), cell_size)
            }
            Some(_) => Err(PlanError::BadTerrain {
                problem: "the grid's terrain layer holds costs, not elevations".into(),
            }),
            None => Err(PlanError::BadTerrain {
                problem: "the grid has no terrain layer".into(),
            }),
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

    /// Slope per cell, degrees.
    pub fn slope_deg(&self) -> &[f64] {
        &self.slope_deg
    }

    /// Roughness (surface-area ratio, `>= 1`) per cell.
    pub fn roughness(&self) -> &[f64] {
        &self.roughness
    }

    /// Relief amplitude per cell, metres.
    pub fn relief(&self) -> &[f64] {
        &self.relief
    }
}

/// Horn's gradient of a 3x3 window, as a slope angle in degrees.
fn horn_slope_deg(z: &[[f64; 3]; 3], e: f64) -> f64 {
    let dzdx =
        ((z[0][2] + 2.0 * z[1][2] + z[2][2]) - (z[0][0] + 2.0 * z[1][0] + z[2][0])) / (8.0 * e);
    let dzdy =
        ((z[2][0] + 2.0 * z[2][1] + z[2][2]) - (z[0][0] + 2.0 * z[0][1] + z[0][2])) / (8.0 * e);
    dzdx.hypot(dzdy).atan().to_degrees()
}

/// Jenness's surface-area ratio of the centre cell of a 3x3 window.
fn surface_ratio(z: &[[f64; 3]; 3], e: f64) -> f64 {
    // The eight neighbours in ring order, as (dx, dy) offsets.
    const RING: [(i64, i64); 8] = [
        (-1, -1),
        (0, -1),
        (1, -1),
        (1, 0),
        (1, 1),
        (0, 1),
        (-1, 1),
        (-1, 0),
    ];
    let point = |(dx, dy): (i64, i64)| {
        [
            dx as f64 * e,
            dy as f64 * e,
            z[(dy + 1) as usize][(dx + 1) as usize],
        ]
    };
    let c = point((0, 0));
    let mut area = 0.0;
    for k in 0..8 {
        let a = point(RING[k]);
        let b = point(RING[(k + 1) % 8]);
        let u = [a[0] - c[0], a[1] - c[1], a[2] - c[2]];
        let v = [b[0] - c[0], b[1] - c[1], b[2] - c[2]];
        let cross = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        let tri = 0.5 * (cross[0].powi(2) + cross[1].powi(2) + cross[2].powi(2)).sqrt();
        // Halving both legs keeps a quarter of the triangle, the part inside the cell.
        area += tri / 4.0;
    }
    area / (e * e)
}

/// The largest change of rise along the four lines through the centre of a 3x3 window.
fn step_amplitude(z: &[[f64; 3]; 3], inside: &[[bool; 3]; 3]) -> f64 {
    // (dx, dy) of one side of each line; the other side is the opposite offset.
    const LINES: [(i64, i64); 4] = [(1, 0), (0, 1), (1, 1), (1, -1)];
    let at = |dx: i64, dy: i64| ((dy + 1) as usize, (dx + 1) as usize);
    let c = z[1][1];
    let mut best: f64 = 0.0;
    for (dx, dy) in LINES {
        let (p, n) = (at(-dx, -dy), at(dx, dy));
        if !(inside[p.0][p.1] && inside[n.0][n.1]) {
            continue;
        }
        let rise_in = (c - z[p.0][p.1]).abs();
        let rise_out = (z[n.0][n.1] - c).abs();
        best = best.max((rise_out - rise_in).abs());
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(w: u32, h: u32, gx: f64, gy: f64) -> Vec<f32> {
        (0..h)
            .flat_map(|y| (0..w).map(move |x| (gx * f64::from(x) + gy * f64::from(y)) as f32))
            .collect()
    }

    #[test]
    fn flat_map_is_all_zero() {
        let f = TerrainFactors::from_heights(4, 3, &[2.5; 12], 1.0).unwrap();
        assert!(f.slope_deg().iter().all(|&s| s == 0.0));
        assert!(f.roughness().iter().all(|&r| (r - 1.0).abs() < 1e-12));
        assert!(f.relief().iter().all(|&r| r == 0.0));
    }

    #[test]
    fn inclined_plane_has_its_slope_and_area_ratio() {
        // Rise 0.5 m per 0.5 m cell in x: 45 degrees; in the interior only.
        let f = TerrainFactors::from_heights(5, 5, &plane(5, 5, 0.5, 0.0), 0.5).unwrap();
        let i = 2 * 5 + 2;
        assert!(
            (f.slope_deg()[i] - 45.0).abs() < 1e-4,
            "{}",
            f.slope_deg()[i]
        );
        assert!((f.roughness()[i] - 2f64.sqrt()).abs() < 1e-5);
        assert!(f.relief()[i] < 1e-6, "a steady slope is no step");
        // A diagonal plane: gradient (0.3, 0.4) per metre -> |grad| = 0.5.
        let f = TerrainFactors::from_heights(5, 5, &plane(5, 5, 0.3, 0.4), 1.0).unwrap();
        assert!((f.slope_deg()[i] - 0.5f64.atan().to_degrees()).abs() < 1e-4);
        assert!((f.roughness()[i] - 1.0 / 0.5f64.atan().cos()).abs() < 1e-5);
    }

    #[test]
    fn a_step_is_relief_on_both_sides() {
        // Columns 0..2 at 0 m, columns 3..5 at 0.3 m.
        let h: Vec<f32> = (0..5)
            .flat_map(|_| (0..6).map(|x| if x >= 3 { 0.3 } else { 0.0 }))
            .collect();
        let f = TerrainFactors::from_heights(6, 5, &h, 1.0).unwrap();
        for y in 1..4 {
            let r = |x: usize| f.relief()[y * 6 + x];
            assert!((r(2) - 0.3).abs() < 1e-6 && (r(3) - 0.3).abs() < 1e-6);
            assert!(r(0) < 1e-9 && r(5) < 1e-9, "far from the step");
        }
    }

    #[test]
    fn bad_input() {
        assert!(TerrainFactors::from_heights(2, 2, &[0.0; 3], 1.0).is_err());
        assert!(TerrainFactors::from_heights(2, 1, &[0.0, f32::NAN], 1.0).is_err());
        assert!(TerrainFactors::from_heights(2, 1, &[0.0; 2], 0.0).is_err());
        let g = Grid::new(2, 2).unwrap();
        assert!(TerrainFactors::from_grid(&g, 1.0).is_err());
    }
}
