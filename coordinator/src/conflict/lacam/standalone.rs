//! The search on its own, outside the rounds: a MAPF instance (a grid, starts, goals) planned
//! at once, for the search-only benchmark (`hnav-bench lacam`) and the tests. The rounds
//! ([`Lacam`](super::Lacam)) plan through the same [`search`], with the
//! online PIBT's distance tables; here the instance builds its own, once
//! ([`Distances`]: one Dijkstra per goal, octile units, the rounds' corner rule), and every
//! PIBT step and LaCAM* estimate of the search reads them.

use std::time::Instant;

use hnav_runtime::grid::{Cell, Grid};

use super::generator::Problem;
use super::graph::Graph;
use super::search::{self, Budget, Plan, SearchError};
use crate::conflict::pibt::distance::{Distances, UNREACHABLE};
use crate::conflict::Options;

/// Why an instance cannot be searched.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum InstanceError {
    /// Starts and goals differ in number.
    #[error("{starts} starts but {goals} goals")]
    Counts {
        /// Starts given.
        starts: usize,
        /// Goals given.
        goals: usize,
    },
    /// An agent's start or goal is off the map or blocked.
    #[error("agent {agent}: {cell} is not a free cell of the map")]
    NotFree {
        /// The agent.
        agent: usize,
        /// Its start or goal.
        cell: Cell,
    },
    /// An agent's goal cannot be reached from its start.
    #[error("agent {agent}: its goal cannot be reached from its start")]
    CutOff {
        /// The agent.
        agent: usize,
    },
}

/// Why a plan is no solution of its instance ([`Instance::check`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PlanError {
    /// The plan does not start at the starts or end at the goals, or a configuration has
    /// the wrong number of agents.
    #[error("the plan does not lead from the starts to the goals")]
    Ends,
    /// An agent's step is neither a wait nor a move of the map (corner rule included).
    #[error("step {step}: agent {agent} jumps")]
    Jump {
        /// The step.
        step: usize,
        /// The agent.
        agent: usize,
    },
    /// Two agents in one cell.
    #[error("step {step}: agents {a} and {b} in one cell")]
    Vertex {
        /// The step.
        step: usize,
        /// One agent.
        a: usize,
        /// The other.
        b: usize,
    },
    /// Two agents swap cells.
    #[error("step {step}: agents {a} and {b} swap")]
    Swap {
        /// The step.
        step: usize,
        /// One agent.
        a: usize,
        /// The other.
        b: usize,
    },
}

/// A MAPF instance ready to search; see the [module docs](self).
pub struct Instance {
    graph: Graph,
    distances: Distances,
    width: u32,
    fixed: Vec<bool>,
    swap: bool,
    /// The starts as row-major cell indices.
    pub starts: Vec<u32>,
    /// The goals as row-major cell indices.
    pub goals: Vec<u32>,
}

impl Instance {
    /// Agent `i` from `starts[i]` to `goals[i]` on `grid` under `options` (the distance
    /// tables are built here).
    pub fn new(
        grid: &Grid,
        starts: &[Cell],
        goals: &[Cell],
        options: Options,
    ) -> Result<Self, InstanceError> {
        if starts.len() != goals.len() {
            return Err(InstanceError::Counts {
                starts: starts.len(),
                goals: goals.len(),
            });
        }
        let free = |c: Cell| grid.checked_index(c).filter(|&i| !grid.blocked()[i]);
        let index = |cells: &[Cell]| -> Result<Vec<u32>, InstanceError> {
            cells
                .iter()
                .enumerate()
                .map(|(agent, &cell)| {
                    free(cell)
                        .map(|i| i as u32)
                        .ok_or(InstanceError::NotFree { agent, cell })
                })
                .collect()
        };
        let (s, g) = (index(starts)?, index(goals)?);
        let distances = Distances::new(grid, goals, options.corner_cutting);
        if let Some(agent) = (0..starts.len()).find(|&i| distances.get(i, starts[i]) == UNREACHABLE)
        {
            return Err(InstanceError::CutOff { agent });
        }
        Ok(Instance {
            graph: Graph::new(grid, options),
            distances,
            width: grid.width(),
            fixed: vec![false; grid.len()],
            swap: true,
            starts: s,
            goals: g,
        })
    }

