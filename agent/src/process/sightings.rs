//! What the agent tells the coordinator of the world (`[sensing]`): the cells its robot saw
//! differ from the swarm's picture, as far as this agent knows that picture.
//!
//! The picture starts as the scenario's map, whatever the agent itself knows of it (an
//! unmapped agent, `known_map = false`, still reports only changes, not every wall it first
//! sees), and follows what the robot saw and what the coordinator sent. A cell is reported
//! when it is seen in another state than the picture's, once, with the candidate that follows
//! (stamped with its round, so that a lockstep round is decided on exactly the sightings sent
//! before it). The coordinator decides what it accepts; a sighting it never received (it died
//! first) is not sent again until the cell changes once more.

use hnav_runtime::grid::Grid;
use hnav_runtime::msg::{ConflictKind, Decision, Sighting, Verdict, View, NO_CELL};
use hnav_runtime::transport::{Sender, TransportError};

/// The agent's copy of the swarm's picture and the changes not reported yet.
pub(super) struct Sightings {
    /// Per cell, blocked in the picture.
    picture: Vec<bool>,
    width: u32,
    /// (cell, closed) seen since the last candidate, oldest first.
    unsent: Vec<(u32, bool)>,
}

impl Sightings {
    /// The picture of the scenario's `map`.
    pub(super) fn new(map: &Grid) -> Self {
        Sightings {
            picture: map.blocked().to_vec(),
            width: map.width(),
            unsent: Vec::new(),
        }
    }

    /// Notes every cell of `view` seen in another state than the picture's, but a mover's.
    pub(super) fn fold(&mut self, view: &View) {
        // A mover's cells are not a change of the map: the coordinator would close and open
        // them behind every person walking by.
        for (x, y, blocked) in view.cells().filter(|&(x, y, _)| !view.is_moving(x, y)) {
            self.see(y * self.width + x, blocked);
        }
    }

    /// Notes `cell` if it is `blocked` otherwise than in the picture (seen, or told by the
    /// all-knowing baseline, which the agent reports like a sighting).
    pub(super) fn see(&mut self, cell: u32, blocked: bool) {
        if let Some(known) = self
            .picture
            .get_mut(cell as usize)
            .filter(|k| **k != blocked)
        {
            *known = blocked;
            self.unsent.push((cell, blocked));
        }
    }

    /// Takes the coordinator's word on `cell` (the map it sent a restarted agent).
    pub(super) fn learn(&mut self, cell: u32, blocked: bool) {
        if let Some(known) = self.picture.get_mut(cell as usize) {
            *known = blocked;
        }
    }

    /// Takes the coordinator's word from decision `d`: a step held or refused as invalid names
    /// a cell closed on its map. The picture follows, so that the next view that shows the
    /// cell open reports it: the coordinator learned the cell closed from another robot, and
    /// no robot that saw it open again told it so (the first to see a door open had never seen
    /// it shut, and its picture had it open all along).
    pub(super) fn refused(&mut self, d: &Decision) {
        let invalid = d.kind == ConflictKind::Invalid as u8 && d.verdict != Verdict::Accept as u8;
        if invalid && d.cell != NO_CELL {
            self.learn(d.cell, true);
        }
    }

    /// Sends what was seen since the last call, as agent `agent`'s sightings before its
    /// candidate for `round`, silently: the candidate that follows wakes the coordinator.
    pub(super) fn send(
        &mut self,
        tx: &Sender<Sighting>,
        round: u64,
        agent: u32,
    ) -> Result<(), TransportError> {
        for chunk in self.unsent.chunks(hnav_runtime::msg::SIGHTING_CELLS) {
            let mut s = Sighting::new(round, agent);
            for &(cell, closed) in chunk {
                s.push(cell, closed);
            }
            tx.send_silently(s)?;
        }
        self.unsent.clear();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_change_is_reported_once_and_a_known_wall_never() {
        let mut map = Grid::new(4, 4).unwrap();
        map.set_blocked(hnav_runtime::grid::Cell::new(0, 0), true);
        let mut s = Sightings::new(&map);
        let mut v = View::default();
        v.reset(0, 0, 4);
        v.mark(0, 0, true); // a wall of the map: no news
        v.mark(1, 0, true); // closed
        v.mark(2, 0, false);
        s.fold(&v);
        s.fold(&v);
        assert_eq!(s.unsent, [(1, true)]);
        let mut v = View::default();
        v.reset(0, 0, 4);
        v.mark(1, 0, false); // opened again
        s.fold(&v);
        assert_eq!(s.unsent, [(1, true), (1, false)]);
        s.learn(5, true);
        let mut v = View::default();
        v.reset(0, 0, 4);
        v.mark(1, 1, true); // cell 5: the coordinator said so already
        s.fold(&v);
        assert_eq!(s.unsent.len(), 2);
        let mut v = View::default();
        v.reset(0, 0, 4);
        v.mark(3, 3, true);
        v.mark_moving(3, 3); // a person walking by: no change of the map
        s.fold(&v);
        assert_eq!(s.unsent.len(), 2);
    }

    #[test]
    fn a_step_held_as_invalid_makes_the_next_view_of_the_cell_open_news() {
        let map = Grid::new(4, 4).unwrap();
        let mut s = Sightings::new(&map);
        let open = |s: &mut Sightings| {
            let mut v = View::default();
            v.reset(0, 0, 4);
            v.mark(2, 1, false);
            s.fold(&v);
        };
        // Another robot saw (2, 1) shut and the coordinator closed it; this agent never saw
        // it shut: seeing it open is no news to its picture.
        open(&mut s);
        assert!(s.unsent.is_empty());
        // A Crossing hold says nothing about the map.
        let mut d = Decision {
            verdict: Verdict::Hold as u8,
            kind: ConflictKind::Crossing as u8,
            cell: 6,
            ..Decision::default()
        };
        s.refused(&d);
        open(&mut s);
        assert!(s.unsent.is_empty());
        // Its step into (2, 1) held as invalid: the coordinator has the cell closed, and the
        // view that shows it open reports it.
        d.kind = ConflictKind::Invalid as u8;
        s.refused(&d);
        assert!(
            s.unsent.is_empty(),
            "the coordinator's word is not news to it"
        );
        open(&mut s);
        assert_eq!(s.unsent, [(6, false)]);
    }
}
