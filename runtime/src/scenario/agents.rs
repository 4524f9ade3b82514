//! Growing or shrinking a scenario's agent set (`hnav check --agents N`, benchmarks).
//!
//! Extra agents get seeded random starts and goals: free cells, every start distinct from all
//! other starts, every goal distinct from all other goals, start != goal, and the goal
//! reachable from the start under the map's corner-cutting rule (checked with a BFS flood).
//! The random numbers come from a tiny SplitMix64 so that the placement is identical on every
//! platform and every version of HNAV for a given seed, without pulling in `rand`.

use std::collections::HashSet;

use super::error::{Loc, ScenarioError};
use super::{AgentSpec, FaultTarget, Scenario};
use crate::grid::{reachable_from, Cell, Grid};

/// SplitMix64 (Steele, Lea, Flood 2014): a 64-bit state, good statistical quality for
/// placement purposes, and trivially reproducible.
#[derive(Clone, Debug)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator with the given seed.
    pub fn new(seed: u64) -> Self {
        SplitMix64 { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A uniform number in `0..n` (`n > 0`), without modulo bias (Lemire's multiply-shift
    /// with rejection).
    pub fn below(&mut self, n: u64) -> u64 {
        if n == 0 {
            return 0;
        }
        let threshold = n.wrapping_neg() % n;
        loop {
            let m = u128::from(self.next_u64()) * u128::from(n);
            if (m as u64) >= threshold {
                return (m >> 64) as u64;
            }
        }
    }
}

/// Connected-component label of every free cell (`u32::MAX` for blocked cells).
fn components(grid: &Grid, rule: crate::grid::CornerCutting) -> Vec<u32> {
    let mut label = vec![u32::MAX; grid.len()];
    let mut next = 0u32;
    for cell in grid.passable_cells() {
        if label[grid.index(cell)] != u32::MAX {
            continue;
        }
        for (i, reached) in reachable_from(grid, cell, rule).into_iter().enumerate() {
            if reached {
                label[i] = next;
            }
        }
        next += 1;
    }
    label
}

/// See [`Scenario::with_agent_count`].
pub(super) fn with_agent_count(
    s: &Scenario,
    n: usize,
    seed: u64,
) -> Result<Scenario, ScenarioError> {
    let at = Loc::new(&s.source_name, 0);
    if n == 0 {
        return Err(ScenarioError::NoAgents { at });
    }
    let mut out = s.clone();
    if n <= s.agents.len() {
        out.agents.truncate(n);
        for (i, f) in out.faults.iter().enumerate() {
            if let FaultTarget::Agent(a) = f.target {
                if a >= n {
                    let index = i64::try_from(a).unwrap_or(i64::MAX);
                    return Err(ScenarioError::FaultAgentOutOfRange {
                        at,
                        fault: i,
                        index,
                        agents: n,
                    });
                }
            }
        }
        return Ok(out);
    }

    let grid = &s.map.grid;
    let label = components(grid, s.map.corner_cutting);
    let mut starts: HashSet<Cell> = s.agents.iter().map(|a| a.start).collect();
    let mut goals: HashSet<Cell> = s.agents.iter().map(|a| a.goal).collect();
    let mut rng = SplitMix64::new(seed);
    let free: Vec<Cell> = grid.passable_cells().collect();
    while out.agents.len() < n {
        // Candidate starts: free, unused as a start, with a usable goal somewhere in their
        // component. Rebuilt per agent; scenarios are small next to the map.
        let mut candidates: Vec<Cell> = free
            .iter()
            .copied()
            .filter(|c| !starts.contains(c))
            .collect();
        let mut placed = false;
        while !candidates.is_empty() {
            let k = rng.below(candidates.len() as u64) as usize;
            let start = candidates.swap_remove(k);
            let comp = label[grid.index(start)];
            let goal_options: Vec<Cell> = free
                .iter()
                .copied()
                .filter(|&c| c != start && label[grid.index(c)] == comp && !goals.contains(&c))
                .collect();
            if goal_options.is_empty() {
                continue;
            }
            let goal = goal_options[rng.below(goal_options.len() as u64) as usize];
            starts.insert(start);
            goals.insert(goal);
            out.agents.push(AgentSpec {
                start,
                goal,
                speed: AgentSpec::DEFAULT_SPEED,
                priority: None,
                start_heading_deg: 0.0,
            });
            placed = true;
            break;
        }
        if !placed {
            return Err(ScenarioError::NotEnoughFreeCells {
                at,
                requested: n,
                placed: out.agents.len(),
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix_reference_values() {
        // First outputs for seed 1234567 from the reference C implementation.
        let mut r = SplitMix64::new(1_234_567);
        assert_eq!(r.next_u64(), 6_457_827_717_110_365_317);
        assert_eq!(r.next_u64(), 3_203_168_211_198_807_973);
    }

    #[test]
    fn below_stays_in_range_and_covers_it() {
        let mut r = SplitMix64::new(7);
        let mut hit = [false; 5];
        for _ in 0..200 {
            let v = r.below(5);
            assert!(v < 5);
            hit[v as usize] = true;
        }
        assert!(hit.iter().all(|&h| h));
        assert_eq!(r.below(0), 0);
    }

    #[test]
    fn components_split_by_wall() {
        let g = crate::grid::read_map_rows([(1, ".@."), (2, ".@.")], "<t>").unwrap();
        let l = components(&g, crate::grid::CornerCutting::Allowed);
        assert_eq!(l[0], l[3]);
        assert_ne!(l[0], l[2]);
        assert_eq!(l[1], u32::MAX);
    }
}
