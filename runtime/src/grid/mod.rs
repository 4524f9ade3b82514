//! Occupancy grids, coordinates, octile neighbours and MovingAI map files.
//!
//! | module | concept |
//! |---|---|
//! | [`Grid`] (here) | width x height cells, blocked flags, original MovingAI characters, optional terrain |
//! | [`coord`] | [`Cell`] (`x` = column, `y` = row, origin top-left) and [`octile`] distance |
//! | [`geometry`] | row-major index <-> [`Cell`], cell centres in metres, octile step length, angle wrapping |
//! | [`neighbours`] | the 8 [`Direction`]s in the dissertation's order and the [`CornerCutting`] rule |
//! | [`tile`] | [`Tile`], the MovingAI characters and which of them block |
//! | [`terrain`] | [`Terrain`], an optional elevation or cost layer |
//! | [`movingai`] | `.map` reader/writer |
//! | [`scen`] | `.scen` reader/writer and validation against a map |
//! | [`scen_gen`] | seeded random `.scen` files for maps that have none (`hnav map scen`) |
//! | [`sight`] | what a range sensor sees from a cell: the cells within a radius in line of sight |
//! | [`shortest`] | octile shortest paths (the "free oracle") and reachability |
//! | [`check`] | the `hnav map check` report |
//! | [`error`] | [`GridError`], every variant naming file and line |
//!
//! # Indices and ids
//!
//! Cells are stored row-major: `index = y * width + x` (0-based, MovingAI's convention). The
//! dissertation numbers cells from 1, also row-major from the top-left: `id = index + 1`. In
//! its 10x10 example, cell 56 is row 6, column 6 (1-based), i.e. `Cell { x: 5, y: 5 }`.
//!
//! ```
//! use hnav_runtime::grid::{Cell, Grid};
//! let g = Grid::new(10, 10).unwrap();
//! assert_eq!(g.cell_id(Cell::new(5, 5)), 56);
//! assert_eq!(g.cell_from_id(1), Some(Cell::new(0, 0)));
//! ```

pub mod check;
pub mod coord;
pub mod error;
pub mod geometry;
pub mod movingai;
pub mod neighbours;
pub mod scen;
pub mod scen_gen;
pub mod shortest;
pub mod sight;
pub mod terrain;
pub mod tile;

pub use coord::{octile, Cell};
pub use error::{Dimension, Endpoint, GridError};
pub use movingai::{read_map, read_map_file, read_map_rows, write_map, write_map_file};
pub use neighbours::{CornerCutting, Direction, Neighbours};
pub use scen::{read_scen, read_scen_file, validate_scen, write_scen, ScenEntry, ScenFile};
pub use shortest::{components, octile_shortest_path, octile_shortest_path_len, reachable_from};
pub use terrain::{Terrain, TerrainKind};
pub use tile::Tile;

/// A rectangular occupancy grid.
///
/// Invariants (kept by every constructor and setter): `width >= 1`, `height >= 1`,
/// `width * height <= MAX_CELLS`, `tiles.len() == blocked.len() == width * height`,
/// `blocked[i] == !tiles[i].is_passable()`, and the terrain, if any, has one value per cell.
/// The `blocked` flags duplicate information in `tiles` on purpose: hot loops (neighbour
/// expansion, the neural map) read a plain `&[bool]`.
#[derive(Clone, PartialEq, Debug)]
pub struct Grid {
    width: u32,
    height: u32,
    tiles: Vec<Tile>,
    blocked: Vec<bool>,
    terrain: Option<Terrain>,
}

impl Grid {
    /// Largest supported number of cells (an 8192 x 8192 map). The largest MovingAI maps are
    /// about 1000 x 1000; the cap keeps a hostile header from requesting gigabytes and keeps
    /// every 1-based cell id within `u32`.
    pub const MAX_CELLS: u64 = 1 << 26;

    /// An all-ground (`.`) grid. Fails if a dimension is 0 or the grid exceeds [`Self::MAX_CELLS`].
    pub fn new(width: u32, height: u32) -> Result<Grid, GridError> {
        let n = Self::checked_len(width, height, "<grid>", 0)?;
        Grid::from_tiles(width, height, vec![Tile::Ground; n])
    }

    /// A grid from row-major tiles (`tiles.len()` must be `width * height`).
    pub fn from_tiles(width: u32, height: u32, tiles: Vec<Tile>) -> Result<Grid, GridError> {
        let n = Self::checked_len(width, height, "<grid>", 0)?;
        if tiles.len() != n {
            return Err(GridError::BadShape {
                source_name: "<grid>".into(),
                line: 0,
                width: width.into(),
                height: height.into(),
                problem: format!("{} tiles given, {n} needed", tiles.len()),
            });
        }
        let blocked = tiles.iter().map(|t| !t.is_passable()).collect();
        Ok(Grid {
            width,
            height,
            tiles,
            blocked,
            terrain: None,
        })
    }

