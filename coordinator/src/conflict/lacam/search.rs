//! LaCAM (Okumura, AAAI 2023): a depth-first search over configurations whose successors the
//! generator (`generator.rs`) makes, one PIBT step each, under constraints that a lazily grown
//! breadth-first tree of "agent `i` goes to cell `v`" adds per configuration. The first
//! successor is plain PIBT's; every later visit of a configuration tries the next constraint,
//! so in the end every executable successor is generated: the search is complete (it finds a
//! solution whenever one exists within its budget), and on easy instances it costs about one
//! PIBT step per step of the plan.
//!
//! # LaCAM*: refinement
//!
//! With [`Budget::refine`] above zero the search is LaCAM* (Okumura, IJCAI 2023; the loop of
//! Kei18/lacam2's `Planner::solve`): every configuration keeps its cost from the start `g`
//! (sum of costs: one per agent and step, except an agent staying on its goal) and its known
//! neighbours; a configuration met again through a cheaper way takes it as its parent, and so
//! does every configuration reached through it (a Dijkstra update, `Tree::rewire` in `tree.rs`). After the
//! first solution the search goes on, dropping every configuration whose `g + h` cannot beat
//! the best solution, and returns the best one when its budget or deadline ends it, or an
//! optimal one when nothing is left to search. One in ten (`RESTART`) revisits of a known
//! configuration during refinement restarts from the start instead (Kei18/lacam3's random
//! insertion, drawn here from a fixed seed). Without refinement nothing is rewired: the plan
//! is the first one found, exactly as plain LaCAM finds it.
//!
//! # Determinism and budgets
//!
//! Ties are broken by hashes of the node, never by the clock or a random seed (LaCAM*'s random
//! restarts are left out), so a lockstep run replans the same way on every machine. The
//! coordinator's budget counts nodes, not time, for the same reason, and it does not refine
//! (`refine = 0`, the default): its plans are the first solutions they always were. A
//! deadline (`solve`'s `deadline`) is for the search-only benchmark (`hnav-bench lacam`),
//! which gives the search a wall-clock limit as the papers do; the coordinator never passes
//! one.
//!
//! # Memory
//!
//! A configuration costs `8 n` bytes for `n` agents (its cells as u32 in one arena,
//! `Configs` of `arena.rs`, and its PIBT priorities as f32 in another) plus about
//! 80 bytes of node, table slot and constraint-queue; a constraint 16 bytes, a LaCAM* edge 12.

use std::time::Instant;

use super::generator::{Generator, Problem};
use super::graph::NONE;
use super::tree::{step_cost, Tree};
use crate::conflict::pibt::distance::DIAGONAL;
use hnav_runtime::hash::SplitMix64;

/// During refinement, one in this many revisits of a known configuration searches on from
/// the start instead (Kei18/lacam3's `RANDOM_INSERT_PROB1` = 0.1): the depth-first search
/// leaves the neighbourhood of the first solution.
const RESTART: u64 = 10;
/// The seed of those draws.
const RESTART_SEED: u64 = 0x0001_aca3;

/// How much a search may grow before it gives up.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Budget {
    /// Configurations.
    pub configurations: usize,
    /// Constraint nodes (the low-level search), in all.
    pub constraints: usize,
    /// Search iterations after the first solution (LaCAM*'s refinement, see the
    /// [module docs](self)); 0: plain LaCAM, the first solution is the plan.
    pub refine: usize,
}

impl Default for Budget {
    /// At most about 200 MiB for 256 agents (a configuration and its priorities take 8 bytes
    /// per agent, a constraint 16 bytes); the MAPF benchmark's hardest instance here
    /// (warehouse, 200 robots) needs 59 000 configurations. No refinement.
    fn default() -> Self {
        Budget {
            configurations: 100_000,
            constraints: 4_000_000,
            refine: 0,
        }
    }
}

