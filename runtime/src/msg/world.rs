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

/// The user header of the coordinator's map (`world`, a `[u32]` slice): the cells whose state
/// differs from the scenario's map after round `round`, the `closed` cells that are closed now
/// first, then the opened ones, each ascending. A whole picture, not a difference from the
/// last sample, so the newest sample is all a reader needs.
///
/// Sent to the agents that restarted: the others learn the world by their own sensing only,
/// as `[sensing]` promises; one sample answers every agent that restarted since the last, so
/// a shallow buffer never drops one's answer. Whom it answers opens the slice: `to` words of
/// one bit per agent (bit `i % 32` of word `i / 32` for agent `i`), as many as the run's
/// agents need, so the header keeps its size whatever the swarm's.
///
/// The slice is `[addressees: to words][closed cells][opened cells]`;
/// [`WorldHeader::split`] reads it.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
#[type_name("hnav::WorldHeader")]
pub struct WorldHeader {
    /// The last round decided on this map.
    pub round: u64,
    /// How many of the slice's cells closed (they come first after the addressees).
    pub closed: u32,
    /// How many opened (they follow): with `to` and `closed`, the slice's length, said again
    /// for readers whose binding reports a slice's length in bytes (iceoryx2's Python does).
    pub opened: u32,
    /// Words of addressee bits that open the slice ([`WorldHeader::words_for`] the run).
    pub to: u32,
    /// Zero.
    pub reserved: u32,
}

impl WorldHeader {
    /// Words of addressee bits for a run of `agents`.
    pub fn words_for(agents: usize) -> usize {
        agents.div_ceil(32)
    }

    /// A sample's slice as its addressee words and its cells (closed, then opened); a header
    /// that claims more words than the slice holds reads as all of it addressees.
    pub fn split<'a>(&self, slice: &'a [u32]) -> (&'a [u32], &'a [u32]) {
        slice.split_at((self.to as usize).min(slice.len()))
    }

    /// Adds agent `i` to the addressee words `to` (an index beyond them is ignored).
    pub fn address(to: &mut [u32], i: usize) {
        if let Some(w) = to.get_mut(i / 32) {
            *w |= 1 << (i % 32);
        }
    }

    /// Whether agent `i` is among the addressee words `to`.
    pub fn is_for(to: &[u32], i: usize) -> bool {
        to.get(i / 32).is_some_and(|w| w >> (i % 32) & 1 != 0)
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
        assert_eq!(size_of::<WorldHeader>(), 24);
        assert_eq!(align_of::<WorldHeader>(), 8);
        assert_eq!(offset_of!(WorldHeader, round), 0);
        assert_eq!(offset_of!(WorldHeader, closed), 8);
        assert_eq!(offset_of!(WorldHeader, opened), 12);
        assert_eq!(offset_of!(WorldHeader, to), 16);
        assert_eq!(offset_of!(WorldHeader, reserved), 20);
    }

    #[test]
    fn a_world_header_says_whom_it_answers() {
        let h = WorldHeader {
            to: WorldHeader::words_for(40) as u32,
            closed: 1,
            opened: 1,
            ..WorldHeader::default()
        };
        let mut slice = vec![0, 0, 17, 18];
        WorldHeader::address(&mut slice[..2], 0);
        WorldHeader::address(&mut slice[..2], 37);
        WorldHeader::address(&mut slice[..2], 100_000);
        let (to, cells) = h.split(&slice);
        assert_eq!(cells, [17, 18]);
        assert!(WorldHeader::is_for(to, 0) && WorldHeader::is_for(to, 37));
        assert!(!WorldHeader::is_for(to, 1) && !WorldHeader::is_for(to, 100_000));
        let liar = WorldHeader { to: 9, ..h };
        assert_eq!(liar.split(&slice), (&slice[..], &[][..]));
        assert_eq!(WorldHeader::words_for(4096), 128);
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
