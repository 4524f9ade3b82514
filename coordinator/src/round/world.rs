//! The map the coordinator decides on in a changing world (`[sensing]`): the scenario's map
//! with every change an agent saw and the coordinator accepted (a map-change record each).
//!
//! A sighting is taken cell by cell. A cell whose reported state differs from the
//! coordinator's map changes; the others are news to nobody, so the first agent to see a door
//! close is the one logged and the next ones change nothing. A later sighting of the opposite
//! state (the door opened again) is a change again. Within one agent's sightings of a round
//! its last word on a cell counts. The agent is trusted with what it saw (its sensor is the
//! sim's truth); the one cell it is not trusted with is one a robot holds (stands on or is
//! committed to): closing it would hold a robot inside a wall, so such a cell stays open until
//! the robot has left it and an agent sees it closed again.

use std::collections::BTreeMap;

use hnav_runtime::consensus_log::MapChangeRecord;

use super::{Arbiter, Round};

impl Arbiter {
    /// The record of what agent `agent`'s sightings `changes` (cell, closed; oldest first)
    /// change on the map, to be logged before round `round` and then applied with
    /// [`Arbiter::apply_map_change`]; `None` when they change nothing.
    pub fn map_change(
        &self,
        round: u64,
        agent: u32,
        changes: impl IntoIterator<Item = (u32, bool)>,
    ) -> Option<MapChangeRecord> {
        let last_word: BTreeMap<u32, bool> = changes.into_iter().collect();
        let (mut closed, mut opened) = (Vec::new(), Vec::new());
        for (c, close) in last_word {
            let Some(cell) = self.grid.cell_at(c as usize) else {
                continue;
            };
            let held = self
                .rows
                .iter()
                .any(|r| r.current == cell || r.next == cell);
            match (close, self.grid.is_blocked(cell)) {
                (true, false) if !held => closed.push(c),
                (false, true) => opened.push(c),
                _ => {}
            }
        }
        (!closed.is_empty() || !opened.is_empty()).then_some(MapChangeRecord {
            round,
            agent,
            closed,
            opened,
        })
    }

    /// Decides from now on on the map `m` changed (a logged record, or one just made by
    /// [`Arbiter::map_change`]); the rules' tables follow the new map.
    pub fn apply_map_change(&mut self, m: &MapChangeRecord) {
        for (c, close) in m.changes() {
            if let Some(cell) = self.grid.cell_at(c as usize) {
                self.grid.set_blocked(cell, close);
            }
        }
        match &mut self.round {
            Round::Dissertation(r) => r.set_map(&self.grid),
            Round::Pibt(p) => p.set_map(&self.grid),
            Round::Lacam(l) => l.set_map(&self.grid),
        }
    }

    /// The map as it stands against the scenario's: the cells closed now that were open at
    /// the start, then those open now that were walls, each ascending. Written into `out`
    /// (cleared first); returns how many closed.
    pub fn world(&self, out: &mut Vec<u32>) -> usize {
        out.clear();
        let now = self.grid.blocked();
        let differs = |want: bool| {
            (0..now.len())
                .filter(move |&i| now[i] == want && self.start[i] != want)
                .map(|i| i as u32)
        };
        out.extend(differs(true));
        let closed = out.len();
        out.extend(differs(false));
        closed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::grid::Cell;
    use hnav_runtime::msg::{Candidate, Verdict, NO_CELL};
    use hnav_runtime::scenario::Scenario;

    /// A corridor with a wall at (3, 0); agent 0 at (0, 1) heading east, agent 1 at (6, 2).
    fn scenario(rules: &str) -> Scenario {
        let text = format!(
            r#"
            name = "t"
            [map]
            rows = ["...@....", "........", "........"]
            [coordinator]
            rules = "{rules}"
            [[agents]]
            start = [0, 1]
            goal = [7, 1]
            [[agents]]
            start = [6, 2]
            goal = [0, 2]
            "#
        );
        Scenario::from_str(&text, "test.toml", std::path::Path::new(".")).unwrap()
    }

    fn at(s: &Scenario, x: u32, y: u32) -> u32 {
        s.map.grid.index(Cell::new(x, y)) as u32
    }

    #[test]
    fn only_what_differs_changes_the_last_word_counts_and_a_held_cell_stays_open() {
        let s = scenario("dissertation");
        let a = Arbiter::new(&s);
        let (wall, free, held) = (at(&s, 3, 0), at(&s, 4, 0), at(&s, 6, 2));
        let seen = [
            (wall, true),  // a wall already
            (free, false), // open already, then closed: the last word
            (free, true),
            (held, true),        // agent 1 stands there
            (wall + 1000, true), // off the grid
        ];
        let m = a.map_change(5, 2, seen).unwrap();
        assert_eq!((m.round, m.agent), (5, 2));
        assert_eq!((m.closed, m.opened), (vec![free], vec![]));
        assert!(a.map_change(5, 0, [(free, false), (wall, true)]).is_none());
        let m = a.map_change(5, 0, [(wall, false)]).unwrap();
        assert_eq!((m.closed, m.opened), (vec![], vec![wall]));
    }

    #[test]
    fn the_world_is_the_difference_from_the_scenario_map() {
        let s = scenario("dissertation");
        let mut a = Arbiter::new(&s);
        let (wall, free) = (at(&s, 3, 0), at(&s, 1, 2));
        let mut out = vec![99];
        assert_eq!(a.world(&mut out), 0);
        assert!(out.is_empty());
        let m = a.map_change(1, 0, [(free, true), (wall, false)]).unwrap();
        a.apply_map_change(&m);
        assert_eq!(a.world(&mut out), 1);
        assert_eq!(out, [free, wall]);
        let back = a.map_change(2, 1, [(free, false), (wall, true)]).unwrap();
        a.apply_map_change(&back);
        assert_eq!(a.world(&mut out), 0);
        assert!(out.is_empty(), "back to the scenario's map: {out:?}");
    }

    #[test]
    fn every_rule_decides_on_the_changed_map() {
        for rules in ["dissertation", "pibt", "lacam"] {
            let s = scenario(rules);
            let mut a = Arbiter::new(&s);
            let door = at(&s, 1, 1);
            let m = a.map_change(1, 1, [(door, true)]).unwrap();
            a.apply_map_change(&m);
            let here = at(&s, 0, 1);
            let c0 = Candidate {
                round: 1,
                agent: 0,
                current: here,
                next: here,
                probable: door,
                ..Candidate::default()
            };
            let c1 = Candidate {
                agent: 1,
                current: at(&s, 6, 2),
                next: at(&s, 6, 2),
                probable: NO_CELL,
                ..c0
            };
            let (d, _) = a.decide(1, &[Some(c0), Some(c1)]);
            let into_door = d
                .iter()
                .any(|d| d.verdict == Verdict::Accept as u8 && d.cell == door);
            assert!(
                !into_door,
                "{rules}: a robot was let into the closed cell: {d:?}"
            );
        }
    }
}