/// Why a search ended without a plan.
#[derive(Clone, Copy, PartialEq, Eq, Debug, thiserror::Error)]
pub enum SearchError {
    /// Every executable configuration reachable from the start was visited.
    #[error("no plan exists: every reachable configuration was searched")]
    NoPlan,
    /// The budget ran out first.
    #[error("the search budget ran out after {configurations} configurations")]
    Budget {
        /// Configurations visited.
        configurations: usize,
    },
    /// The deadline passed first (only a search given one).
    #[error("the deadline passed after {configurations} configurations")]
    Deadline {
        /// Configurations visited.
        configurations: usize,
    },
}

/// A plan found.
pub struct Plan {
    /// The configurations from the start to the goals, one executable step apart.
    pub configs: Vec<Box<[u32]>>,
    /// Configurations the search visited.
    pub visited: usize,
    /// Constraint nodes it made.
    pub constraints: usize,
    /// Configurations visited when the first solution was found.
    pub first_visited: usize,
    /// The first solution's sum of costs ([`sum_of_costs`]).
    pub first_cost: u64,
    /// When the first solution was found: only a search with a deadline reads the clock.
    pub first_at: Option<Instant>,
    /// Whether the search proved the plan optimal (LaCAM*: nothing cheaper was left).
    pub optimal: bool,
    /// Bytes of the search's tables at the end.
    pub bytes: usize,
}

/// The sum of costs of `plan` towards `goals`, as the MAPF papers count it: per agent, the
/// step at which it last arrives at its goal (0 for one that never leaves it).
pub fn sum_of_costs(plan: &[Box<[u32]>], goals: &[u32]) -> u64 {
    let mut sum = 0;
    for (i, &g) in goals.iter().enumerate() {
        let last_off = plan.iter().rposition(|c| c[i] != g);
        sum += last_off.map_or(0, |t| t as u64 + 1);
    }
    sum
}

/// LaCAM*'s `h`: the steps every agent needs at least, its distance over the longest step.
fn estimate(p: &Problem, config: &[u32]) -> u64 {
    let step = u64::from(DIAGONAL);
    let mut h = 0;
    for (i, &c) in config.iter().enumerate() {
        h += u64::from((p.distance)(i, c)).div_ceil(step);
    }
    h
}

/// How the loop ended.
enum End {
    /// Nothing left to search.
    Exhausted,
    /// A budget or the refinement's iterations ran out.
    Budget,
    Deadline,
}

