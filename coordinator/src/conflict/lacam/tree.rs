//! The search's nodes: configurations (high level, in the [`Configs`] arena with their PIBT
//! priorities beside them) and constraints (low level), and, for LaCAM*, each configuration's
//! cost from the start and its known neighbours, so that a cheaper way found to a
//! configuration rewires its parent and those of every configuration reached through it.

use std::collections::VecDeque;

use super::arena::Configs;
use super::generator::Problem;
use super::graph::NONE;

/// A high-level node: one configuration.
pub(super) struct Node {
    /// The node it was reached from on the cheapest way known (LaCAM*) or first (LaCAM).
    pub parent: u32,
    /// Constraint nodes still to try from here.
    pub tree: VecDeque<u32>,
    /// Cost from the start on the way through `parent` (LaCAM*: agents not staying on
    /// their goals, summed over the steps).
    pub g: u64,
    /// The admissible estimate of the cost to the goals.
    pub h: u64,
    /// The first of its neighbour edges (LaCAM* only), [`NONE`] if none.
    edges: u32,
}

impl Node {
    /// `g + h`: no solution through this node costs less.
    pub fn f(&self) -> u64 {
        self.g + self.h
    }
}

/// A low-level node: one more constraint on top of its parent's.
#[derive(Clone, Copy)]
pub(super) struct Constraint {
    parent: u32,
    who: u32,
    to: u32,
    depth: u32,
}

/// A directed edge between configurations one step apart (LaCAM*'s `neighbor` sets), with
/// its cost; the edges of one node form a list through `next`.
#[derive(Clone, Copy)]
struct Edge {
    to: u32,
    cost: u32,
    next: u32,
}

/// The search's nodes; see the [module docs](self).
pub(super) struct Tree {
    n: usize,
    pub configs: Configs,
    /// `n` per node, PIBT's priorities of the configuration's agents.
    priorities: Vec<f32>,
    pub nodes: Vec<Node>,
    lows: Vec<Constraint>,
    edges: Vec<Edge>,
    /// The rewiring's queue, kept between calls.
    queue: VecDeque<u32>,
}

/// The cost of the step `from -> to` (LaCAM*'s sum-of-costs edge): the agents that are not
/// on their goals both before and after it.
pub(super) fn step_cost(goals: &[u32], from: &[u32], to: &[u32]) -> u32 {
    let mut cost = 0;
    for ((&g, &a), &b) in goals.iter().zip(from).zip(to) {
        cost += u32::from(a != g || b != g);
    }
    cost
}

impl Tree {
    pub fn new(n: usize) -> Self {
        Tree {
            n,
            configs: Configs::new(n),
            priorities: Vec::new(),
            nodes: Vec::new(),
            lows: Vec::new(),
            edges: Vec::new(),
            queue: VecDeque::new(),
        }
    }

    /// Constraint nodes made so far.
    pub fn constraint_count(&self) -> usize {
        self.lows.len()
    }

    /// Bytes held by the tree's tables (not counting the per-node queues' heap), for reports.
    pub fn bytes(&self) -> usize {
        self.configs.bytes()
            + self.priorities.capacity() * 4
            + self.nodes.capacity() * std::mem::size_of::<Node>()
            + self.lows.capacity() * std::mem::size_of::<Constraint>()
            + self.edges.capacity() * std::mem::size_of::<Edge>()
    }

    /// Configuration `t`.
    pub fn config(&self, t: u32) -> &[u32] {
        self.configs.get(t)
    }

    /// Node `t`'s priorities.
    pub fn priorities(&self, t: u32) -> &[f32] {
        let at = t as usize * self.n;
        &self.priorities[at..at + self.n]
    }

