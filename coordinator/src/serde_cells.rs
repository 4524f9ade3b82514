//! Serde helpers: a list of [`Cell`](hnav_runtime::grid::Cell)s as `[[x, y], ...]` (the
//! runtime's `Cell` has no serde impls), the shape of the bench's JSON `path` field.

/// A list of cells as `[[x, y], ...]`.
pub(crate) mod cells {
    use hnav_runtime::grid::Cell;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(cells: &[Cell], s: S) -> Result<S::Ok, S::Error> {
        let pairs: Vec<[u32; 2]> = cells.iter().map(|c| [c.x, c.y]).collect();
        pairs.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Cell>, D::Error> {
        let pairs = Vec::<[u32; 2]>::deserialize(d)?;
        Ok(pairs.into_iter().map(|[x, y]| Cell::new(x, y)).collect())
    }
}
