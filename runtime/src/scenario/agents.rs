//! Growing or shrinking a scenario's agent set (`hnav check --agents N`, benchmarks).
//!
//! Extra agents get seeded random starts and goals: free cells, every start distinct from all
//! other starts, every goal distinct from all other goals, start != goal, and the goal
//! reachable from the start under the map's corner-cutting rule (checked with a BFS flood).
//! The random numbers come from [`SplitMix64`] so that the placement is identical on every
//! platform and every version of HNAV for a given seed, without pulling in `rand`.

use std::collections::HashSet;

use super::error::{Loc, ScenarioError};
use super::{AgentSpec, FaultTarget, Planner, Scenario};
use crate::grid::{components, Cell};
use crate::hash::SplitMix64;
use crate::msg::MAX_AGENTS;

/// See [`Scenario::with_agent_count`].
pub(super) fn with_agent_count(
    s: &Scenario,
    n: usize,
    seed: u64,
) -> Result<Scenario, ScenarioError> {
    let at = Loc::new(&s.source_name, 0);
    if n == 0 {
        return Err(ScenarioError::InvalidParameter {
            at,
            key: "--agents".into(),
            problem: "must be at least 1 (a run needs a robot), got 0".into(),
        });
    }
    if n > MAX_AGENTS {
        return Err(ScenarioError::TooManyAgents {
            at,
            agents: n,
            max: MAX_AGENTS,
        });
    }
    let mut out = s.clone();
    if let Some(t) = out.tasks.as_mut().filter(|t| !t.cycles.is_empty()) {
        // A list's added agents keep their one goal; dropped agents drop their lists.
        t.cycles.truncate(n);
    }
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
                planner: Planner::Hnav,
            });
            if let Some(t) = out.tasks.as_mut().filter(|t| !t.cycles.is_empty()) {
                t.cycles.push(vec![goal]);
            }
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
    fn components_split_by_wall() {
        let g = crate::grid::read_map_rows([(1, ".@."), (2, ".@.")], "<t>").unwrap();
        let l = components(&g, crate::grid::CornerCutting::Allowed);
        assert_eq!(l[0], l[3]);
        assert_ne!(l[0], l[2]);
        assert_eq!(l[1], u32::MAX);
    }
}
