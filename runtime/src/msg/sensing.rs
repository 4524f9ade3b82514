//! What a robot's range sensor sees of the world (an emulated LiDAR, seed 000 §3.1.1): the
//! cells within range and in line of sight, free or blocked, as the sim's truth has them, and
//! which of them a moving obstacle holds.

use iceoryx2::prelude::ZeroCopySend;

/// The largest window edge a [`View`] holds, cells: a range of up to 15 cells.
pub const VIEW_EDGE: usize = 32;

/// Robot `agent`'s view at the end of control period `period`: a window of `size` x `size`
/// cells whose top-left cell is (`x0`, `y0`), centred on the robot's cell (clipped to the
/// map). Bit `c` of row `r` stands for cell (`x0 + c`, `y0 + r`): in `seen` if it is within
/// range and in line of sight, in `blocked` if it is then a wall, a closed cell or a moving
/// obstacle's, in `moving` if a mover holds it: stands in it, or walks the leg into or out of
/// it (then it says nothing about the map: the agent keeps out of it for now and does not
/// learn it). A cell not seen says nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
#[type_name("hnav::View")]
pub struct View {
    /// Simulated time of the view, ns since the start of the run.
    pub sim_time_ns: u64,
    /// Control period the view closes.
    pub period: u64,
    /// Agent (robot) index.
    pub agent: u32,
    /// Column of the window's top-left cell.
    pub x0: u32,
    /// Row of the window's top-left cell.
    pub y0: u32,
    /// Window edge, cells (at most [`VIEW_EDGE`]).
    pub size: u32,
    /// Per window row, the cells seen.
    pub seen: [u32; VIEW_EDGE],
    /// Per window row, the cells seen blocked.
    pub blocked: [u32; VIEW_EDGE],
    /// Per window row, the cells seen that a mover holds.
    pub moving: [u32; VIEW_EDGE],
}

impl Default for View {
    fn default() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}

impl View {
    /// Clears the window and places it at (`x0`, `y0`) with edge `size` (at most
    /// [`VIEW_EDGE`]).
    pub fn reset(&mut self, x0: u32, y0: u32, size: u32) {
        self.x0 = x0;
        self.y0 = y0;
        self.size = size.min(VIEW_EDGE as u32);
        self.seen = [0; VIEW_EDGE];
        self.blocked = [0; VIEW_EDGE];
        self.moving = [0; VIEW_EDGE];
    }

    /// The window row and column bit of cell (`x`, `y`) of the map, if it is in the window.
    fn bit(&self, x: u32, y: u32) -> Option<(usize, u32)> {
        let (c, r) = (x.checked_sub(self.x0)?, y.checked_sub(self.y0)?);
        // Lazily: `1 << c` overflows for a cell 32 or more columns right of the window.
        (c < self.size && r < self.size).then(|| (r as usize, 1 << c))
    }

    /// Marks cell (`x`, `y`) of the map seen, blocked or not; one outside the window is
    /// ignored.
    pub fn mark(&mut self, x: u32, y: u32, blocked: bool) {
        let Some((r, bit)) = self.bit(x, y) else {
            return;
        };
        self.seen[r] |= bit;
        if blocked {
            self.blocked[r] |= bit;
        }
    }

    /// Marks cell (`x`, `y`) moving if it is seen (a mover out of sight is not sensed).
    pub fn mark_moving(&mut self, x: u32, y: u32) {
        if let Some((r, bit)) = self.bit(x, y).filter(|&(r, bit)| self.seen[r] & bit != 0) {
            self.moving[r] |= bit;
        }
    }

    /// Whether cell (`x`, `y`) of the map is seen moving.
    pub fn is_moving(&self, x: u32, y: u32) -> bool {
        self.bit(x, y)
            .is_some_and(|(r, bit)| self.moving[r] & bit != 0)
    }

    /// Every cell seen moving, as (`x`, `y`), row by row.
    pub fn moving_cells(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.cells()
            .filter(|&(x, y, _)| self.is_moving(x, y))
            .map(|(x, y, _)| (x, y))
    }

