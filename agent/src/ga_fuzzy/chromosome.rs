//! Chromosomes and the genetic operators (seed 004 §B.3 with the operators of the GA it
//! builds on, Ahn & Ramakrishna as the dissertation reviews them, notes §C.5).
//!
//! A chromosome is a sequence of nodes, start first and goal last (the seed); its length
//! `N_p` varies (Ahn & Ramakrishna) up to the number of time layers `N`. Node `t` is where the
//! robot is at tick `t`, so a repeated node is a wait. Every operator keeps a chromosome a
//! chain of legal moves under the grid's corner rule, so only the fitness decides between
//! routes, never a repair:
//!
//! * initialisation: a goal-biased randomised depth-first walk (the "heuristic" initialisation
//!   the review recommends when many routes exist) `[inferred: the bias and its strength]`;
//!   with moving obstacles node `t` avoids layer `t`'s occupied cells and may wait for the
//!   best neighbour to clear `\[inferred\]`;
//! * crossover: one point at a node both parents share, loops cut (Ahn & Ramakrishna);
//! * mutation: a random stretch of up to [`MUTATION_SPAN`] nodes re-walked, or, when the
//!   obstacles move, a wait inserted or removed `\[inferred\]`.
//!
//! The buffers live in [`Operators`] and are reused: after the first query on a grid the
//! operators allocate only when a chromosome outgrows its capacity.

use hnav_runtime::grid::{Cell, Direction, Grid};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::time_grid::TimeGrid;

/// The longest stretch (in nodes) a mutation re-walks `\[inferred\]`.
pub const MUTATION_SPAN: usize = 12;

/// Scratch space of the operators.
#[derive(Clone, Debug, Default)]
pub struct Operators {
    stamp: Vec<u32>,
    pos: Vec<u32>,
    generation: u32,
    walk: Vec<Cell>,
    common: Vec<(usize, usize)>,
}

