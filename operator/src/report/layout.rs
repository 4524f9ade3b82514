//! Where everything lands on the report's canvas, in pixels: the map panel on the left, one
//! heatmap panel per chosen agent beside it, the legend under both.
//!
//! Cells are square; the map's cells are at most [`MAX_CELL_PX`] and the map at most about
//! [`MAP_PX`] on its longer side, heatmap cells half as large (at least one pixel each).

/// The map panel's longer side aims at this many pixels.
pub const MAP_PX: f64 = 640.0;
/// The largest cell of the map panel.
pub const MAX_CELL_PX: f64 = 40.0;
/// The outer margin.
pub const MARGIN: i32 = 20;
/// The title line above the panels.
pub const TITLE_PX: i32 = 30;
/// A panel's caption line.
pub const CAPTION_PX: i32 = 20;
/// Between panels.
pub const GAP: i32 = 30;
/// One legend line.
pub const LEGEND_LINE: i32 = 20;
/// One legend column.
pub const LEGEND_COLUMN: i32 = 170;
/// Room for a heatmap's caption and scale line, which may be wider than a small map.
pub const CAPTION_WIDTH: i32 = 230;
/// Marker kinds in the legend after the robots (start, goal, committed cell, conflict,
/// replan, collision).
pub const LEGEND_MARKERS: usize = 6;

/// A grid drawn on the canvas: its top-left pixel, its cells' size and count.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Panel {
    /// Left edge, px.
    pub x: i32,
    /// Top edge, px.
    pub y: i32,
    /// Pixels per cell.
    pub cell: f64,
    /// Columns (cells).
    pub cols: u32,
    /// Rows (cells).
    pub rows: u32,
}

impl Panel {
    /// The pixel of the point `(x, y)` in cell units (cell `(c, r)` spans `[c, c + 1)`).
    pub fn px(&self, x: f64, y: f64) -> (i32, i32) {
        (
            self.x + (x * self.cell).round() as i32,
            self.y + (y * self.cell).round() as i32,
        )
    }

    /// The centre pixel of cell `(c, r)`.
    pub fn centre(&self, c: u32, r: u32) -> (i32, i32) {
        self.px(f64::from(c) + 0.5, f64::from(r) + 0.5)
    }

    /// The corners of cell `(c, r)`, adjacent cells sharing their edges.
    pub fn cell_rect(&self, c: u32, r: u32) -> [(i32, i32); 2] {
        [
            self.px(f64::from(c), f64::from(r)),
            self.px(f64::from(c) + 1.0, f64::from(r) + 1.0),
        ]
    }

    /// Right edge, px.
    pub fn right(&self) -> i32 {
        self.px(f64::from(self.cols), 0.0).0
    }

    /// Bottom edge, px.
    pub fn bottom(&self) -> i32 {
        self.px(0.0, f64::from(self.rows)).1
    }

    /// Whether pixel `(x, y)` lies on the panel.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        x >= f64::from(self.x)
            && y >= f64::from(self.y)
            && x < f64::from(self.right())
            && y < f64::from(self.bottom())
    }
}

/// The canvas: its size, the panels and the legend's top-left corner.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// Canvas width, px.
    pub width: u32,
    /// Canvas height, px.
    pub height: u32,
    /// The map.
    pub map: Panel,
    /// One per chosen agent, left to right.
    pub heatmaps: Vec<Panel>,
    /// The legend's top-left corner.
    pub legend: (i32, i32),
    /// Legend entries per column.
    pub legend_rows: usize,
}

impl Layout {
    /// The layout of a `cols` x `rows` map with `heatmaps` neural maps and `robots` robots.
    pub fn new(cols: u32, rows: u32, heatmaps: usize, robots: usize) -> Self {
        let longer = f64::from(cols.max(rows).max(1));
        let cell = (MAP_PX / longer).clamp(1.0, MAX_CELL_PX);
        let top = MARGIN + TITLE_PX + CAPTION_PX;
        let map = Panel {
            x: MARGIN,
            y: top,
            cell,
            cols,
            rows,
        };
        let hm_cell = (cell / 2.0).max(1.0);
        let mut x = map.right() + GAP;
        let heatmaps: Vec<Panel> = (0..heatmaps)
            .map(|_| {
                let p = Panel {
                    x,
                    y: top,
                    cell: hm_cell,
                    cols,
                    rows,
                };
                x = p.right() + GAP;
                p
            })
            .collect();
        let bottom = heatmaps
            .iter()
            .map(|p| p.bottom() + CAPTION_PX)
            .fold(map.bottom(), i32::max);
        let captions = heatmaps.last().map_or(0, |p| p.x + CAPTION_WIDTH);
        let legend = (MARGIN, bottom + GAP);
        let entries = robots + LEGEND_MARKERS;
        let legend_rows = entries.clamp(1, 8);
        let columns = entries.div_ceil(legend_rows) as i32;
        let right = (x - GAP)
            .max(captions)
            .max(MARGIN + columns * LEGEND_COLUMN);
        Layout {
            width: (right + MARGIN) as u32,
            height: (legend.1 + legend_rows as i32 * LEGEND_LINE + MARGIN) as u32,
            map,
            heatmaps,
            legend,
            legend_rows,
        }
    }

    /// The top-left pixel of legend entry `i` (robots first, then the markers).
    pub fn legend_entry(&self, i: usize) -> (i32, i32) {
        let (col, row) = (i / self.legend_rows, i % self.legend_rows);
        (
            self.legend.0 + col as i32 * LEGEND_COLUMN,
            self.legend.1 + row as i32 * LEGEND_LINE,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panels_sit_side_by_side_and_cells_tile() {
        let l = Layout::new(12, 12, 2, 6);
        assert_eq!(l.map.cell, MAX_CELL_PX);
        assert_eq!(l.heatmaps.len(), 2);
        assert_eq!(l.heatmaps[0].x, l.map.right() + GAP);
        assert_eq!(l.heatmaps[1].x, l.heatmaps[0].right() + GAP);
        assert!(l.width as i32 >= l.heatmaps[1].right());
        let a = l.map.cell_rect(3, 4);
        let b = l.map.cell_rect(4, 4);
        assert_eq!(a[1].0, b[0].0);
        assert!(l.legend.1 > l.map.bottom());
    }

    #[test]
    fn a_large_map_gets_small_cells_but_at_least_a_pixel() {
        let l = Layout::new(2000, 100, 1, 1);
        assert_eq!(l.map.cell, 1.0);
        assert_eq!(l.heatmaps[0].cell, 1.0);
        let l = Layout::new(128, 128, 1, 1);
        assert!((l.map.cell - 5.0).abs() < 1e-9);
    }
}
