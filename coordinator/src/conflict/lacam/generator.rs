//! LaCAM's configuration generator: one synchronous PIBT step from a configuration, with some
//! agents' moves fixed by the search's constraints, restricted to what robots that hold a
//! cell until they have left it can execute one after another.
//!
//! A step is executable when no two agents end in one cell, no two swap, no diagonal's side
//! cell is occupied before or after the step or swept by another diagonal, and the agents
//! entering occupied cells form chains, not cycles: in a chain the front robot leaves first
//! and the others follow; in a cycle (a rotation of three or more, which PIBT allows) every
//! robot would wait for the next one. [`Generator::generate`] checks all of it at the end,
//! whatever produced the step, so the search only ever sees executable steps; PIBT itself
//! avoids rotations and occupied corners so that it rarely produces a step that fails.

use super::graph::{Graph, Move, NONE};

/// A cell's distance to one agent's goal: `distance(agent, cell)`, smaller is better.
pub(super) type Distance<'a> = &'a dyn Fn(usize, u32) -> u32;

/// One search's instance: the map, the fixed obstacles and the goals.
pub(super) struct Problem<'a> {
    pub graph: &'a Graph,
    /// Per cell, whether an agent outside the search holds it.
    pub fixed: &'a [bool],
    pub goals: &'a [u32],
    pub distance: Distance<'a>,
    /// Whether PIBT swaps in corridors (LaCAM3's swap, `swap.rs`): off in the rounds.
    pub swap: bool,
}

/// The generator's scratch, sized once for a map and a number of agents.
pub(super) struct Generator {
    /// Per cell, the agent standing there in the configuration stepped from.
    pub(super) occ_now: Vec<u32>,
    /// Per cell, the agent entering (or staying in) it.
    occ_next: Vec<u32>,
    /// Per cell, the agent whose diagonal sweeps it.
    swept: Vec<u32>,
    /// Cells written in `occ_next` and `swept`, to clear them.
    touched: Vec<u32>,
    /// Per agent, its cell after the step, [`NONE`] while undecided.
    pub(super) next: Vec<u32>,
    /// Per agent, the cycle check's colour (0 unvisited, 1 on the walk, 2 done).
    colour: Vec<u8>,
}

impl Generator {
    pub fn new(cells: usize, agents: usize) -> Self {
        Generator {
            occ_now: vec![NONE; cells],
            occ_next: vec![NONE; cells],
            swept: vec![NONE; cells],
            touched: Vec::new(),
            next: vec![NONE; agents],
            colour: vec![0; agents],
        }
    }

    /// The step from `from`: `constraints` (agent, cell) first, then PIBT for the others in
    /// `order`; ties broken by `salt`. On success `out` holds the next configuration.
    pub fn generate(
        &mut self,
        p: &Problem,
        from: &[u32],
        constraints: &[(u32, u32)],
        order: &[u32],
        salt: u64,
        out: &mut Vec<u32>,
    ) -> bool {
        for (i, &c) in from.iter().enumerate() {
            self.occ_now[c as usize] = i as u32;
        }
        self.next.fill(NONE);
        let ok = self.fill(p, from, constraints, order, salt) && self.executable(p, from);
        if ok {
            out.clear();
            out.extend_from_slice(&self.next);
        }
        for &c in from {
            self.occ_now[c as usize] = NONE;
        }
        self.clear_next();
        ok
    }

    /// Forgets every entry and sweep of the step.
    fn clear_next(&mut self) {
        for &c in &self.touched {
            self.occ_next[c as usize] = NONE;
            self.swept[c as usize] = NONE;
        }
        self.touched.clear();
    }

    fn fill(
        &mut self,
        p: &Problem,
        from: &[u32],
        constraints: &[(u32, u32)],
        order: &[u32],
        salt: u64,
    ) -> bool {
        for &(i, to) in constraints {
            let Some(m) = p.graph.step(from[i as usize], to) else {
                return false;
            };
            if !self.enterable(p, m) || !self.sides_free(p, m) {
                return false;
            }
            self.take(i, m);
        }
        for &i in order {
            if self.next[i as usize] == NONE && !self.pibt(p, from, i, salt) {
                return false;
            }
        }
        true
    }

    pub(super) fn enterable(&self, p: &Problem, m: Move) -> bool {
        let u = m.to as usize;
        !p.fixed[u] && self.occ_next[u] == NONE && self.swept[u] == NONE
    }

    /// A diagonal's side cells: nobody in them before or after the step, nobody else sweeping.
    pub(super) fn sides_free(&self, p: &Problem, m: Move) -> bool {
        m.sides.iter().filter(|&&s| s != NONE).all(|&s| {
            let s = s as usize;
            !p.fixed[s]
                && self.occ_now[s] == NONE
                && self.occ_next[s] == NONE
                && self.swept[s] == NONE
        })
    }

    pub(super) fn take(&mut self, i: u32, m: Move) {
        self.next[i as usize] = m.to;
        self.occ_next[m.to as usize] = i;
        self.touched.push(m.to);
        for s in m.sides.into_iter().filter(|&s| s != NONE) {
            self.swept[s as usize] = i;
            self.touched.push(s);
        }
    }

