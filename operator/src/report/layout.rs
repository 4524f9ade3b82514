//! Where everything lands on the report's canvas, in pixels: the map panel on the left (its
//! cell coordinates along its top and left edges), one heatmap panel per chosen agent beside
//! it (what it shows in lines under it), the legend under both, and the run's process events
//! (down, restarted, lost) under the legend.
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
/// Room for a heatmap's caption and the lines under it, which may be wider than a small map.
pub const CAPTION_WIDTH: i32 = 330;
/// Lines under a heatmap: its scale and which map it is (round, target, why).
pub const HEATMAP_LINES: i32 = 3;
/// Room for the row numbers left of the map.
pub const AXIS_LEFT: i32 = 30;
/// Room for the column numbers above the map.
pub const AXIS_TOP: i32 = 16;
/// The fewest pixels between two coordinate labels along an edge.
pub const AXIS_SPACING_PX: f64 = 24.0;
/// The process events listed under the legend at most (the rest is counted in one more line).
pub const MAX_EVENT_LINES: usize = 8;
/// The criteria lines (summary's optimality, energy, ...; consensus latency) above the process
/// events at most.
pub const MAX_CRITERIA_LINES: usize = 2;
/// Marker kinds in the legend after the robots (start, goal, committed cell, conflict,
/// replan, agent down, collision, a cell closed during the run, a sensed cell, a mover).
pub const LEGEND_MARKERS: usize = 10;

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
    /// The top-left corner of the process events' lines.
    pub events: (i32, i32),
}

impl Layout {
    /// The layout of a `cols` x `rows` map with `heatmaps` neural maps and `robots` robots,
    /// without process events.
    pub fn new(cols: u32, rows: u32, heatmaps: usize, robots: usize) -> Self {
        Self::with_events(cols, rows, heatmaps, robots, 0)
    }

    /// [`Layout::new`] with `events` lines of criteria and process events under the legend.
    pub fn with_events(
        cols: u32,
        rows: u32,
        heatmaps: usize,
        robots: usize,
        events: usize,
    ) -> Self {
        let longer = f64::from(cols.max(rows).max(1));
        let cell = (MAP_PX / longer).clamp(1.0, MAX_CELL_PX);
        let top = MARGIN + TITLE_PX + CAPTION_PX + AXIS_TOP;
        let map = Panel {
            x: MARGIN + AXIS_LEFT,
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
            .map(|p| p.bottom() + HEATMAP_LINES * CAPTION_PX)
            .fold(map.bottom(), i32::max);
        let captions = heatmaps.last().map_or(0, |p| p.x + CAPTION_WIDTH);
        let legend = (MARGIN, bottom + GAP);
        let entries = robots + LEGEND_MARKERS;
        let legend_rows = entries.clamp(1, 8);
        let columns = entries.div_ceil(legend_rows) as i32;
        let right = (x - GAP)
            .max(captions)
            .max(MARGIN + columns * LEGEND_COLUMN);
        let events_at = (
            MARGIN,
            legend.1 + legend_rows as i32 * LEGEND_LINE + GAP / 2,
        );
        let event_lines = match events {
            0 => 0,
            n => 1 + n.min(MAX_EVENT_LINES + 1 + MAX_CRITERIA_LINES) as i32,
        };
        Layout {
            width: (right + MARGIN) as u32,
            height: (events_at.1 + event_lines * LEGEND_LINE + MARGIN) as u32,
            map,
            heatmaps,
            legend,
            legend_rows,
            events: events_at,
        }
    }

    /// The coordinate labels of `n` cells of `cell` pixels: every `step`-th cell from 0, the
    /// step 1, 2 or 5 times a power of ten so that labels stay [`AXIS_SPACING_PX`] apart.
    pub fn axis_step(n: u32, cell: f64) -> u32 {
        let mut base = 1u32;
        loop {
            for s in [base, base.saturating_mul(2), base.saturating_mul(5)] {
                if f64::from(s) * cell >= AXIS_SPACING_PX || s >= n.max(1) || s == u32::MAX {
                    return s;
                }
            }
            base = base.saturating_mul(10);
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
    fn coordinate_labels_stay_apart() {
        assert_eq!(Layout::axis_step(12, 40.0), 1);
        assert_eq!(Layout::axis_step(32, 20.0), 2);
        assert_eq!(Layout::axis_step(128, 5.0), 5);
        assert_eq!(Layout::axis_step(2000, 1.0), 50);
        assert_eq!(Layout::axis_step(3, 1.0), 5, "one label, at 0");
    }

    #[test]
    fn process_events_make_room_under_the_legend() {
        let plain = Layout::new(12, 12, 1, 6);
        let with = Layout::with_events(12, 12, 1, 6, 2);
        assert_eq!(with.map, plain.map);
        assert_eq!(with.height as i32, plain.height as i32 + 3 * LEGEND_LINE);
        assert!(with.events.1 > with.legend.1);
        let many = Layout::with_events(12, 12, 1, 6, 100);
        assert_eq!(
            many.height as i32,
            plain.height as i32 + (2 + (MAX_EVENT_LINES + MAX_CRITERIA_LINES) as i32) * LEGEND_LINE
        );
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
