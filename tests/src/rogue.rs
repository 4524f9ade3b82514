//! The hostile candidates `hnav-rogue` publishes: one [`Rejected`] class at a time, or all of
//! them in turn for a flood.
//!
//! Each forged candidate is a real agent's candidate (its index, its start cell, the open
//! round, the scenario's priority and speed) with exactly one thing wrong, the thing its
//! class names, so that only that class's check stands between it and the round's decisions:
//! a coordinator without the check would take it as the agent's candidate and the lockstep
//! log would change.

use hnav_runtime::hash::SplitMix64;
use hnav_runtime::msg::{Candidate, CandidateFlags, NO_CELL};
use hnav_runtime::rejected::Rejected;
use hnav_runtime::scenario::Scenario;

/// Rounds a forged future round lies ahead of the open round as the rogue last saw it, at
/// least: far more than the coordinator can decide while a forged sample is in flight.
const FUTURE_MARGIN: u64 = 10_000;

/// What `hnav-rogue --class` attacks with.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Attack {
    /// Candidates of one class, at a modest rate.
    Class(Rejected),
    /// Candidates of every class in turn, as fast as the transport takes them.
    Flood,
}

impl Attack {
    /// The attack named `name`: a [`Rejected`] class name or `flood`.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "flood" => Some(Attack::Flood),
            _ => Rejected::from_name(name).map(Attack::Class),
        }
    }

    /// Every attack's name, for help and error messages.
    pub fn names() -> String {
        let mut names: Vec<&str> = Rejected::ALL.iter().map(|c| c.name()).collect();
        names.push("flood");
        names.join(", ")
    }
}

/// Forges hostile candidates for one scenario's run.
pub struct Forger {
    rng: SplitMix64,
    cells: u32,
    width: u32,
    starts: Vec<u32>,
    claims: Vec<(f32, f32)>,
    turn: usize,
}

impl Forger {
    /// A forger for `scenario`'s agents and map, drawing from `seed`.
    pub fn new(scenario: &Scenario, seed: u64) -> Self {
        let g = &scenario.map.grid;
        Self {
            rng: SplitMix64::new(seed),
            cells: g.len() as u32,
            width: g.width(),
            starts: scenario
                .agents
                .iter()
                .map(|a| g.index(a.start) as u32)
                .collect(),
            claims: scenario
                .agents
                .iter()
                .map(|a| (a.effective_priority() as f32, a.speed as f32))
                .collect(),
            turn: 0,
        }
    }

    /// The next candidate of `attack` when the last commit seen was `last_commit`, with the
    /// class it belongs to.
    pub fn next(&mut self, attack: Attack, last_commit: u64) -> (Rejected, Candidate) {
        let class = match attack {
            Attack::Class(c) => c,
            Attack::Flood => {
                self.turn = (self.turn + 1) % Rejected::ALL.len();
                Rejected::ALL[self.turn]
            }
        };
        (class, self.forge(class, last_commit))
    }