    /// A new configuration (not known yet) reached from `parent` at cost `g`, with its
    /// estimate `h`; LaCAM* links it to its parent as a neighbour when `link`.
    pub fn add(&mut self, config: &[u32], prio: &[f32], parent: u32, (g, h): (u64, u64)) -> u32 {
        let id = self.configs.push(config);
        debug_assert_eq!(id as usize, self.nodes.len());
        self.lows.push(Constraint {
            parent: NONE,
            who: NONE,
            to: NONE,
            depth: 0,
        });
        self.nodes.push(Node {
            parent,
            tree: VecDeque::from([self.lows.len() as u32 - 1]),
            g,
            h,
            edges: NONE,
        });
        self.priorities.extend_from_slice(prio);
        id
    }

    /// Records the step `from -> to` of cost `cost` as a neighbour edge (once).
    pub fn link(&mut self, from: u32, to: u32, cost: u32) {
        let mut e = self.nodes[from as usize].edges;
        while e != NONE {
            if self.edges[e as usize].to == to {
                return;
            }
            e = self.edges[e as usize].next;
        }
        let next = self.nodes[from as usize].edges;
        self.nodes[from as usize].edges = self.edges.len() as u32;
        self.edges.push(Edge { to, cost, next });
    }

    /// LaCAM*'s Dijkstra update from `from` (Kei18/lacam2 `Planner::rewrite`): every node
    /// reachable over known edges more cheaply than its `g` takes the cheaper way as its
    /// parent; those cheaper than `bound` (the best solution's cost) are pushed on `open`
    /// again to be searched from.
    pub fn rewire(&mut self, from: u32, bound: Option<u64>, open: &mut Vec<u32>) {
        self.queue.clear();
        self.queue.push_back(from);
        while let Some(u) = self.queue.pop_front() {
            let gu = self.nodes[u as usize].g;
            let mut e = self.nodes[u as usize].edges;
            while e != NONE {
                let Edge { to, cost, next } = self.edges[e as usize];
                let g = gu + u64::from(cost);
                let v = &mut self.nodes[to as usize];
                if g < v.g {
                    v.g = g;
                    v.parent = u;
                    self.queue.push_back(to);
                    if bound.is_some_and(|b| v.f() < b) {
                        open.push(to);
                    }
                }
                e = next;
            }
        }
    }

    /// The configurations from the root to `end`.
    pub fn path(&self, end: u32) -> Vec<Box<[u32]>> {
        let mut out = Vec::new();
        let mut k = end;
        while k != NONE {
            out.push(self.config(k).into());
            k = self.nodes[k as usize].parent;
        }
        out.reverse();
        out
    }

    /// Grows the constraint tree of node `t` below constraint `low`: the next agent in the
    /// node's order, to each of its cells.
    pub fn expand(&mut self, p: &Problem, t: u32, low: u32, order: &[u32]) {
        let c = self.lows[low as usize];
        if c.depth as usize >= order.len() {
            return;
        }
        let who = order[c.depth as usize];
        let at = self.config(t)[who as usize];
        let moves = p.graph.moves(at);
        let k = moves.len() + 1;
        let shift = (t as usize).wrapping_add(low as usize) % k;
        for r in 0..k {
            let m = (r + shift) % k;
            let to = if m == 0 { at } else { moves[m - 1].to };
            self.nodes[t as usize]
                .tree
                .push_back(self.lows.len() as u32);
            self.lows.push(Constraint {
                parent: low,
                who,
                to,
                depth: c.depth + 1,
            });
        }
    }

    /// Node `t`'s agents by priority, highest first (PIBT's order), into `out`.
    pub fn order(&self, t: u32, out: &mut Vec<u32>) {
        let prio = self.priorities(t);
        out.clear();
        out.extend(0..prio.len() as u32);
        out.sort_by(|&a, &b| {
            prio[b as usize]
                .total_cmp(&prio[a as usize])
                .then(a.cmp(&b))
        });
    }

    /// The constraints of `low`, shallowest first.
    pub fn constraints(&self, low: u32, out: &mut Vec<(u32, u32)>) {
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
