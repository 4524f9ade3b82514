//! The all-knowing baseline (`[sensing] all_knowing = true`): every agent is told each close
//! and open of the scenario's `[[events]]` at the control period it happens in, wherever its
//! robot is, as if the swarm shared a perfect map; what it sees still comes on top (movers
//! are only seen). Experiments compare sensing and repairing with it (issue 35 item 9).
//!
//! The agent reads the events from the scenario it was started with, as the sim does, and
//! applies an event at the first control period whose sim time has reached it (the sim's rule
//! in `sim/src/world/changes.rs`), so a lockstep run stays reproducible.

use hnav_runtime::grid::Cell;
use hnav_runtime::scenario::Scenario;

/// The scenario's closes and opens, in time order, and how many were told.
pub(super) struct Oracle {
    /// (sim time s, cells, closed).
    events: Vec<(f64, Vec<Cell>, bool)>,
    told: usize,
}

impl Oracle {
    /// The oracle of `scenario`, when it is all-knowing.
    pub(super) fn of(scenario: &Scenario) -> Option<Self> {
        scenario.sensing.filter(|s| s.all_knowing)?;
        let events = scenario
            .events
            .iter()
            .filter_map(|e| {
                let (cells, closed) = e.change.cells()?;
                Some((e.at_s, cells.to_vec(), closed))
            })
            .collect();
        Some(Oracle { events, told: 0 })
    }

    /// Every (cell, blocked) of the events due by sim time `t_s` not told yet.
    pub(super) fn due(&mut self, t_s: f64) -> Vec<(Cell, bool)> {
        let mut out = Vec::new();
        while let Some((_, cells, closed)) =
            self.events.get(self.told).filter(|e| e.0 <= t_s + 1e-9)
        {
            out.extend(cells.iter().map(|&c| (c, *closed)));
            self.told += 1;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_are_told_once_when_their_time_has_come_and_movers_never() {
        let text = r#"
            name = "t"
            [map]
            rows = ["......", "......"]
            [sensing]
            all_knowing = true
            [[agents]]
            start = [0, 0]
            goal = [5, 0]
            [[events]]
            at_round = 10
            close = [[2, 1]]
            [[events]]
            at_round = 20
            mover = "p"
            path = [[5, 1], [3, 1]]
            speed = 1.0
            [[events]]
            at_round = 30
            open = [[2, 1]]
        "#;
        let s = Scenario::from_str(text, "t.toml", std::path::Path::new(".")).unwrap();
        let mut o = Oracle::of(&s).expect("all-knowing");
        assert!(
            o.due(0.05).is_empty(),
            "round 10 is 0.1 s at 100 Hz odometry"
        );
        assert_eq!(o.due(0.1), [(Cell::new(2, 1), true)]);
        assert!(
            o.due(0.25).is_empty(),
            "told once; the mover is not a change of the map"
        );
        assert_eq!(o.due(1.0), [(Cell::new(2, 1), false)]);
        let plain = text.replace("all_knowing = true", "");
        let s = Scenario::from_str(&plain, "t.toml", std::path::Path::new(".")).unwrap();
        assert!(Oracle::of(&s).is_none());
    }
}
