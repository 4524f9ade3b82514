//! The map on screen: grid cells scaled to the area the terminal gives, obstacles, goals and
//! each robot as its label on its ground-truth cell.
//!
//! A map that fits twice over in width gets two columns per cell (terminal characters are
//! about twice as tall as wide, so the room keeps its shape); one that fits once gets one;
//! a larger one is shown in square blocks of `step x step` cells, one character each, a block
//! drawn as a wall when all its cells are blocked and as shaded when some are. Robots are
//! drawn over goals, goals over the floor; in a block holding several robots the lowest
//! index shows. With `[sensing]` the floor a robot's range sensor sees now is drawn `:`
//! instead of `.` (a block: when it sees any of its cells).

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::widgets::Widget;

use super::state::{AgentState, ViewState};
use hnav_runtime::grid::Grid;

/// How grid cells map to terminal characters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MapScale {
    /// Grid cells per block side (1: every cell shown).
    pub step: u32,
    /// Terminal columns per block (2 when the map fits twice over in width, else 1).
    pub cols: u16,
}

impl MapScale {
    /// The largest scale at which a `width x height` grid fits in `area_w x area_h`
    /// characters (an empty area gets the scale of a one-character one).
    pub fn fit(width: u32, height: u32, area_w: u16, area_h: u16) -> MapScale {
        let (aw, ah) = (u32::from(area_w.max(1)), u32::from(area_h.max(1)));
        let (w, h) = (width.max(1), height.max(1));
        if 2 * w <= aw && h <= ah {
            MapScale { step: 1, cols: 2 }
        } else {
            let step = w.div_ceil(aw).max(h.div_ceil(ah));
            MapScale { step, cols: 1 }
        }
    }

    /// The characters the scaled grid takes: (columns, rows).
    pub fn size(&self, width: u32, height: u32) -> (u16, u16) {
        let blocks = |n: u32| n.div_ceil(self.step);
        let cols = blocks(width).saturating_mul(u32::from(self.cols));
        (
            u16::try_from(cols).unwrap_or(u16::MAX),
            u16::try_from(blocks(height)).unwrap_or(u16::MAX),
        )
    }

    /// The block (column, row, in blocks) holding cell `id` of a grid `width` wide.
    pub fn block_of(&self, id: u32, width: u32) -> (u32, u32) {
        ((id % width) / self.step, (id / width) / self.step)
    }
}

/// How a block of cells looks: every cell free, some blocked, all blocked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Floor {
    /// Every cell is free.
    Free,
    /// Some cells are blocked.
    Partly,
    /// Every cell is blocked.
    Wall,
}

/// The floor of block (`bx`, `by`) at `scale`.
pub fn floor_of(grid: &Grid, scale: MapScale, bx: u32, by: u32) -> Floor {
    let (x0, y0) = (bx * scale.step, by * scale.step);
    let (x1, y1) = (
        (x0 + scale.step).min(grid.width()),
        (y0 + scale.step).min(grid.height()),
    );
    let blocked = grid.blocked();
    let (mut free, mut walls) = (false, false);
    for y in y0..y1 {
        let row = (y * grid.width()) as usize;
        for x in x0..x1 {
            if blocked[row + x as usize] {
                walls = true;
            } else {
                free = true;
            }
        }
    }
    match (free, walls) {
        (_, false) => Floor::Free,
        (true, true) => Floor::Partly,
        (false, true) => Floor::Wall,
    }
}

/// Whether any cell of block (`bx`, `by`) at `scale` is `sensed` (one flag per cell of a grid
/// `width` wide).
fn block_sensed(sensed: &[bool], width: u32, scale: MapScale, bx: u32, by: u32) -> bool {
    let (x0, y0) = (bx * scale.step, by * scale.step);
    let height = sensed.len() as u32 / width.max(1);
    (y0..(y0 + scale.step).min(height))
        .any(|y| (x0..(x0 + scale.step).min(width)).any(|x| sensed[(y * width + x) as usize]))
}

/// Agent `i`'s label: `0`-`9`, then `A`-`Z`, then `a`-`z`; `@` for the rest.
pub fn agent_label(i: usize) -> char {
    const LABELS: &[u8] = b"0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz";
    LABELS.get(i).map_or('@', |&b| char::from(b))
}

/// Agent `i`'s colour.
pub fn agent_color(i: usize) -> Color {
    const COLORS: [Color; 8] = [
        Color::LightCyan,
        Color::LightYellow,
        Color::LightMagenta,
        Color::LightGreen,
        Color::LightRed,
        Color::LightBlue,
        Color::Cyan,
        Color::Yellow,
    ];
    COLORS[i % COLORS.len()]
}

/// The map of a [`ViewState`], as a ratatui widget.
#[derive(Debug, Clone, Copy)]
pub struct MapWidget<'a> {
    state: &'a ViewState,
}

impl<'a> MapWidget<'a> {
    /// The map of `state`.
    pub fn new(state: &'a ViewState) -> Self {
        Self { state }
    }
}

