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

/// Two far-apart cells of the largest connected region (a double BFS sweep under `rule`).
pub fn far_pair(g: &Grid, rule: hnav_runtime::grid::CornerCutting) -> (Cell, Cell) {
    use hnav_runtime::grid::reachable_from;
    // The largest region: try free cells until one reaches at least half of the free cells
    // or keep the best seen.
    let free: Vec<Cell> = g.passable_cells().collect();
    let mut best = (0usize, free[0]);
    let mut seen = vec![false; g.len()];
    for &c in &free {
        if seen[g.index(c)] {
            continue;
        }
        let r = reachable_from(g, c, rule);
        let n = r.iter().filter(|&&b| b).count();
        for (i, &b) in r.iter().enumerate() {
            seen[i] |= b;
        }
        if n > best.0 {
            best = (n, c);
        }
    }
    let a = farthest(g, best.1, rule);
    let b = farthest(g, a, rule);
    (a, b)
}

/// The cell farthest (in moves) from `from`.
pub fn farthest(g: &Grid, from: Cell, rule: hnav_runtime::grid::CornerCutting) -> Cell {
    let mut dist = vec![u32::MAX; g.len()];
    let mut queue = std::collections::VecDeque::from([from]);
    dist[g.index(from)] = 0;
    let mut last = from;
    while let Some(c) = queue.pop_front() {
        last = c;
        for (_, n) in g.neighbours(c, rule) {
            if dist[g.index(n)] == u32::MAX {
                dist[g.index(n)] = dist[g.index(c)] + 1;
                queue.push_back(n);
            }
        }
    }
    last
}

/// `mean, p95, max (worst case)` of path-length ratios, or `None` if there are none.
pub fn ratio_summary(mut ratios: Vec<(f64, String)>) -> Option<String> {
    if ratios.is_empty() {
        return None;
    }
    ratios.sort_by(|a, b| a.0.total_cmp(&b.0));
    let n = ratios.len();
    let mean = ratios.iter().map(|r| r.0).sum::<f64>() / n as f64;
    let p95 = ratios[((n as f64 * 0.95).ceil() as usize).clamp(1, n) - 1].0;
    let (max, worst) = &ratios[n - 1];
    let optimal = ratios.iter().filter(|r| r.0 < 1.0 + 1e-9).count();
    Some(format!(
        "n {n}, optimal {optimal} ({:.1} %), mean {mean:.4}, p95 {p95:.4}, max {max:.4} ({worst})",
        100.0 * optimal as f64 / n as f64
    ))
}
