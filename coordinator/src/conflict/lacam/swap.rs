//! LaCAM3's swap in the configuration generator (Okumura, "Engineering LaCAM*", AAMAS 2024;
//! `is_swap_required_and_possible`, `is_swap_required` and `is_swap_possible` in
//! Kei18/lacam3's `pibt.cpp`), on for the search-only benchmark and off in the rounds.
//!
//! Plain PIBT fails where agent `i`'s best cell holds `j`, `j` wants `i`'s cell, and ahead of
//! them lies a corridor or a dead end where two cannot pass: `i` pushes `j` deeper, step after
//! step. The swap is *required* when walking from `i` through `j` along `i`'s way meets no
//! cell with two ways on before `i`'s way ends, and `j` wants to come towards `i`; it is
//! *possible* when walking from `j` through `i`, away from `j`, meets such a cell before a
//! dead end. Then `i` takes its preferences in reverse (it backs off) and pulls `j` into its
//! cell in the same step: `j` follows `i`, a chain, which robots can execute. Unlike the
//! online PIBT's swap (`pibt/swap.rs`), no priority hand-over is needed: a step of the plan
//! may enter a cell its robot leaves.
//!
//! Cells are ways on unless they are dead ends where an agent stands on its goal (LaCAM3's
//! agents who need not move). Every walk is bounded by the map's size.

use super::generator::{Generator, Problem};
use super::graph::NONE;
use crate::conflict::pibt::swap::{possible_walk, required_walk};

impl Generator {
    /// The ways on from `at` other than `back` that count: how many, and the last one.
    fn ways_on(&self, p: &Problem, at: u32, back: u32) -> (usize, u32) {
        let (mut n, mut last) = (0, at);
        for m in p.graph.moves(at) {
            let u = m.to;
            if u == back {
                continue;
            }
            let a = self.occ_now[u as usize];
            let parked = a != NONE && p.goals[a as usize] == u && p.graph.moves(u).len() == 1;
            if !parked {
                n += 1;
                last = u;
            }
        }
        (n, last)
    }

    /// LaCAM3's `is_swap_required(pusher, puller, v_pusher, v_puller)`.
    fn swap_required(&self, p: &Problem, pusher: u32, puller: u32, from: u32, ahead: u32) -> bool {
        required_walk(
            from,
            ahead,
            p.graph.cells(),
            |c| (p.distance)(pusher as usize, c),
            |c| (p.distance)(puller as usize, c),
            |at, back| self.ways_on(p, at, back),
        )
    }

    /// LaCAM3's `is_swap_possible(v_pusher, v_puller)`: a place to pass behind `v_puller`,
    /// walking away from `v_pusher`.
    fn swap_possible(&self, p: &Problem, v_pusher: u32, v_puller: u32) -> bool {
        possible_walk(v_pusher, v_puller, p.graph.cells(), |at, back| {
            self.ways_on(p, at, back)
        })
    }

    /// The agent `i` (at `here`, best cell `best`) should swap with, or [`NONE`]: the
    /// undecided agent on `best`, or (LaCAM3's "clear" case) a neighbour that would have to
    /// swap with `i` once `i` stands on `best`.
    pub(super) fn swap_partner(&self, p: &Problem, from: &[u32], i: u32, best: u32) -> u32 {
        let here = from[i as usize];
        let j = self.occ_now[best as usize];
        if j != NONE
            && j != i
            && self.next[j as usize] == NONE
            && self.swap_required(p, i, j, here, best)
            && self.swap_possible(p, best, here)
        {
            return j;
        }
        if best == here {
            return NONE;
        }
        for m in p.graph.moves(here) {
            let k = self.occ_now[m.to as usize];
            if k != NONE
                && from[k as usize] != best
                && self.swap_required(p, k, i, here, best)
                && self.swap_possible(p, best, here)
            {
                return k;
            }
        }
        NONE
    }

    /// Pulls the undecided agent `j` into `cell`, the cell its swap partner has just left,
    /// when that is a move of the map nobody else takes.
    pub(super) fn pull(&mut self, p: &Problem, from: &[u32], j: u32, cell: u32) {
        if self.next[j as usize] != NONE {
            return;
        }
        let Some(m) = p.graph.step(from[j as usize], cell) else {
            return;
        };
        if self.enterable(p, m) && self.sides_free(p, m) {
            self.take(j, m);
        }
    }
}
