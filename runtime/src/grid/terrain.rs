//! Optional per-cell terrain layer.
//!
//! Occupancy alone says where a robot may stand. Some planners also want to know how hard a
//! cell is to cross (the coordinator's terrain-cost Theta*) or how high it is (a sim that
//! models slopes). A [`Terrain`] carries one `f32` per cell, row-major like the grid, and a
//! [`TerrainKind`] saying which of the two meanings the numbers have, so a layer of heights
//! can never be mistaken for costs.

use super::error::GridError;

/// What the numbers of a [`Terrain`] layer mean.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum TerrainKind {
    /// Height of the cell's floor in metres above an arbitrary datum (any finite value).
    Elevation,
    /// Traversal cost multiplier, finite and `>= 0`: a move into the cell costs its length
    /// times the value. Planners that use the octile distance as heuristic assume `>= 1`.
    Cost,
}

/// A per-cell layer of elevations or traversal costs, indexed like the grid (`y * width + x`).
#[derive(Clone, PartialEq, Debug)]
pub struct Terrain {
    kind: TerrainKind,
    values: Vec<f32>,
}

impl Terrain {
    /// A layer of the given kind. Checks that every value is finite (and `>= 0` for costs);
    /// the length is checked when the layer is attached to a grid.
    pub fn new(kind: TerrainKind, values: Vec<f32>) -> Result<Terrain, GridError> {
        for (i, &v) in values.iter().enumerate() {
            let ok = v.is_finite() && (kind == TerrainKind::Elevation || v >= 0.0);
            if !ok {
                let layer = match kind {
                    TerrainKind::Elevation => "an elevation layer (finite metres)",
                    TerrainKind::Cost => "a cost layer (finite, >= 0)",
                };
                return Err(GridError::BadTerrain {
                    problem: format!("value {v} at index {i} is not valid for {layer}"),
                });
            }
        }
        Ok(Terrain { kind, values })
    }

    /// A layer with the same value everywhere.
    pub fn uniform(kind: TerrainKind, cells: usize, value: f32) -> Result<Terrain, GridError> {
        Terrain::new(kind, vec![value; cells])
    }

    /// Elevation or cost.
    pub fn kind(&self) -> TerrainKind {
        self.kind
    }

    /// All values, row-major.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// The value at a grid index, if in range.
    pub fn get(&self, index: usize) -> Option<f32> {
        self.values.get(index).copied()
    }

    /// Number of values.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether the layer has no values.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_nan_and_negative_cost() {
        assert!(Terrain::new(TerrainKind::Cost, vec![1.0, f32::NAN]).is_err());
        assert!(Terrain::new(TerrainKind::Cost, vec![1.0, -0.5]).is_err());
        assert!(Terrain::new(TerrainKind::Elevation, vec![1.0, -0.5]).is_ok());
        assert!(Terrain::new(TerrainKind::Elevation, vec![f32::INFINITY]).is_err());
        let t = Terrain::uniform(TerrainKind::Cost, 4, 1.5).unwrap();
        assert_eq!(t.len(), 4);
        assert_eq!(t.get(3), Some(1.5));
        assert_eq!(t.get(4), None);
    }
}