    /// Every cell seen, as (`x`, `y`, blocked), row by row.
    pub fn cells(&self) -> impl Iterator<Item = (u32, u32, bool)> + '_ {
        let size = self.size.min(VIEW_EDGE as u32);
        (0..size).flat_map(move |r| {
            (0..size).filter_map(move |c| {
                let bit = 1u32 << c;
                (self.seen[r as usize] & bit != 0).then(|| {
                    let blocked = self.blocked[r as usize] & bit != 0;
                    (self.x0 + c, self.y0 + r, blocked)
                })
            })
        })
    }
}

/// The user header of the sim's `movers` topic, a slice of [`MoverPlace`]: where the moving
/// obstacles (`[[events]]` movers: a person, a forklift) on the floor are at the end of
/// control period `period`. Published with the truth, only by a run that has movers: the
/// recorder keeps them, so the report, the replay and the MCAP export draw them and the
/// sensed areas they hid, as `hnav top` does live.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
#[type_name("hnav::MoversHeader")]
pub struct MoversHeader {
    /// Simulated time, ns since the start of the run.
    pub sim_time_ns: u64,
    /// Control period.
    pub period: u64,
}

/// One mover on the floor: its index `mover` (the order the movers appeared in: mover `k` of
/// a contact) and its pose, heading along the leg it walks. A mover that waits to come on
/// (its first cell claimed by a robot) is not in the slice.
#[derive(
    Debug, Clone, Copy, PartialEq, Default, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
#[type_name("hnav::MoverPlace")]
pub struct MoverPlace {
    /// The mover's index.
    pub mover: u32,
    /// Zero.
    pub reserved: u32,
    /// Where it is.
    pub pose: crate::msg::Pose,
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::mem::{align_of, offset_of, size_of};

    #[test]
    fn mover_place_layout() {
        assert_eq!(size_of::<MoverPlace>(), 32);
        assert_eq!(align_of::<MoverPlace>(), 8);
        assert_eq!(offset_of!(MoverPlace, mover), 0);
        assert_eq!(offset_of!(MoverPlace, reserved), 4);
        assert_eq!(offset_of!(MoverPlace, pose), 8);
    }

    #[test]
    fn movers_header_layout() {
        assert_eq!(size_of::<MoversHeader>(), 16);
        assert_eq!(align_of::<MoversHeader>(), 8);
        assert_eq!(offset_of!(MoversHeader, sim_time_ns), 0);
        assert_eq!(offset_of!(MoversHeader, period), 8);
    }

    #[test]
    fn view_layout() {
        assert_eq!(size_of::<View>(), 416);
        assert_eq!(align_of::<View>(), 8);
        assert_eq!(offset_of!(View, sim_time_ns), 0);
        assert_eq!(offset_of!(View, period), 8);
        assert_eq!(offset_of!(View, agent), 16);
        assert_eq!(offset_of!(View, x0), 20);
        assert_eq!(offset_of!(View, y0), 24);
        assert_eq!(offset_of!(View, size), 28);
        assert_eq!(offset_of!(View, seen), 32);
        assert_eq!(offset_of!(View, blocked), 160);
        assert_eq!(offset_of!(View, moving), 288);
    }

    #[test]
    fn marked_cells_come_back_and_cells_off_the_window_are_ignored() {
        let mut v = View::default();
        v.reset(3, 4, 5);
        v.mark(3, 4, false);
        v.mark(7, 8, true);
        v.mark(8, 8, true);
        v.mark(2, 5, true);
        assert_eq!(v.cells().collect::<Vec<_>>(), [(3, 4, false), (7, 8, true)]);
        // Moving only where seen.
        v.mark_moving(7, 8);
        v.mark_moving(4, 4);
        assert_eq!(v.moving_cells().collect::<Vec<_>>(), [(7, 8)]);
        assert!(v.is_moving(7, 8) && !v.is_moving(3, 4));
        v.reset(0, 0, 3);
        assert_eq!(v.cells().count(), 0);
    }

    #[test]
    fn a_cell_far_right_of_the_window_is_ignored_not_a_panic() {
        // A mover 40 columns right of a robot's window: the sim marks every mover cell.
        let mut v = View::default();
        v.reset(0, 0, 5);
        v.mark(40, 0, true);
        v.mark_moving(40, 0);
        assert!(!v.is_moving(40, 0));
        assert_eq!(v.cells().count(), 0);
    }
}
