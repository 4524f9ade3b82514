//! The swarm's shared picture of a changing world (`[sensing]`): the cells agents saw change
//! ([`Sighting`], agent -> coordinator) and the coordinator's map as it now stands
//! ([`WorldHeader`] over a `[u32]` slice, coordinator -> a restarted agent).
//!
//! The coordinator plans and resolves conflicts on the map it accepted from these sightings
//! and logs each accepted change (a map-change record), so the log says on which map every
//! round was decided.

use iceoryx2::prelude::ZeroCopySend;

/// The most cells one [`Sighting`] carries; an agent that saw more sends several.
pub const SIGHTING_CELLS: usize = 32;

/// Cells agent `agent` saw change from its map, sent just before its candidate for `round`
/// (so in lockstep the coordinator holds every sighting of a round when it decides it).
/// Cell `cells[k]` (`k < count`) closed if bit `k` of `closed` is set, else opened.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
#[type_name("hnav::Sighting")]
pub struct Sighting {
    /// The round of the candidate it precedes.
    pub round: u64,
    /// Agent (robot) index.
    pub agent: u32,
    /// Cells used of `cells` (at most [`SIGHTING_CELLS`]).
    pub count: u32,
    /// Bit `k`: `cells[k]` closed (else it opened).
    pub closed: u32,
    /// Zero.
    pub reserved: u32,
    /// Row-major cell indices.
    pub cells: [u32; SIGHTING_CELLS],
}

impl Default for Sighting {
    fn default() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}

impl Sighting {
    /// An empty sighting of `agent` for `round`.
    pub fn new(round: u64, agent: u32) -> Self {
        Sighting {
            round,
            agent,
            ..Default::default()
        }
    }

    /// Adds `cell` (closed or opened); `false` when the sighting is full.
    pub fn push(&mut self, cell: u32, closed: bool) -> bool {
        let k = self.count as usize;
        if k >= SIGHTING_CELLS {
            return false;
        }
        self.cells[k] = cell;
        if closed {
            self.closed |= 1 << k;
        }
        self.count += 1;
        true
    }

    /// Every cell, as (cell, closed); a `count` beyond [`SIGHTING_CELLS`] (a sender's bug) is
    /// cut to it.
    pub fn changes(&self) -> impl Iterator<Item = (u32, bool)> + '_ {
        let n = (self.count as usize).min(SIGHTING_CELLS);
        (0..n).map(move |k| (self.cells[k], self.closed >> k & 1 != 0))
    }
}

/// Words of [`WorldHeader::to`]: one bit per agent.
pub const WORLD_TO_WORDS: usize = crate::msg::MAX_AGENTS / 32;

/// The user header of the coordinator's map (`world`, a `[u32]` slice): the cells whose state
/// differs from the scenario's map after round `round`, the `closed` cells that are closed now
/// first, then the opened ones, each ascending. A whole picture, not a difference from the
/// last sample, so the newest sample is all a reader needs.
///
/// Sent to the agents that restarted (bit `i % 32` of `to[i / 32]` for agent `i`): the others
/// learn the world by their own sensing only, as `[sensing]` promises; one sample answers every
/// agent that restarted since the last, so a shallow buffer never drops one's answer.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
#[type_name("hnav::WorldHeader")]
pub struct WorldHeader {
    /// The last round decided on this map.
    pub round: u64,
    /// How many of the slice's cells closed (they come first).
    pub closed: u32,
    /// How many opened (they follow): with `closed`, the slice's length, said again for
    /// readers whose binding reports a slice's length in bytes (iceoryx2's Python does).
    pub opened: u32,
    /// The agents it answers, one bit each.
    pub to: [u32; WORLD_TO_WORDS],
}

impl WorldHeader {
    /// Adds agent `i` to the addressees (an index beyond the bits is ignored).
    pub fn address(&mut self, i: usize) {
        if let Some(w) = self.to.get_mut(i / 32) {
            *w |= 1 << (i % 32);
        }
    }

    /// Whether agent `i` is an addressee.
    pub fn is_for(&self, i: usize) -> bool {
        self.to.get(i / 32).is_some_and(|w| w >> (i % 32) & 1 != 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::mem::{align_of, offset_of, size_of};

    #[test]
    fn sighting_layout() {
        assert_eq!(size_of::<Sighting>(), 152);
        assert_eq!(align_of::<Sighting>(), 8);
        assert_eq!(offset_of!(Sighting, round), 0);
        assert_eq!(offset_of!(Sighting, agent), 8);
        assert_eq!(offset_of!(Sighting, count), 12);
        assert_eq!(offset_of!(Sighting, closed), 16);
        assert_eq!(offset_of!(Sighting, reserved), 20);
        assert_eq!(offset_of!(Sighting, cells), 24);
    }

    #[test]
    fn world_header_layout() {
        assert_eq!(size_of::<WorldHeader>(), 48);
        assert_eq!(align_of::<WorldHeader>(), 8);
        assert_eq!(offset_of!(WorldHeader, round), 0);
        assert_eq!(offset_of!(WorldHeader, closed), 8);
        assert_eq!(offset_of!(WorldHeader, opened), 12);
        assert_eq!(offset_of!(WorldHeader, to), 16);
    }

    #[test]
    fn a_world_header_says_whom_it_answers() {
        let mut h = WorldHeader::default();
        h.address(0);
        h.address(37);
        h.address(100_000);
        assert!(h.is_for(0) && h.is_for(37));
        assert!(!h.is_for(1) && !h.is_for(36) && !h.is_for(100_000));
    }

    #[test]
    fn a_sighting_keeps_what_was_pushed_until_full() {
        let mut s = Sighting::new(7, 2);
        assert!(s.push(10, true));
        assert!(s.push(11, false));
        assert_eq!(s.changes().collect::<Vec<_>>(), [(10, true), (11, false)]);
        for c in 2..SIGHTING_CELLS as u32 {
            assert!(s.push(c, c % 2 == 0));
        }
        assert!(!s.push(99, true), "a full sighting takes no more");
        assert_eq!(s.changes().count(), SIGHTING_CELLS);
        s.count = 1000;
        assert_eq!(s.changes().count(), SIGHTING_CELLS, "a bad count is cut");
    }
}
