//! Where the benchmark's agents stand and what they ask for, round by round.
//!
//! The map is an open 36 x 36 grid (room for 306 agents, the round table's largest swarm 256
//! among them). Agents
//! come in pairs on odd rows: agent `2k` at `(x0, y)` and agent `2k + 1` at `(x0 + 2, y)` with
//! `x0 = 4 (k mod 9)` and `y = 1 + 2 (k div 9)`, so the cell between a pair, and the even
//! rows, are free. Every
//! agent is at rest (`current = next` = its start, never moved: the benchmark measures
//! rounds, not motion), and what it proposes cycles with the round:
//!
//! | round mod 4 | both agents of a pair propose | outcome |
//! |---|---|---|
//! | 0 | the cell between them | a crossing conflict: the right agent wins, the left is blocked |
//! | 1 | the cell below | all accepted |
//! | 2 | left: stand still (`NO_CELL`); right: the cell above | accepted, left holds |
//! | 3 | the cell diagonally below the middle cell | a diagonal crossing conflict, as in 0 |
//!
//! The right agent of a pair is the slower one (speed 0.5 against 1 cell/s), so it has the
//! higher priority (`1 / speed`) and wins the crossings. The left one is blocked at most two
//! rounds in a row, fewer than the scenario's `replan_after_rounds = 3`, so no round runs the
//! global planner. Goals are the starts
//! mirrored through the centre (even rows), distinct and never reached: no candidate says
//! `AT_GOAL`, so the coordinator never ends the run by itself.

use std::fmt::Write as _;

use hnav_runtime::msg::{Candidate, CandidateFlags, NO_CELL};
use hnav_runtime::scenario::FsyncPolicy;

/// Side of the square map, in cells.
pub const SIDE: u32 = 36;
/// Pairs per row of agents.
const PAIRS_PER_ROW: u32 = SIDE / 4;
/// Rows of agents (odd rows 1, 3, ..., 33: row 35 would have no free row below it).
const AGENT_ROWS: u32 = (SIDE - 2) / 2;
/// The largest swarm the layout holds: a pair of agents every four cells of every odd row.
pub const MAX_AGENTS: usize = (2 * PAIRS_PER_ROW * AGENT_ROWS) as usize;
// The round table measures up to 256 agents.
const _: () = assert!(MAX_AGENTS >= 256);

/// The layout of a swarm of `n` agents.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    n: usize,
}

impl Layout {
    /// A layout for `n` agents, 1 to [`MAX_AGENTS`].
    pub fn new(n: usize) -> Result<Self, String> {
        if n == 0 || n > MAX_AGENTS {
            return Err(format!(
                "{n} agents: the benchmark's {SIDE}x{SIDE} map holds 1 to {MAX_AGENTS}"
            ));
        }
        Ok(Self { n })
    }

    /// Number of agents.
    pub fn agents(&self) -> usize {
        self.n
    }

    /// Agent `i`'s start cell `(x, y)`.
    pub fn start(&self, i: usize) -> (u32, u32) {
        let k = i as u32 / 2;
        let side = i as u32 % 2;
        (
            4 * (k % PAIRS_PER_ROW) + 2 * side,
            1 + 2 * (k / PAIRS_PER_ROW),
        )
    }

    /// Agent `i`'s goal: its start mirrored through the centre of the map.
    pub fn goal(&self, i: usize) -> (u32, u32) {
        let (x, y) = self.start(i);
        (SIDE - 1 - x, SIDE - 1 - y)
    }

    /// Agent `i`'s candidate for `round`.
    pub fn candidate(&self, i: usize, round: u64) -> Candidate {
        let (x, y) = self.start(i);
        let left = i.is_multiple_of(2);
        // Towards the partner: the left agent looks right, the right one looks left.
        let toward = if left { x + 1 } else { x - 1 };
        let probable = match round % 4 {
            0 => Some((toward, y)),
            1 => Some((x, y + 1)),
            2 => (!left).then(|| (x, y - 1)),
            _ => Some((toward, y + 1)),
        };
        let current = index(x, y);
        Candidate {
            round,
            agent: i as u32,
            current,
            next: current,
            probable: probable.map_or(NO_CELL, |(x, y)| index(x, y)),
            priority: 1.0 / speed(i),
            speed: speed(i),
            flags: if probable.is_none() {
                CandidateFlags::STANDING
            } else {
                0
            },
            reserved: 0,
        }
    }

    /// The scenario file's text: the open map, the agents, the coordinator's fsync policy
    /// and its number of Raft replicas, the lockstep clock, a time limit no bench reaches.
    pub fn scenario_toml(&self, fsync: FsyncPolicy, replicas: u32) -> String {
        let mut s = String::from("# Written by `hnav-bench round`.\nname = \"bench-round\"\n\n");
        s.push_str("[map]\nrows = [\n");
        let row = ".".repeat(SIDE as usize);
        for _ in 0..SIDE {
            let _ = writeln!(s, "  \"{row}\",");
        }
        s.push_str("]\n\n[sim]\nclock = \"lockstep\"\n\n[coordinator]\n");
        let _ = writeln!(s, "fsync = \"{}\"", fsync_name(fsync));
        let _ = writeln!(s, "replicas = {replicas}");
        s.push_str("replan_after_rounds = 3\n");
        // The layout's conflicts (one loser per pair, every other round) are the dissertation
        // rules' decisions; the default `lacam` would plan them away.
        s.push_str("rules = \"dissertation\"\n");
        // The bench plays as many rounds as it is asked for: a lockstep coordinator ends the
        // run after its time limit's rounds (12 000 by default), so the limit is set far out.
        s.push_str("time_limit_s = 1e9\n");
        for i in 0..self.n {
            let (sx, sy) = self.start(i);
            let (gx, gy) = self.goal(i);
            let _ = write!(
                s,
                "\n[[agents]]\nstart = [{sx}, {sy}]\ngoal = [{gx}, {gy}]\nspeed = {}\n",
                speed(i)
            );
        }
        s
    }
}