    fn untake_sides(&mut self, i: u32, m: Move) {
        for s in m.sides.into_iter().filter(|&s| s != NONE) {
            if self.swept[s as usize] == i {
                self.swept[s as usize] = NONE;
            }
        }
    }

    /// Whether agent `me` entering the cell of the decided, moving agent `j` would close a
    /// rotation: the chain of agents each entering the next one's cell leads back to `me`.
    fn closes_cycle(&self, from: &[u32], j: u32, me: u32) -> bool {
        let mut a = j;
        for _ in 0..from.len() {
            let t = self.next[a as usize];
            if t == NONE || t == from[a as usize] {
                return false;
            }
            let b = self.occ_now[t as usize];
            if b == NONE {
                return false;
            }
            if b == me {
                return true;
            }
            a = b;
        }
        true
    }

    /// PIBT for agent `i`: its best enterable cell, pushing an undecided agent standing there
    /// (which must then move, recursively); staying when nothing works.
    fn pibt(&mut self, p: &Problem, from: &[u32], i: u32, salt: u64) -> bool {
        let here = from[i as usize];
        let mut cands = [(
            0u64,
            Move {
                to: here,
                sides: [NONE; 2],
            },
        ); 9];
        let key = |to: u32, k: u64| {
            let tie = (salt ^ u64::from(i).wrapping_mul(0x9E37_79B9_7F4A_7C15))
                .wrapping_add(k)
                .wrapping_mul(0xBF58_476D_1CE4_E5B9)
                >> 56;
            (u64::from((p.distance)(i as usize, to)) << 8) | tie
        };
        cands[0].0 = key(here, 0);
        let mut len = 1;
        for (k, &m) in p.graph.moves(here).iter().enumerate() {
            cands[len] = (key(m.to, k as u64 + 1), m);
            len += 1;
        }
        cands[..len].sort_unstable_by_key(|&(k, _)| k);
        let partner = if p.swap {
            self.swap_partner(p, from, i, cands[0].1.to)
        } else {
            NONE
        };
        if partner != NONE {
            cands[..len].reverse();
        }
        for (k, &(_, m)) in cands[..len].iter().enumerate() {
            if !self.enterable(p, m) || !self.sides_free(p, m) {
                continue;
            }
            let j = self.occ_now[m.to as usize];
            let other = j != NONE && j != i;
            if other && self.next[j as usize] == here {
                continue; // a swap
            }
            if other && self.next[j as usize] != NONE && self.closes_cycle(from, j, i) {
                continue;
            }
            self.take(i, m);
            if other && self.next[j as usize] == NONE && !self.pibt(p, from, j, salt) {
                self.untake_sides(i, m);
                continue;
            }
            if k == 0 && partner != NONE && m.to != here {
                self.pull(p, from, partner, here);
            }
            return true;
        }
        self.next[i as usize] = here;
        self.occ_next[here as usize] = i;
        self.touched.push(here);
        false
    }

    /// The whole step checked from scratch: every agent decided on a move of the map, off the
    /// fixed cells, no two in one cell, no swap, corners free, no rotation.
    fn executable(&mut self, p: &Problem, from: &[u32]) -> bool {
        // `swept` and `occ_next` are recounted from `next` alone.
        self.clear_next();
        for (i, &at) in from.iter().enumerate() {
            let to = self.next[i];
            let Some(m) = (to != NONE).then(|| p.graph.step(at, to)).flatten() else {
                return false;
            };
            if !self.enterable(p, m) {
                return false;
            }
            self.take(i as u32, m);
        }
        for (i, &at) in from.iter().enumerate() {
            let m = p.graph.step(at, self.next[i]).expect("checked above");
            if m.sides.iter().any(|&s| {
                s != NONE
                    && (self.occ_now[s as usize] != NONE
                        || self.occ_next[s as usize] != NONE
                        || self.swept[s as usize] != i as u32)
            }) {
                return false;
            }
            let j = self.occ_now[m.to as usize];
            if j != NONE && j != i as u32 && self.next[j as usize] == at {
                return false;
            }
        }
        self.acyclic(from)
    }

    /// Whether following "the agent in the cell I enter" never comes back round.
    fn acyclic(&mut self, from: &[u32]) -> bool {
        self.colour.fill(0);
        for start in 0..from.len() {
            let mut a = start;
            while self.colour[a] == 0 {
                self.colour[a] = 1;
                let to = self.next[a];
                let b = self.occ_now[to as usize];
                if to == from[a] || b == NONE {
                    break;
                }
                a = b as usize;
                if self.colour[a] == 1 {
                    return false;
                }
            }
            let mut a = start;
            while self.colour[a] == 1 {
                self.colour[a] = 2;
                let b = self.occ_now[self.next[a] as usize];
                if b == NONE || b as usize == a {
                    break;
                }
                a = b as usize;
            }
        }
        true
    }
}