    /// A candidate that only `class`'s check refuses.
    pub fn forge(&mut self, class: Rejected, last_commit: u64) -> Candidate {
        let agents = self.starts.len() as u64;
        let i = self.rng.below(agents.max(1)) as usize;
        let start = self.starts.get(i).copied().unwrap_or(0);
        let (priority, speed) = self.claims.get(i).copied().unwrap_or((1.0, 1.0));
        let mut c = Candidate {
            round: last_commit + 1,
            agent: i as u32,
            current: start,
            next: start,
            probable: NO_CELL,
            priority,
            speed,
            flags: 0,
            reserved: 0,
        };
        match class {
            Rejected::Agent => {
                c.agent = (agents + self.rng.below(u64::from(u32::MAX) - agents)) as u32;
            }
            Rejected::Flags => {
                if self.rng.below(2) == 0 {
                    let unknown = !CandidateFlags::ALL;
                    c.flags = unknown & (1 << (5 + self.rng.below(27)));
                } else {
                    c.reserved = 1 + self.rng.below(u64::from(u32::MAX)) as u32;
                }
            }
            Rejected::PrioritySpeed => {
                let bad = [
                    f32::NAN,
                    f32::INFINITY,
                    f32::NEG_INFINITY,
                    -1.0,
                    -0.0,
                    priority * 2.0 + 1.0,
                ];
                let v = bad[self.rng.below(bad.len() as u64) as usize];
                let field = if self.rng.below(2) == 0 {
                    &mut c.priority
                } else {
                    &mut c.speed
                };
                // A scenario may give a negative priority; the forged one must differ.
                *field = if v.to_bits() == field.to_bits() {
                    f32::NAN
                } else {
                    v
                };
            }
            Rejected::Cell => self.bad_cells(&mut c),
            Rejected::FutureRound => {
                c.round = match self.rng.below(4) {
                    0 => u64::MAX,
                    _ => last_commit + FUTURE_MARGIN + self.rng.below(1 << 20),
                };
            }
            Rejected::PastRound => {
                // At most the last round seen, which the coordinator has decided already.
                c.round = last_commit.saturating_sub(self.rng.below(4));
            }
        }
        c
    }

    /// Makes one of `c`'s cells impossible: off the map, or not a neighbour where one must be.
    fn bad_cells(&mut self, c: &mut Candidate) {
        let off_map = self.cells + self.rng.below(u64::from(u32::MAX - self.cells)) as u32;
        let far = self.far_from(c.current);
        match self.rng.below(5) {
            0 => c.current = off_map,
            1 => c.next = off_map,
            2 => c.probable = off_map,
            3 => c.next = far.unwrap_or(off_map),
            _ => c.probable = far.unwrap_or(off_map),
        }
    }

    /// A cell of the map that is neither `cell` nor one of its neighbours, if the map has one.
    fn far_from(&mut self, cell: u32) -> Option<u32> {
        let (x, y) = (cell % self.width, cell / self.width);
        let offset = self.rng.below(u64::from(self.cells)) as u32;
        (0..self.cells)
            .map(|k| (offset + k) % self.cells)
            .find(|&v| (v % self.width).abs_diff(x) > 1 || (v / self.width).abs_diff(y) > 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_coordinator::round::Arbiter;

    const ROOM: &str = r#"
        name = "room"
        [map]
        rows = ["......", "......", "......", "......"]
        [coordinator]
        rules = "dissertation"
        [[agents]]
        start = [0, 0]
        goal = [5, 3]
        [[agents]]
        start = [5, 0]
        goal = [0, 3]
        speed = 0.5
        priority = 3
    "#;

    #[test]
    fn every_forged_candidate_is_refused_for_its_own_class() {
        let s = Scenario::from_str(ROOM, "room.toml", std::path::Path::new(".")).unwrap();
        let arbiter = Arbiter::new(&s);
        let mut forger = Forger::new(&s, 7);
        for decided in [0, 1, 40] {
            for class in Rejected::ALL {
                for _ in 0..300 {
                    let c = forger.forge(class, decided);
                    assert_eq!(arbiter.classify(&c, decided), Err(class), "{c:?}");
                }
            }
            let mut seen = std::collections::HashSet::new();
            for _ in 0..60 {
                let (class, c) = forger.next(Attack::Flood, decided);
                assert_eq!(arbiter.classify(&c, decided), Err(class), "{c:?}");
                seen.insert(class);
            }
            assert_eq!(seen.len(), Rejected::ALL.len(), "a flood mixes every class");
        }
    }

    #[test]
    fn attacks_are_named_like_the_classes() {
        assert_eq!(Attack::from_name("flood"), Some(Attack::Flood));
        assert_eq!(
            Attack::from_name("priority-speed"),
            Some(Attack::Class(Rejected::PrioritySpeed))
        );
        assert_eq!(Attack::from_name("teleport"), None);
        assert!(Attack::names().ends_with("past-round, flood"));
    }
}