/// Agent `i`'s nominal speed in cells/s: the right agent of a pair is the slower one.
fn speed(i: usize) -> f32 {
    if i % 2 == 1 {
        0.5
    } else {
        1.0
    }
}

/// Row-major cell index of `(x, y)`.
fn index(x: u32, y: u32) -> u32 {
    y * SIDE + x
}

/// The policy as the scenario file spells it.
pub fn fsync_name(p: FsyncPolicy) -> &'static str {
    match p {
        FsyncPolicy::EveryRecord => "every-record",
        FsyncPolicy::Batched => "batched",
        FsyncPolicy::None => "none",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::scenario::Scenario;
    use std::collections::HashSet;

    #[test]
    fn the_largest_swarm_fits_on_distinct_cells() {
        let l = Layout::new(MAX_AGENTS).unwrap();
        let starts: HashSet<_> = (0..MAX_AGENTS).map(|i| l.start(i)).collect();
        let goals: HashSet<_> = (0..MAX_AGENTS).map(|i| l.goal(i)).collect();
        assert_eq!(starts.len(), MAX_AGENTS);
        assert_eq!(goals.len(), MAX_AGENTS);
        assert!(starts.is_disjoint(&goals));
        assert!(Layout::new(0).is_err());
        assert!(Layout::new(MAX_AGENTS + 1).is_err());
    }

    #[test]
    fn candidates_name_cells_next_to_the_start_and_pairs_collide() {
        let l = Layout::new(MAX_AGENTS).unwrap();
        for round in 1..=8u64 {
            let mut claimed = HashSet::new();
            let mut repeats = 0;
            for i in 0..MAX_AGENTS {
                let c = l.candidate(i, round);
                assert!(c.current < SIDE * SIDE && c.next == c.current);
                if c.probable == NO_CELL {
                    assert_eq!(c.flags, CandidateFlags::STANDING);
                    continue;
                }
                let (cx, cy) = (c.current % SIDE, c.current / SIDE);
                let (px, py) = (c.probable % SIDE, c.probable / SIDE);
                assert!(px.abs_diff(cx) <= 1 && py.abs_diff(cy) <= 1 && c.probable < SIDE * SIDE);
                repeats += usize::from(!claimed.insert(c.probable));
            }
            // Conflict rounds: every pair claims one cell; the others: no shared cell.
            let expected = if round % 4 == 0 || round % 4 == 3 {
                MAX_AGENTS / 2
            } else {
                0
            };
            assert_eq!(repeats, expected, "round {round}");
        }
    }

    #[test]
    fn the_coordinators_arbiter_sees_conflicts_but_never_replans() {
        use hnav_coordinator::round::Arbiter;
        use hnav_runtime::msg::Verdict;
        for n in [1, 8, 128] {
            let l = Layout::new(n).unwrap();
            let s = Scenario::from_str(
                &l.scenario_toml(FsyncPolicy::None, 1),
                "bench.toml",
                std::path::Path::new("."),
            )
            .unwrap();
            let mut arbiter = Arbiter::new(&s);
            let mut blocked = 0;
            for round in 1..=40u64 {
                let cands: Vec<_> = (0..n).map(|i| Some(l.candidate(i, round))).collect();
                // A candidate the coordinator drops as hostile would stall the bench's round.
                for c in cands.iter().flatten() {
                    assert_eq!(arbiter.classify(c, round - 1), Ok(()), "{c:?}");
                }
                let (decisions, replans) = arbiter.decide(round, &cands);
                assert!(replans.is_empty(), "{n} agents, round {round}");
                for d in decisions {
                    let v = Verdict::from_u8(d.verdict);
                    assert!(matches!(
                        v,
                        Some(Verdict::Accept | Verdict::Block | Verdict::Hold)
                    ));
                    blocked += usize::from(v != Some(Verdict::Accept));
                }
            }
            // Two conflict rounds in four, one loser per pair: the left agent.
            assert_eq!(blocked, 20 * (n / 2), "{n} agents");
            assert_eq!(
                arbiter.tally().agents()[0].conflicts as usize,
                20 * usize::from(n > 1)
            );
        }
    }

    #[test]
    fn the_scenario_parses_with_the_layout() {
        let l = Layout::new(9).unwrap();
        let s = Scenario::from_str(
            &l.scenario_toml(FsyncPolicy::None, 1),
            "bench.toml",
            std::path::Path::new("."),
        )
        .unwrap();
        assert_eq!(s.agents.len(), 9);
        assert_eq!(s.coordinator.fsync, FsyncPolicy::None);
        assert_eq!(s.map.grid.width(), SIDE);
        assert_eq!(s.coordinator.replicas, 1);
        let (x, y) = l.start(8);
        assert_eq!((s.agents[8].start.x, s.agents[8].start.y), (x, y));
        for n in [3, 5] {
            let s = Scenario::from_str(
                &l.scenario_toml(FsyncPolicy::EveryRecord, n),
                "bench.toml",
                std::path::Path::new("."),
            )
            .unwrap();
            assert_eq!(s.coordinator.replicas, n);
        }
    }
}