    /// A grid from row-major blocked flags; blocked cells become `@`, free ones `.`.
    pub fn from_blocked(width: u32, height: u32, blocked: &[bool]) -> Result<Grid, GridError> {
        let tiles = blocked
            .iter()
            .map(|&b| if b { Tile::OutOfBounds } else { Tile::Ground })
            .collect();
        Grid::from_tiles(width, height, tiles)
    }

    /// Validates a shape and returns its cell count. Shared with the readers so that a header
    /// is rejected before any row is read.
    pub(crate) fn checked_len(
        width: u32,
        height: u32,
        source_name: &str,
        line: usize,
    ) -> Result<usize, GridError> {
        let n = u64::from(width) * u64::from(height);
        let problem = if n == 0 {
            "width and height must be at least 1".to_string()
        } else if n > Self::MAX_CELLS {
            format!("more than {} cells", Self::MAX_CELLS)
        } else {
            // n <= 2^26 fits in usize on every supported target.
            return Ok(n as usize);
        };
        Err(GridError::BadShape {
            source_name: source_name.into(),
            line,
            width: width.into(),
            height: height.into(),
            problem,
        })
    }

    /// Number of columns.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Number of rows.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Number of cells, `width * height`.
    pub fn len(&self) -> usize {
        self.tiles.len()
    }

    /// Always `false` (a grid has at least one cell); present because `len` is.
    pub fn is_empty(&self) -> bool {
        self.tiles.is_empty()
    }

    /// Whether `cell` lies inside the grid.
    pub fn contains(&self, cell: Cell) -> bool {
        cell.x < self.width && cell.y < self.height
    }

    /// The cell at signed coordinates, if inside the grid (handy for `cell + offset` maths).
    pub fn cell_checked(&self, x: i64, y: i64) -> Option<Cell> {
        let x = u32::try_from(x).ok()?;
        let y = u32::try_from(y).ok()?;
        let c = Cell { x, y };
        self.contains(c).then_some(c)
    }

    /// Row-major index `y * width + x`. Only meaningful for cells inside the grid (it never
    /// panics, but an outside cell maps to some unrelated number); see [`Self::checked_index`].
    pub fn index(&self, cell: Cell) -> usize {
        geometry::cell_index(self.width, cell)
    }

    /// Row-major index, or `None` for a cell outside the grid.
    pub fn checked_index(&self, cell: Cell) -> Option<usize> {
        self.contains(cell).then(|| self.index(cell))
    }

    /// The cell at a row-major index, or `None` if `index >= len()`.
    pub fn cell_at(&self, index: usize) -> Option<Cell> {
        if index >= self.len() {
            return None;
        }
        geometry::index_cell(self.width, index)
    }

    /// The dissertation's 1-based row-major cell id, `y * width + x + 1`. Only meaningful for
    /// cells inside the grid (outside cells give a wrapped number, never a panic); see
    /// [`Self::checked_cell_id`].
    pub fn cell_id(&self, cell: Cell) -> u32 {
        cell.y
            .wrapping_mul(self.width)
            .wrapping_add(cell.x)
            .wrapping_add(1)
    }

    /// The 1-based cell id, or `None` for a cell outside the grid.
    pub fn checked_cell_id(&self, cell: Cell) -> Option<u32> {
        self.contains(cell).then(|| self.cell_id(cell))
    }

    /// The cell with a 1-based id, or `None` if `id` is 0 or above `width * height`.
    pub fn cell_from_id(&self, id: u32) -> Option<Cell> {
        let index = usize::try_from(id).ok()?.checked_sub(1)?;
        self.cell_at(index)
    }

    /// The tile of a cell, or `None` outside the grid.
    pub fn tile(&self, cell: Cell) -> Option<Tile> {
        self.checked_index(cell).map(|i| self.tiles[i])
    }

    /// All tiles, row-major.
    pub fn tiles(&self) -> &[Tile] {
        &self.tiles
    }

    /// Changes one cell's tile (and thus whether it is blocked). Returns `false`, changing
    /// nothing, if the cell is outside the grid.
    pub fn set_tile(&mut self, cell: Cell, tile: Tile) -> bool {
        match self.checked_index(cell) {
            Some(i) => {
                self.tiles[i] = tile;
                self.blocked[i] = !tile.is_passable();
                true
            }
            None => false,
        }
    }

    /// Blocks (`@`) or frees (`.`) a cell. Returns `false` if the cell is outside the grid.
    pub fn set_blocked(&mut self, cell: Cell, blocked: bool) -> bool {
        self.set_tile(
            cell,
            if blocked {
                Tile::OutOfBounds
            } else {
                Tile::Ground
            },
        )
    }

    /// Whether a cell is blocked. Cells outside the grid count as blocked, which is what
    /// every neighbour and corner-cutting test wants.
    pub fn is_blocked(&self, cell: Cell) -> bool {
        self.checked_index(cell).is_none_or(|i| self.blocked[i])
    }

    /// Whether a cell is inside the grid and free.
    pub fn is_passable(&self, cell: Cell) -> bool {
        !self.is_blocked(cell)
    }