    /// Switches LaCAM3's swap in the generator (`swap.rs`) on (the default here; the rounds
    /// search without it) or off.
    pub fn set_swap(&mut self, on: bool) {
        self.swap = on;
    }

    /// Whether the distance tables are exact (see [`Distances::exact`]).
    pub fn exact_distances(&self) -> bool {
        self.distances.exact()
    }

    /// Searches a plan within `budget` and, if given, `deadline` (see
    /// [`search`]'s docs: only a deadline makes the search read the clock).
    pub fn solve(&self, budget: Budget, deadline: Option<Instant>) -> Result<Plan, SearchError> {
        let width = self.width;
        let distance = |k: usize, c: u32| self.distances.get(k, Cell::new(c % width, c / width));
        let problem = Problem {
            graph: &self.graph,
            fixed: &self.fixed,
            goals: &self.goals,
            distance: &distance,
            swap: self.swap,
        };
        search::solve(&problem, &self.starts, budget, deadline, &mut || {})
    }

    /// Whether `plan` is a solution: from the starts to the goals, every step each agent's
    /// wait or move of the map (as the graph, `graph.rs`, allows it under the corner
    /// rule), no two agents in one cell, no two swapping.
    pub fn check(&self, plan: &[Box<[u32]>]) -> Result<(), PlanError> {
        let n = self.starts.len();
        if plan.first().map(|c| &c[..]) != Some(&self.starts[..])
            || plan.last().map(|c| &c[..]) != Some(&self.goals[..])
            || plan.iter().any(|c| c.len() != n)
        {
            return Err(PlanError::Ends);
        }
        let mut at = vec![u32::MAX; self.graph.cells()];
        for (step, pair) in plan.windows(2).enumerate() {
            let (from, to) = (&pair[0], &pair[1]);
            for (agent, &c) in from.iter().enumerate() {
                at[c as usize] = agent as u32;
            }
            for agent in 0..n {
                if self.graph.step(from[agent], to[agent]).is_none() {
                    return Err(PlanError::Jump { step, agent });
                }
                let b = at[to[agent] as usize] as usize;
                if b != agent && b < n && to[b] == from[agent] {
                    return Err(PlanError::Swap { step, a: agent, b });
                }
            }
            for &c in from.iter() {
                at[c as usize] = u32::MAX;
            }
            for (agent, &c) in to.iter().enumerate() {
                let b = at[c as usize];
                if b != u32::MAX {
                    return Err(PlanError::Vertex {
                        step: step + 1,
                        a: b as usize,
                        b: agent,
                    });
                }
                at[c as usize] = agent as u32;
            }
            for &c in to.iter() {
                at[c as usize] = u32::MAX;
            }
        }
        Ok(())
    }

    /// The lower bound of every plan's sum of costs: each agent's fewest steps from its
    /// start to its goal on the graph (a breadth-first search per agent), summed.
    pub fn lower_bound(&self) -> u64 {
        let mut depth = vec![u32::MAX; self.graph.cells()];
        let mut queue = std::collections::VecDeque::new();
        let mut sum = 0;
        for (&s, &g) in self.starts.iter().zip(&self.goals) {
            depth.fill(u32::MAX);
            queue.clear();
            depth[s as usize] = 0;
            queue.push_back(s);
            while let Some(u) = queue.pop_front() {
                if u == g {
                    break;
                }
                for m in self.graph.moves(u) {
                    if depth[m.to as usize] == u32::MAX {
                        depth[m.to as usize] = depth[u as usize] + 1;
                        queue.push_back(m.to);
                    }
                }
            }
            sum += u64::from(depth[g as usize]);
        }
        sum
    }

    /// The sum of costs of `plan` ([`search::sum_of_costs`]).
    pub fn sum_of_costs(&self, plan: &[Box<[u32]>]) -> u64 {
        search::sum_of_costs(plan, &self.goals)
    }
}
