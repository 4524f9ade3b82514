//! Per-node search state kept between queries.
//!
//! Every node has a `g`, a parent and a closed flag. Instead of clearing these arrays before
//! each query (a cost proportional to the grid even when the search touches ten cells), each
//! node carries the *generation* (query number) in which it was last written; a node whose
//! stamp is not the current generation reads as untouched (`g = inf`, open/closed: no). The
//! coordinator replans often on the same map, so this matters more than it looks.

use hnav_runtime::grid::Cell;

use super::interface::PlanStats;
use super::open_list::OpenList;
use super::space::Space;
use crate::line_of_sight::euclid;

/// One node's state, valid only while `stamp` equals the current generation.
#[derive(Clone, Copy, Debug, Default)]
struct Node {
    stamp: u32,
    closed: bool,
    /// Lazy Theta* with hazard: `g` and parent have been checked by a cell walk since the
    /// node's last improvement.
    verified: bool,
    parent: u32,
    g: f64,
}

/// The reusable state of one planner: node table, open list and counters.
#[derive(Clone, Debug, Default)]
pub(crate) struct Search {
    nodes: Vec<Node>,
    /// Current query number; 0 is never used, so a fresh (all-zero) node is untouched.
    generation: u32,
    open: OpenList,
    /// Counters of the current (or last) query.
    pub(crate) stats: PlanStats,
}

impl Search {
    /// Starts a query over `n` nodes: new generation, empty open list, zero counters.
    pub(crate) fn begin(&mut self, n: usize) {
        if self.nodes.len() < n {
            self.nodes.resize(n, Node::default());
        }
        if self.generation == u32::MAX {
            // After 4 billion queries the stamps would repeat: forget them all once.
            self.nodes.iter_mut().for_each(|node| node.stamp = 0);
            self.generation = 0;
        }
        self.generation += 1;
        self.open.reset();
        self.stats = PlanStats::default();
    }

    /// `g` of a node, infinite if untouched in this query.
    #[inline]
    pub(crate) fn g(&self, i: usize) -> f64 {
        let node = &self.nodes[i];
        if node.stamp == self.generation {
            node.g
        } else {
            f64::INFINITY
        }
    }

    /// Parent of a node touched in this query (itself for the start).
    #[inline]
    pub(crate) fn parent(&self, i: usize) -> usize {
        self.nodes[i].parent as usize
    }

    /// Whether the node has been expanded in this query.
    #[inline]
    pub(crate) fn is_closed(&self, i: usize) -> bool {
        let node = &self.nodes[i];
        node.stamp == self.generation && node.closed
    }

    /// Sets `g` and parent, touching the node (it stays closed if it was).
    #[inline]
    pub(crate) fn set(&mut self, i: usize, g: f64, parent: usize) {
        let generation = self.generation;
        let node = &mut self.nodes[i];
        if node.stamp != generation {
            node.stamp = generation;
            node.closed = false;
        }
        node.verified = false;
        node.g = g;
        node.parent = parent as u32;
    }

    /// Sets `g` and parent and puts the node on the open list with key `g + h`.
    #[inline]
    pub(crate) fn open(&mut self, i: usize, g: f64, h: f64, parent: usize) {
        self.set(i, g, parent);
        self.open.push(i, g + h, g);
        self.stats.generated += 1;
    }

    /// Takes the best open node and marks it closed (the caller counts the expansion).
    /// Skips stale entries: of closed nodes, or pushed before the node's `g` changed.
    #[inline]
    pub(crate) fn pop(&mut self) -> Option<usize> {
        loop {
            let e = self.open.pop()?;
            let i = e.node as usize;
            // Every node with an entry was touched by `open` in this generation.
            let node = &mut self.nodes[i];
            if node.closed || node.g != e.g {
                continue;
            }
            node.closed = true;
            return Some(i);
        }
    }

    /// Puts a just-popped node back on the open list with its current `g` (after a repair
    /// raised it), keeping its parent and verified flag.
    pub(crate) fn requeue(&mut self, i: usize, h: f64) {
        let node = &mut self.nodes[i];
        node.closed = false;
        let g = node.g;
        self.open.push(i, g + h, g);
    }

    /// Records that the node's `g` and parent are checked (until its next improvement).
    pub(crate) fn mark_verified(&mut self, i: usize) {
        self.nodes[i].verified = true;
    }

    /// Whether the node's `g` and parent are checked.
    pub(crate) fn is_verified(&self, i: usize) -> bool {
        let node = &self.nodes[i];
        node.stamp == self.generation && node.verified
    }

    /// Whether no node waits.
    pub(crate) fn open_is_empty(&self) -> bool {
        self.open.is_empty()
    }

    /// The cells from the start to `goal` by parent pointers, and their polyline length.
    pub(crate) fn path_to(&self, space: &Space<'_>, goal: usize) -> (Vec<Cell>, f64) {
        let mut cells = vec![space.cell(goal)];
        let mut i = goal;
        // A parent chain is at most as long as the number of nodes; the bound only guards
        // against a planner bug turning into an endless loop.
        for _ in 0..self.nodes.len() {
            let p = self.parent(i);
            if p == i {
                break;
            }
            cells.push(space.cell(p));
            i = p;
        }
        cells.reverse();
        let length = cells.windows(2).map(|w| euclid(w[0], w[1])).sum();
        (cells, length)
    }
}

/// The constructor and option accessors every planner (`config` + `search` fields) shares.
macro_rules! planner_options {
    ($planner:ident) => {
        impl $planner {
            /// A planner with the given options.
            pub fn new(config: PlannerConfig) -> Self {
                $planner {
                    config,
                    search: Search::default(),
                }
            }

            /// The options in use.
            pub fn config(&self) -> &PlannerConfig {
                &self.config
            }

            /// Replaces the options (the buffers are kept).
            pub fn set_config(&mut self, config: PlannerConfig) {
                self.config = config;
            }
        }
    };
}
pub(crate) use planner_options;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_new_query_forgets_the_last_even_across_the_stamp_wrap() {
        let mut s = Search::default();
        s.begin(4);
        s.open(2, 1.5, 0.0, 2);
        assert_eq!(s.pop(), Some(2));
        assert!(s.is_closed(2) && s.g(2) == 1.5);
        s.generation = u32::MAX - 1;
        for _ in 0..3 {
            s.begin(6);
            assert!(!s.is_closed(2) && s.g(2).is_infinite() && !s.is_verified(2));
            s.open(2, 0.5, 1.0, 2);
            s.open(2, 0.25, 1.0, 2); // improvement: the first entry goes stale
            assert_eq!(s.pop(), Some(2));
            assert_eq!(s.g(2), 0.25);
            assert_eq!(s.pop(), None);
        }
        assert!(s.generation < 3, "wrapped and restarted");
    }
}
