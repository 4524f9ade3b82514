//! Shared fixtures: the dissertation's grids, written from the published cell lists.
#![allow(dead_code)]

use hnav_runtime::grid::{Cell, Grid};

/// The 42 obstacle cells of Fig. 2-16 (1-based row-major ids on 10 x 10).
pub const FIG_2_16_OBSTACLES: [u32; 42] = [
    4, 5, 6, 7, 8, 9, 10, 11, 12, 22, 24, 25, 26, 27, 28, 29, 32, 42, 43, 45, 46, 47, 48, 49, 55,
    59, 62, 63, 65, 66, 67, 69, 72, 79, 82, 83, 84, 85, 86, 87, 88, 89,
];

/// A grid of `w x h` with the given 1-based ids blocked.
pub fn grid_with_ids(w: u32, h: u32, ids: &[u32]) -> Grid {
    let mut g = Grid::new(w, h).unwrap();
    for &id in ids {
        let c = g.cell_from_id(id).unwrap();
        g.set_blocked(c, true);
    }
    g
}

/// The Fig. 2-16 maze.
pub fn maze() -> Grid {
    grid_with_ids(10, 10, &FIG_2_16_OBSTACLES)
}

/// A cell from its 1-based id on a 10-wide grid.
pub fn id(g: &Grid, id: u32) -> Cell {
    g.cell_from_id(id).unwrap()
}

/// A MovingAI map shipped in the repository.
pub fn movingai(name: &str) -> Grid {
    let path = format!("{}/../maps/{name}", env!("CARGO_MANIFEST_DIR"));
    hnav_runtime::grid::read_map_file(path).unwrap()
}

/// The map as text (`#` blocked, `.` free), for failure messages.
pub fn render(g: &Grid) -> String {
    (0..g.height())
        .map(|y| g.row_string(y).unwrap())
        .collect::<Vec<_>>()
        .join("\n")
}