impl Operators {
    fn begin(&mut self, cells: usize) -> u32 {
        if self.stamp.len() < cells {
            self.stamp.resize(cells, 0);
            self.pos.resize(cells, 0);
        }
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamp.fill(0);
            self.generation = 1;
        }
        self.generation
    }

    /// A goal-biased random depth-first walk from `from` to `to`, written into `out`: with
    /// probability `greed` the next node is the unvisited neighbour nearest `to` (octile),
    /// otherwise any unvisited neighbour; dead ends are backed out of. `false` when `to` is
    /// not reached within `max_nodes` nodes (the walk then explored all it could). With
    /// `t0 = Some(t)` node `k` of the walk is held at tick `t + k` and avoids the moving
    /// obstacles of that layer; with `None` only the walls count.
    #[allow(clippy::too_many_arguments)]
    pub fn random_walk(
        &mut self,
        tg: &TimeGrid,
        t0: Option<usize>,
        from: Cell,
        to: Cell,
        max_nodes: usize,
        greed: f64,
        rng: &mut ChaCha8Rng,
        out: &mut Vec<Cell>,
    ) -> bool {
        let grid = tg.grid();
        let g = self.begin(grid.len());
        out.clear();
        out.push(from);
        self.stamp[grid.index(from)] = g;
        // Waits (timed walks) can be pushed and backed out of again and again; bound the
        // decisions so a walk ends in time linear in its length.
        let mut budget = 16 * max_nodes.min(grid.len()) + 64;
        while let Some(&cur) = out.last() {
            if cur == to {
                return true;
            }
            if budget == 0 {
                return false;
            }
            budget -= 1;
            let mut cand = [Cell::new(0, 0); 8];
            let mut n = 0;
            if out.len() < max_nodes {
                for (_, c) in grid.neighbours(cur, tg.rule()) {
                    if self.stamp[grid.index(c)] != g {
                        cand[n] = c;
                        n += 1;
                    }
                }
            }
            if let Some(t0) = t0.filter(|_| !tg.is_static()) {
                let t = t0 + out.len();
                // The layer of tick t: a neighbour taken by a moving obstacle then is no
                // move; when the best one is taken, waiting for it is the greedy choice.
                let best = (n > 0).then(|| nearest(&cand[..n], to, rng));
                let wait_ok = !tg.moving_at(t, cur) && out.len() < max_nodes;
                if best.is_some_and(|b| tg.moving_at(t, b)) && wait_ok && rng.gen_bool(greed) {
                    out.push(cur);
                    continue;
                }
                let mut kept = 0;
                for k in 0..n {
                    if !tg.moving_at(t, cand[k]) {
                        cand[kept] = cand[k];
                        kept += 1;
                    }
                }
                n = kept;
            }
            if n == 0 {
                out.pop();
                continue;
            }
            let pick = if rng.gen_bool(greed) {
                nearest(&cand[..n], to, rng)
            } else {
                cand[rng.gen_range(0..n)]
            };
            self.stamp[grid.index(pick)] = g;
            out.push(pick);
        }
        false
    }

    /// Cuts every loop of `route` (a node met again: the nodes in between go), keeping waits
    /// (a node repeated at once).
    pub fn remove_loops(&mut self, grid: &Grid, route: &mut Vec<Cell>) {
        let g = self.begin(grid.len());
        let mut out = 0usize;
        for k in 0..route.len() {
            let c = route[k];
            let i = grid.index(c);
            let seen = self.stamp[i] == g
                && (self.pos[i] as usize) < out
                && route[self.pos[i] as usize] == c;
            if seen {
                if route[out - 1] != c {
                    out = self.pos[i] as usize + 1;
                    continue;
                }
            } else {
                self.stamp[i] = g;
                self.pos[i] = out as u32;
            }
            route[out] = c;
            out += 1;
        }
        route.truncate(out);
    }

    /// One-point crossover at a node both parents share (not their common ends): the
    /// children `a[..i] + b[j..]` and `b[..j] + a[i..]`, loops cut. `false` (children
    /// untouched) when the parents share no inner node.
    #[allow(clippy::too_many_arguments)]
    pub fn crossover(
        &mut self,
        grid: &Grid,
        a: &[Cell],
        b: &[Cell],
        rng: &mut ChaCha8Rng,
        child_a: &mut Vec<Cell>,
        child_b: &mut Vec<Cell>,
    ) -> bool {
        let g = self.begin(grid.len());
        for (i, &c) in a.iter().enumerate().skip(1).take(a.len().saturating_sub(2)) {
            let k = grid.index(c);
            if self.stamp[k] != g {
                self.stamp[k] = g;
                self.pos[k] = i as u32;
            }
        }
        self.common.clear();
        for (j, &c) in b.iter().enumerate().skip(1).take(b.len().saturating_sub(2)) {
            let k = grid.index(c);
            if self.stamp[k] == g {
                self.common.push((self.pos[k] as usize, j));
            }
        }
        if self.common.is_empty() {
            return false;
        }
        let (i, j) = self.common[rng.gen_range(0..self.common.len())];
        child_a.clear();
        child_a.extend_from_slice(&a[..i]);
        child_a.extend_from_slice(&b[j..]);
        child_b.clear();
        child_b.extend_from_slice(&b[..j]);
        child_b.extend_from_slice(&a[i..]);
        self.remove_loops(grid, child_a);
        self.remove_loops(grid, child_b);
        true
    }

    /// Mutates `route` in place: re-walks a random stretch (goal-biased with `greed`), or,
    /// when `timed`, inserts or removes a wait with probability one half `\[inferred\]`.
    /// Routes stay at most `tg.depth()` nodes; a mutation that cannot keep that is dropped.
    pub fn mutate(
        &mut self,
        tg: &TimeGrid,
        route: &mut Vec<Cell>,
        greed: f64,
        timed: bool,
        rng: &mut ChaCha8Rng,
    ) {
        if route.len() < 2 {
            return;
        }
        if timed && rng.gen_bool(0.5) {
            let t = rng.gen_range(0..route.len() - 1);
            if route[t] == route[t + 1] {
                route.remove(t);
            } else if route.len() < tg.depth() {
                route.insert(t, route[t]);
            }
            return;
        }
        let i = rng.gen_range(0..route.len() - 1);
        let j = rng.gen_range(i + 1..route.len().min(i + MUTATION_SPAN + 1));
        let (from, to) = (route[i], route[j]);
        let mut walk = std::mem::take(&mut self.walk);
        let span = 2 * MUTATION_SPAN;
        if self.random_walk(
            tg,
            timed.then_some(i),
            from,
            to,
            span,
            greed,
            rng,
            &mut walk,
        ) && route.len() - (j - i) + walk.len() - 1 <= tg.depth()
        {
            route.splice(i..=j, walk.iter().copied());
            self.remove_loops(tg.grid(), route);
        }
        self.walk = walk;
    }
}