/// Searches a plan from `starts` to the problem's goals within `budget` and, if given,
/// `deadline`, calling `tick` once per step of the search (a long search keeps the
/// process's heartbeat going through it).
pub(super) fn solve(
    p: &Problem,
    starts: &[u32],
    budget: Budget,
    deadline: Option<Instant>,
    tick: &mut dyn FnMut(),
) -> Result<Plan, SearchError> {
    let n = starts.len();
    let star = budget.refine > 0;
    let mut gen = Generator::new(p.graph.cells(), n);
    let mut tree = Tree::new(n);
    // LaCAM's initial priorities: the distance to go, scaled below one step of waiting.
    let scale = 1.0 / (1000.0 * p.graph.cells().max(1) as f32);
    let mut prio: Vec<f32> = (0..n)
        .map(|i| ((p.distance)(i, starts[i]).min(1 << 30)) as f32 * scale)
        .collect();
    let mut open = vec![tree.add(starts, &prio, NONE, (0, estimate(p, starts)))];
    let mut fixed: Vec<(u32, u32)> = Vec::with_capacity(n);
    let mut next: Vec<u32> = Vec::with_capacity(n);
    let mut order: Vec<u32> = Vec::with_capacity(n);
    // The node whose order `order` holds: the depth-first search expands one node many times
    // in a row, and a sort of a thousand agents is not free.
    let mut ordered = NONE;
    let mut goal: Option<u32> = None;
    let mut first = (0, 0, None);
    // The first solution, kept: refinement lowers `g`, which counts an agent resting on its
    // goal for nothing, while the sum of costs counts it until its last arrival; the plan
    // returned is never worse than the first by either.
    let mut first_path = Vec::new();
    let mut refined = 0usize;
    // LaCAM3's random restarts, drawn from a fixed seed: deterministic like the rest.
    let mut restarts = SplitMix64::new(RESTART_SEED);
    let end = loop {
        let Some(&top) = open.last() else {
            break End::Exhausted;
        };
        tick();
        if deadline.is_some_and(|d| Instant::now() >= d) {
            break End::Deadline;
        }
        if let Some(g) = goal {
            refined += 1;
            if refined > budget.refine {
                break End::Budget;
            }
            if tree.nodes[top as usize].f() >= tree.nodes[g as usize].g {
                open.pop();
                continue;
            }
        }
        if goal.is_none() && tree.config(top) == p.goals {
            goal = Some(top);
            first = (tree.nodes.len(), 0, deadline.map(|_| Instant::now()));
            if !star {
                break End::Budget;
            }
            first_path = tree.path(top);
            first.1 = sum_of_costs(&first_path, p.goals);
            continue;
        }
        let Some(low) = tree.nodes[top as usize].tree.pop_front() else {
            open.pop();
            continue;
        };
        if ordered != top {
            tree.order(top, &mut order);
            ordered = top;
        }
        tree.expand(p, top, low, &order);
        if tree.constraint_count() > budget.constraints {
            break End::Budget;
        }
        tree.constraints(low, &mut fixed);
        let salt = (u64::from(top) << 32) | u64::from(low);
        if !gen.generate(p, tree.config(top), &fixed, &order, salt, &mut next) {
            continue;
        }
        let cost = step_cost(p.goals, tree.config(top), &next);
        let bound = goal.map(|g| tree.nodes[g as usize].g);
        if let Some(known) = tree.configs.find(&next) {
            if star {
                tree.link(top, known, cost);
                tree.rewire(top, bound, &mut open);
                let bound = goal.map(|g| tree.nodes[g as usize].g);
                if bound.is_some() && restarts.below(RESTART) == 0 {
                    open.push(0);
                    continue;
                }
                if bound.is_some_and(|b| tree.nodes[known as usize].f() >= b) {
                    continue;
                }
            }
            open.push(known);
            continue;
        }
        if tree.nodes.len() >= budget.configurations {
            break End::Budget;
        }
        let parent = tree.priorities(top);
        for (i, q) in prio.iter_mut().enumerate() {
            let p0 = parent[i];
            *q = if next[i] == p.goals[i] {
                p0 - p0.floor()
            } else {
                p0 + 1.0
            };
        }
        let g = tree.nodes[top as usize].g + u64::from(cost);
        let id = tree.add(&next, &prio, top, (g, estimate(p, &next)));
        if star {
            tree.link(top, id, cost);
        }
        if bound.is_none_or(|b| tree.nodes[id as usize].f() < b) {
            open.push(id);
        }
    };
    let visited = tree.nodes.len();
    let Some(g) = goal else {
        return Err(match end {
            End::Exhausted => SearchError::NoPlan,
            End::Budget => SearchError::Budget {
                configurations: visited,
            },
            End::Deadline => SearchError::Deadline {
                configurations: visited,
            },
        });
    };
    let mut configs = tree.path(g);
    let mut optimal = star && matches!(end, End::Exhausted);
    if !star {
        first.1 = sum_of_costs(&configs, p.goals);
    } else if sum_of_costs(&configs, p.goals) > first.1 {
        configs = first_path;
        optimal = false;
    }
    Ok(Plan {
        configs,
        visited,
        constraints: tree.constraint_count(),
        first_visited: first.0,
        first_cost: first.1,
        first_at: first.2,
        optimal,
        bytes: tree.bytes(),
    })
}