    /// Blocked flags, row-major (`true` = blocked).
    pub fn blocked(&self) -> &[bool] {
        &self.blocked
    }

    /// Number of blocked cells.
    pub fn blocked_count(&self) -> usize {
        self.blocked.iter().filter(|&&b| b).count()
    }

    /// Fraction of blocked cells, `0.0..=1.0`.
    pub fn blocked_fraction(&self) -> f64 {
        self.blocked_count() as f64 / self.len() as f64
    }

    /// All cells, row-major.
    pub fn cells(&self) -> impl Iterator<Item = Cell> + '_ {
        (0..self.len()).filter_map(|i| self.cell_at(i))
    }

    /// All free cells, row-major.
    pub fn passable_cells(&self) -> impl Iterator<Item = Cell> + '_ {
        self.cells().filter(|&c| self.is_passable(c))
    }

    /// The terrain layer, if any.
    pub fn terrain(&self) -> Option<&Terrain> {
        self.terrain.as_ref()
    }

    /// Attaches (or, with `None`, removes) a terrain layer; it must have one value per cell.
    pub fn set_terrain(&mut self, terrain: Option<Terrain>) -> Result<(), GridError> {
        if let Some(t) = &terrain {
            if t.len() != self.len() {
                return Err(GridError::BadTerrain {
                    problem: format!("{} values for a grid of {} cells", t.len(), self.len()),
                });
            }
        }
        self.terrain = terrain;
        Ok(())
    }

    /// One row as MovingAI characters, or `None` if `y` is outside the grid.
    pub fn row_string(&self, y: u32) -> Option<String> {
        if y >= self.height {
            return None;
        }
        let start = y as usize * self.width as usize;
        Some(
            self.tiles[start..start + self.width as usize]
                .iter()
                .map(|t| t.to_char())
                .collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dissertation_ids_on_10x10() {
        let g = Grid::new(10, 10).unwrap();
        assert_eq!(g.cell_id(Cell::new(0, 0)), 1);
        assert_eq!(g.cell_id(Cell::new(5, 5)), 56);
        assert_eq!(g.cell_id(Cell::new(9, 9)), 100);
        assert_eq!(g.cell_from_id(56), Some(Cell::new(5, 5)));
        assert_eq!(g.cell_from_id(1), Some(Cell::new(0, 0)));
        assert_eq!(g.cell_from_id(0), None);
        assert_eq!(g.cell_from_id(101), None);
        assert_eq!(g.checked_cell_id(Cell::new(10, 0)), None);
    }

    #[test]
    fn index_conversions_non_square() {
        let g = Grid::new(7, 3).unwrap();
        assert_eq!(g.index(Cell::new(2, 1)), 9);
        assert_eq!(g.cell_at(9), Some(Cell::new(2, 1)));
        assert_eq!(g.cell_at(21), None);
        assert_eq!(g.checked_index(Cell::new(0, 3)), None);
        assert_eq!(g.cells().count(), 21);
        assert_eq!(g.cells().last(), Some(Cell::new(6, 2)));
    }

    #[test]
    fn shape_errors() {
        assert!(matches!(Grid::new(0, 5), Err(GridError::BadShape { .. })));
        assert!(matches!(
            Grid::new(1 << 14, 1 << 14),
            Err(GridError::BadShape { .. })
        ));
        assert!(Grid::from_tiles(2, 2, vec![Tile::Ground; 3]).is_err());
    }

    #[test]
    fn blocking_and_terrain() {
        let mut g = Grid::new(3, 2).unwrap();
        assert!(g.set_blocked(Cell::new(1, 0), true));
        assert!(!g.set_blocked(Cell::new(3, 0), true));
        assert!(g.is_blocked(Cell::new(1, 0)));
        assert!(g.is_blocked(Cell::new(3, 0)), "outside counts as blocked");
        assert!(g.set_tile(Cell::new(2, 1), Tile::Swamp));
        assert!(g.is_passable(Cell::new(2, 1)));
        assert_eq!(g.blocked_count(), 1);
        assert_eq!(g.row_string(0).as_deref(), Some(".@."));
        assert_eq!(g.row_string(1).as_deref(), Some("..S"));
        assert_eq!(g.passable_cells().count(), 5);
        let t = Terrain::uniform(TerrainKind::Elevation, 5, 0.0).unwrap();
        assert!(g.set_terrain(Some(t)).is_err());
        let t = Terrain::uniform(TerrainKind::Elevation, 6, 0.0).unwrap();
        assert!(g.set_terrain(Some(t)).is_ok());
        assert_eq!(g.terrain().map(|t| t.kind()), Some(TerrainKind::Elevation));
    }

    #[test]
    fn cell_checked_handles_negative() {
        let g = Grid::new(4, 4).unwrap();
        assert_eq!(g.cell_checked(-1, 0), None);
        assert_eq!(g.cell_checked(3, 3), Some(Cell::new(3, 3)));
        assert_eq!(g.cell_checked(4, 0), None);
    }
}