/// The candidate nearest `to` (octile), ties broken at random.
fn nearest(cand: &[Cell], to: Cell, rng: &mut ChaCha8Rng) -> Cell {
    let best = cand
        .iter()
        .map(|c| c.octile(to))
        .fold(f64::INFINITY, f64::min);
    let ties = cand.iter().filter(|c| c.octile(to) <= best + 1e-9).count();
    let k = rng.gen_range(0..ties);
    *cand
        .iter()
        .filter(|c| c.octile(to) <= best + 1e-9)
        .nth(k)
        .unwrap_or(&cand[0])
}

/// Whether `route` is a chain of legal moves (or waits) on `tg`'s walls under its corner rule.
pub fn is_legal(tg: &TimeGrid, route: &[Cell]) -> bool {
    let grid = tg.grid();
    route
        .iter()
        .all(|&c| grid.contains(c) && !grid.is_blocked(c))
        && route.windows(2).all(|w| {
            w[0] == w[1]
                || Direction::between(w[0], w[1]).is_some_and(|d| grid.can_move(w[0], d, tg.rule()))
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::grid::CornerCutting;
    use rand::SeedableRng;

    fn room() -> TimeGrid {
        let g =
            Grid::from_rows(&["........", ".@@@@@@.", "........", ".@@@@@@.", "........"]).unwrap();
        TimeGrid::fixed(g, CornerCutting::Forbidden, 200).unwrap()
    }

    #[test]
    fn walks_are_legal_and_reach_the_goal() {
        let tg = room();
        let mut ops = Operators::default();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut out = Vec::new();
        for greed in [0.0, 0.5, 1.0] {
            assert!(ops.random_walk(
                &tg,
                None,
                Cell::new(0, 0),
                Cell::new(7, 4),
                200,
                greed,
                &mut rng,
                &mut out
            ));
            assert_eq!(
                (out[0], *out.last().unwrap()),
                (Cell::new(0, 0), Cell::new(7, 4))
            );
            assert!(is_legal(&tg, &out), "{out:?}");
        }
        // Walled in: the walk gives up.
        let mut g = Grid::new(3, 3).unwrap();
        for c in [Cell::new(1, 0), Cell::new(1, 1), Cell::new(1, 2)] {
            g.set_blocked(c, true);
        }
        let tg = TimeGrid::fixed(g, CornerCutting::Forbidden, 9).unwrap();
        assert!(!ops.random_walk(
            &tg,
            None,
            Cell::new(0, 0),
            Cell::new(2, 2),
            9,
            0.5,
            &mut rng,
            &mut out
        ));
    }

    #[test]
    fn loops_are_cut_and_waits_kept() {
        let tg = room();
        let c = |x, y| Cell::new(x, y);
        let mut r = vec![
            c(0, 0),
            c(1, 0),
            c(2, 0),
            c(1, 0),
            c(1, 0),
            c(2, 0),
            c(2, 0),
            c(3, 0),
        ];
        Operators::default().remove_loops(tg.grid(), &mut r);
        // The loop 1 -> 2 -> 1 goes; the wait at 1 and the one at 2 stay.
        assert_eq!(
            r,
            vec![c(0, 0), c(1, 0), c(1, 0), c(2, 0), c(2, 0), c(3, 0)]
        );
    }

    #[test]
    fn crossover_and_mutation_keep_routes_legal() {
        let tg = room();
        let mut ops = Operators::default();
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let (mut a, mut b, mut ca, mut cb) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let (s, g) = (Cell::new(0, 0), Cell::new(7, 4));
        let mut crossed = 0;
        for _ in 0..50 {
            assert!(ops.random_walk(&tg, None, s, g, 200, 0.3, &mut rng, &mut a));
            assert!(ops.random_walk(&tg, None, s, g, 200, 0.3, &mut rng, &mut b));
            if ops.crossover(tg.grid(), &a, &b, &mut rng, &mut ca, &mut cb) {
                crossed += 1;
                for ch in [&ca, &cb] {
                    assert!(is_legal(&tg, ch) && ch[0] == s && *ch.last().unwrap() == g);
                }
            }
            for timed in [false, true] {
                ops.mutate(&tg, &mut a, 0.5, timed, &mut rng);
                assert!(
                    is_legal(&tg, &a) && a[0] == s && *a.last().unwrap() == g,
                    "{a:?}"
                );
            }
        }
        assert!(crossed > 25, "{crossed}");
    }
}
