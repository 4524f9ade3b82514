//! The open list: an indexed binary min-heap with decrease-key.
//!
//! Each node is in the heap at most once (a better `g` moves it up instead of pushing a
//! duplicate, as `std::collections::BinaryHeap` with lazy deletion would). Its storage lives
//! as long as the planner, so a query allocates nothing once the buffers have grown to the
//! largest grid seen.
//!
//! # Order and tie-breaking
//!
//! Smallest `f = g + h` first. Among equal `f`, the **larger `g`** first: that node is the one
//! nearer the goal along its path, and preferring it lets A* run down one of the many
//! equal-length octile paths instead of fanning out over all of them. Nodes with equal `f`
//! and `g` leave in the heap's order, which is deterministic for a given query.

/// One heap entry: the node and the two keys it is ordered by.
#[derive(Clone, Copy, Debug)]
struct Entry {
    f: f64,
    g: f64,
    node: u32,
}

impl Entry {
    /// Whether `self` must leave the heap before `other`.
    #[inline]
    fn before(&self, other: &Entry) -> bool {
        self.f < other.f || (self.f == other.f && self.g > other.g)
    }
}

/// Marks "not in the heap" in [`OpenList::pos`].
const NOT_IN_HEAP: u32 = u32::MAX;

/// An indexed binary min-heap over node numbers `0..capacity`.
#[derive(Clone, Debug, Default)]
pub(crate) struct OpenList {
    heap: Vec<Entry>,
    /// Position of each node in `heap`, or [`NOT_IN_HEAP`].
    pos: Vec<u32>,
}

impl OpenList {
    /// Empties the heap and makes room for nodes `0..nodes`. Reuses the storage: only the
    /// positions of the nodes still in the heap are reset, so clearing after a query costs
    /// the size of the final open list, not of the grid.
    pub(crate) fn reset(&mut self, nodes: usize) {
        for e in &self.heap {
            self.pos[e.node as usize] = NOT_IN_HEAP;
        }
        self.heap.clear();
        if self.pos.len() < nodes {
            self.pos.resize(nodes, NOT_IN_HEAP);
        }
    }

    /// Whether no node is waiting.
    pub(crate) fn is_empty(&self) -> bool {
        self.heap.is_empty()
    }

    /// Number of waiting nodes.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.heap.len()
    }

    /// Inserts `node`, or moves it to its new keys if it is already waiting. The planners
    /// only ever lower a waiting node's `f`; a raise is handled too, for safety.
    pub(crate) fn push_or_update(&mut self, node: usize, f: f64, g: f64) {
        let entry = Entry {
            f,
            g,
            node: node as u32,
        };
        let at = self.pos[node];
        if at == NOT_IN_HEAP {
            self.heap.push(entry);
            self.sift_up(self.heap.len() - 1);
        } else {
            let at = at as usize;
            let up = entry.before(&self.heap[at]);
            self.heap[at] = entry;
            if up {
                self.sift_up(at);
            } else {
                self.sift_down(at);
            }
        }
    }

    /// Removes and returns the first node, if any.
    pub(crate) fn pop(&mut self) -> Option<usize> {
        let top = *self.heap.first()?;
        let last = self.heap.pop()?;
        self.pos[top.node as usize] = NOT_IN_HEAP;
        if !self.heap.is_empty() {
            self.heap[0] = last;
            self.pos[last.node as usize] = 0;
            self.sift_down(0);
        }
        Some(top.node as usize)
    }

    fn sift_up(&mut self, mut i: usize) {
        let e = self.heap[i];
        while i > 0 {
            let parent = (i - 1) / 2;
            if !e.before(&self.heap[parent]) {
                break;
            }
            self.heap[i] = self.heap[parent];
            self.pos[self.heap[i].node as usize] = i as u32;
            i = parent;
        }
        self.heap[i] = e;
        self.pos[e.node as usize] = i as u32;
    }

    fn sift_down(&mut self, mut i: usize) {
        let e = self.heap[i];
        let n = self.heap.len();
        loop {
            let left = 2 * i + 1;
            if left >= n {
                break;
            }
            let right = left + 1;
            let child = if right < n && self.heap[right].before(&self.heap[left]) {
                right
            } else {
                left
            };
            if !self.heap[child].before(&e) {
                break;
            }
            self.heap[i] = self.heap[child];
            self.pos[self.heap[i].node as usize] = i as u32;
            i = child;
        }
        self.heap[i] = e;
        self.pos[e.node as usize] = i as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_in_order_with_updates_and_ties() {
        let mut h = OpenList::default();
        h.reset(10);
        for (n, f) in [(0, 5.0), (1, 3.0), (2, 8.0), (3, 3.0), (4, 1.0)] {
            h.push_or_update(n, f, 0.0);
        }
        h.push_or_update(2, 0.5, 0.0); // decrease
        h.push_or_update(3, 3.0, 2.0); // same f, larger g: before node 1
        assert_eq!(h.len(), 5);
        let order: Vec<usize> = std::iter::from_fn(|| h.pop()).collect();
        assert_eq!(order, vec![2, 4, 3, 1, 0]);
        assert!(h.is_empty());
    }

    #[test]
    fn reset_reuses_and_forgets() {
        let mut h = OpenList::default();
        h.reset(4);
        h.push_or_update(1, 1.0, 0.0);
        h.push_or_update(2, 2.0, 0.0);
        h.reset(8);
        assert!(h.is_empty());
        h.push_or_update(2, 4.0, 0.0);
        h.push_or_update(7, 3.0, 0.0);
        assert_eq!(h.pop(), Some(7));
        assert_eq!(h.pop(), Some(2));
        assert_eq!(h.pop(), None);
    }
}
