//! LaCAM (Okumura, AAAI 2023): a depth-first search over configurations whose successors the
//! generator (`generator.rs`) makes, one PIBT step each, under constraints that a lazily grown breadth-first
//! tree of "agent `i` goes to cell `v`" adds per configuration. The first successor is plain
//! PIBT's; every later visit of a configuration tries the next constraint, so in the end every
//! executable successor is generated: the search is complete (it finds a solution whenever
//! one exists within its budget), and on easy instances it costs about one PIBT step per step
//! of the plan.
//!
//! Deterministic: ties are broken by hashes of the node, never by the clock or a random seed,
//! so a lockstep run replans the same way on every machine. The budget counts nodes, not time,
//! for the same reason.

use std::collections::{HashMap, VecDeque};
use std::rc::Rc;

use super::generator::{Generator, Problem};
use super::graph::NONE;

/// How much a search may grow before it gives up.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Budget {
    /// Configurations.
    pub configurations: usize,
    /// Constraint nodes (the low-level search), in all.
    pub constraints: usize,
}

impl Default for Budget {
    /// At most about 200 MiB for 256 agents (a configuration and its priorities take 8 bytes
    /// per agent, a constraint 16 bytes); the MAPF benchmark's hardest instance here
    /// (warehouse, 200 robots) needs 59 000 configurations.
    fn default() -> Self {
        Budget {
            configurations: 100_000,
            constraints: 4_000_000,
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
}

/// A high-level node: one configuration.
struct Node {
    parent: u32,
    /// Constraint nodes still to try from here.
    tree: VecDeque<u32>,
}

/// A low-level node: one more constraint on top of its parent's.
#[derive(Clone, Copy)]
struct Constraint {
    parent: u32,
    who: u32,
    to: u32,
    depth: u32,
}

/// The search's nodes.
#[derive(Default)]
struct Tree {
    /// Shared with `explored`: a configuration is stored once.
    configs: Vec<Rc<[u32]>>,
    priorities: Vec<Box<[f32]>>,
    nodes: Vec<Node>,
    lows: Vec<Constraint>,
    explored: HashMap<Rc<[u32]>, u32>,
}

impl Tree {
    /// A new configuration.
    fn add(&mut self, config: Rc<[u32]>, prio: Box<[f32]>, parent: u32) -> u32 {
        let id = self.nodes.len() as u32;
        self.lows.push(Constraint {
            parent: NONE,
            who: NONE,
            to: NONE,
            depth: 0,
        });
        self.nodes.push(Node {
            parent,
            tree: VecDeque::from([self.lows.len() as u32 - 1]),
        });
        self.explored.insert(config.clone(), id);
        self.configs.push(config);
        self.priorities.push(prio);
        id
    }

    /// The configurations from the root to `end`.
    fn path(&self, end: u32) -> Vec<Box<[u32]>> {
        let mut out = Vec::new();
        let mut k = end;
        while k != NONE {
            out.push(self.configs[k as usize].as_ref().into());
            k = self.nodes[k as usize].parent;
        }
        out.reverse();
        out
    }

    /// Grows the constraint tree of node `t` below constraint `low`: the next agent in the
    /// node's order, to each of its cells.
    fn expand(&mut self, p: &Problem, t: usize, low: u32, order: &[u32]) {
        let c = self.lows[low as usize];
        if c.depth as usize >= order.len() {
            return;
        }
        let who = order[c.depth as usize];
        let at = self.configs[t][who as usize];
        let moves = p.graph.moves(at);
        let k = moves.len() + 1;
        let shift = t.wrapping_add(low as usize) % k;
        for r in 0..k {
            let m = (r + shift) % k;
            let to = if m == 0 { at } else { moves[m - 1].to };
            self.nodes[t].tree.push_back(self.lows.len() as u32);
            self.lows.push(Constraint {
                parent: low,
                who,
                to,
                depth: c.depth + 1,
            });
        }
    }

    /// Node `t`'s agents by priority, highest first (PIBT's order), into `out`.
    fn order(&self, t: usize, out: &mut Vec<u32>) {
        let prio = &self.priorities[t];
        out.clear();
        out.extend(0..prio.len() as u32);
        out.sort_by(|&a, &b| {
            prio[b as usize]
                .total_cmp(&prio[a as usize])
                .then(a.cmp(&b))
        });
    }

    /// The constraints of `low`, shallowest first.
    fn constraints(&self, low: u32, out: &mut Vec<(u32, u32)>) {
        out.clear();
        let mut l = low;
        while l != NONE && self.lows[l as usize].who != NONE {
            let c = self.lows[l as usize];
            out.push((c.who, c.to));
            l = c.parent;
        }
        out.reverse();
    }
}

/// A plan found.
pub(super) struct Plan {
    /// The configurations from the start to the goals, one executable step apart.
    pub configs: Vec<Box<[u32]>>,
    /// Configurations the search visited.
    pub visited: usize,
}

/// Searches a plan from `starts` to the problem's goals, calling `tick` once per step of the
/// search (a long search keeps the process's heartbeat going through it).
pub(super) fn solve(
    p: &Problem,
    starts: &[u32],
    budget: Budget,
    tick: &mut dyn FnMut(),
) -> Result<Plan, SearchError> {
    let n = starts.len();
    let mut gen = Generator::new(p.graph.cells(), n);
    let mut tree = Tree::default();
    // LaCAM's initial priorities: the distance to go, scaled below one step of waiting.
    let scale = 1.0 / (1000.0 * p.graph.cells().max(1) as f32);
    let first: Box<[f32]> = (0..n)
        .map(|i| ((p.distance)(i, starts[i]).min(1 << 30)) as f32 * scale)
        .collect();
    let mut open = vec![tree.add(starts.into(), first, NONE)];
    let mut fixed: Vec<(u32, u32)> = Vec::with_capacity(n);
    let mut next: Vec<u32> = Vec::with_capacity(n);
    let mut order: Vec<u32> = Vec::with_capacity(n);
    let over = |tree: &Tree| SearchError::Budget {
        configurations: tree.nodes.len(),
    };
    while let Some(&top) = open.last() {
        tick();
        let t = top as usize;
        if tree.configs[t].iter().zip(p.goals).all(|(a, b)| a == b) {
            return Ok(Plan {
                configs: tree.path(top),
                visited: tree.nodes.len(),
            });
        }
        let Some(low) = tree.nodes[t].tree.pop_front() else {
            open.pop();
            continue;
        };
        tree.order(t, &mut order);
        tree.expand(p, t, low, &order);
        if tree.lows.len() > budget.constraints {
            return Err(over(&tree));
        }
        tree.constraints(low, &mut fixed);
        let salt = (u64::from(top) << 32) | u64::from(low);
        if !gen.generate(p, &tree.configs[t], &fixed, &order, salt, &mut next) {
            continue;
        }
        if let Some(&known) = tree.explored.get(next.as_slice()) {
            open.push(known);
            continue;
        }
        if tree.nodes.len() >= budget.configurations {
            return Err(over(&tree));
        }
        let prio: Box<[f32]> = (0..n)
            .map(|i| {
                let p0 = tree.priorities[t][i];
                if next[i] == p.goals[i] {
                    p0 - p0.floor()
                } else {
                    p0 + 1.0
                }
            })
            .collect();
        open.push(tree.add(next.as_slice().into(), prio, top));
    }
    Err(SearchError::NoPlan)
}