impl Widget for MapWidget<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let grid = &self.state.info.grid;
        let (w, h) = (grid.width(), grid.height());
        let scale = MapScale::fit(w, h, area.width, area.height);
        let (cols, rows) = scale.size(w, h);
        let (cols, rows) = (cols.min(area.width), rows.min(area.height));
        let at = |bx: u32, by: u32| -> Option<(u16, u16)> {
            let x = u16::try_from(bx).ok()?.checked_mul(scale.cols)?;
            let y = u16::try_from(by).ok()?;
            (x < cols && y < rows).then_some((area.x + x, area.y + y))
        };
        let put = |buf: &mut Buffer, bx: u32, by: u32, text: &str, style: Style| {
            if let Some((x, y)) = at(bx, by) {
                let room = usize::from(area.x + cols - x);
                buf.set_stringn(x, y, text, room, style);
            }
        };
        let wall = Style::default().fg(Color::Gray);
        let floor = Style::default().fg(Color::DarkGray);
        let (free_s, sensed_s, partly_s, wall_s) = if scale.cols == 2 {
            (" .", " :", "▒▒", "██")
        } else {
            (".", ":", "▒", "█")
        };
        let sensed = self.state.sensed();
        for by in 0..u32::from(rows) {
            for bx in 0..u32::from(cols / scale.cols) {
                let (text, style) = match floor_of(grid, scale, bx, by) {
                    Floor::Free if block_sensed(&sensed, grid.width(), scale, bx, by) => {
                        (sensed_s, floor)
                    }
                    Floor::Free => (free_s, floor),
                    Floor::Partly => (partly_s, wall),
                    Floor::Wall => (wall_s, wall),
                };
                put(buf, bx, by, text, style);
            }
        }
        let goal = if scale.cols == 2 { "+ " } else { "+" };
        for (i, a) in self.state.agents.iter().enumerate() {
            let (bx, by) = scale.block_of(a.goal, w);
            put(buf, bx, by, goal, Style::default().fg(agent_color(i)));
        }
        // Movers before robots: a robot on a mover's block (a contact) shows over it.
        let mover = if scale.cols == 2 { "@@" } else { "@" };
        let mover_s = Style::default()
            .fg(Color::LightRed)
            .add_modifier(Modifier::BOLD);
        for cell in self.state.mover_cells() {
            let (bx, by) = scale.block_of(cell, w);
            put(buf, bx, by, mover, mover_s);
        }
        // Drawn from the last agent to the first, so the lowest index shows on a shared block.
        for (i, a) in self.state.agents.iter().enumerate().rev() {
            let Some(cell) = a.cell else { continue };
            let (bx, by) = scale.block_of(cell, w);
            let mut style = Style::default()
                .fg(agent_color(i))
                .add_modifier(Modifier::BOLD);
            if a.state() == AgentState::Down {
                style = style.add_modifier(Modifier::CROSSED_OUT | Modifier::DIM);
            }
            let mut label = [0u8; 4];
            let label = agent_label(i).encode_utf8(&mut label);
            put(buf, bx, by, label, style);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_block_is_sensed_when_any_of_its_cells_is() {
        // 4 x 2 cells, cell (3, 1) seen.
        let mut sensed = vec![false; 8];
        sensed[7] = true;
        let one = MapScale { step: 1, cols: 2 };
        assert!(block_sensed(&sensed, 4, one, 3, 1));
        assert!(!block_sensed(&sensed, 4, one, 2, 1));
        let two = MapScale { step: 2, cols: 1 };
        assert!(block_sensed(&sensed, 4, two, 1, 0));
        assert!(!block_sensed(&sensed, 4, two, 0, 0));
    }

    #[test]
    fn a_small_map_gets_two_columns_per_cell() {
        assert_eq!(MapScale::fit(12, 12, 40, 20), MapScale { step: 1, cols: 2 });
        assert_eq!(MapScale { step: 1, cols: 2 }.size(12, 12), (24, 12));
        // Too narrow for two columns, wide enough for one.
        assert_eq!(MapScale::fit(30, 10, 40, 20), MapScale { step: 1, cols: 1 });
    }

    #[test]
    fn a_large_map_is_shown_in_blocks_that_fit() {
        // 512 x 512 into 80 x 40: 13 cells a block (512 / 40 rounded up), 40 x 40 blocks.
        let s = MapScale::fit(512, 512, 80, 40);
        assert_eq!(s, MapScale { step: 13, cols: 1 });
        let (c, r) = s.size(512, 512);
        assert!(c <= 80 && r <= 40, "{c} x {r}");
        assert_eq!(s.block_of(512 * 511 + 511, 512), (39, 39));
        // A wide map is limited by its width.
        let wide = MapScale::fit(300, 10, 100, 40);
        assert_eq!(wide, MapScale { step: 3, cols: 1 });
        assert_eq!(wide.size(300, 10), (100, 4));
        // No area at all still gives a usable scale.
        assert_eq!(MapScale::fit(5, 5, 0, 0).step, 5);
    }

    #[test]
    fn blocks_are_free_partly_blocked_or_walls() {
        let mut blocked = vec![false; 16];
        blocked[0] = true; // block (0, 0) of a 2-step scale: 1 of 4 cells
        for i in [2, 3, 6, 7] {
            blocked[i] = true; // block (1, 0): all four
        }
        let grid = Grid::from_blocked(4, 4, &blocked).unwrap();
        let s = MapScale { step: 2, cols: 1 };
        assert_eq!(floor_of(&grid, s, 0, 0), Floor::Partly);
        assert_eq!(floor_of(&grid, s, 1, 0), Floor::Wall);
        assert_eq!(floor_of(&grid, s, 0, 1), Floor::Free);
    }

    #[test]
    fn labels_run_through_digits_and_letters() {
        assert_eq!(agent_label(0), '0');
        assert_eq!(agent_label(10), 'A');
        assert_eq!(agent_label(36), 'a');
        assert_eq!(agent_label(61), 'z');
        assert_eq!(agent_label(62), '@');
    }
}
