//! PIBT's swap operation (Okumura, "Improving LaCAM for Scalable Eventually Optimal
//! Multi-Agent Pathfinding", IJCAI 2023; `is_swap_required_and_possible` in LaCAM3's
//! `pibt.cpp`), adapted to robots that hold a cell until they have left it.
//!
//! Plain PIBT fails when agent `i`'s best cell holds `j`, `j` wants `i`'s cell, and ahead of
//! `i` lies a corridor or dead end where the two cannot pass: `i` pushes `j` deeper, or the
//! push fails, round after round. The swap is *required* when walking from `i` through `j`
//! along `i`'s way meets no cell with two free ways on before `i`'s way ends, and `j` wants to
//! come towards `i`; it is *possible* when walking from `i` away from `j` meets such a cell
//! (a place to pass) before a dead end.
//!
//! LaCAM3 then reverses `i`'s preferences (it moves away from its goal) and pulls `j` into
//! `i`'s cell in the same step. Here no robot enters a cell vacated in the same round, so the
//! pull is a priority hand-over instead: `i` moves away this round and `j` takes `i`'s rank
//! plus one from the next round on ([`Pibt::resolve`]'s hand-over). Then `j` is the pusher:
//! it follows `i` and pushes it back along the corridor until `i` can step aside at the place
//! to pass, and standard priority inheritance resolves the rest. The moves are logged like any
//! other choice that is not the agent's own: [`Redirected`](super::ConflictKind::Redirected)
//! for `i`, [`Pushed`](super::ConflictKind::Pushed) for the agent it pushes back.
//!
//! Off by default ([`Pibt::set_swap`]): measured better on the MovingAI maps, worse on one
//! instance of the property test, not understood yet.
//!
//! Cells are counted as ways on unless they are dead ends (one move) where an agent stands on
//! its goal (LaCAM3's "agents who need not move"). All walks are bounded by the map's size and
//! allocate nothing.

use hnav_runtime::grid::{Cell, Direction};

use super::distance::can_step;
use super::{Pibt, State, NOBODY};

impl Pibt {
    /// The moves from `cell` on the static map (the round's corner rule).
    fn moves(&self, cell: Cell) -> impl Iterator<Item = Cell> + '_ {
        let rule = self.options.corner_cutting;
        Direction::ALL
            .into_iter()
            .filter_map(move |d| can_step(&self.blocked, self.width, self.height, rule, cell, d))
    }

    /// The agent standing on `cell` this round (taking part or fixed), or [`NOBODY`].
    fn stander(&self, cell: Cell) -> u32 {
        let c = self.cell(cell);
        if c.occupant != NOBODY {
            c.occupant
        } else {
            c.fixed
        }
    }

    /// The ways on from `at` other than `back` that count: `(how many, the last one)`.
    fn ways_on(&self, at: Cell, back: Cell) -> (usize, Cell) {
        let mut n = 0;
        let mut last = at;
        for u in self.moves(at) {
            if u == back {
                continue;
            }
            let k = self.stander(u);
            let parked = k != NOBODY
                && self.distances.goal(k as usize) == Some(u)
                && self.moves(u).count() == 1;
            if !parked {
                n += 1;
                last = u;
            }
        }
        (n, last)
    }

    /// LaCAM3's `is_swap_required(pusher, puller, v_pusher, v_puller)`.
    fn swap_required(&self, pusher: usize, puller: usize, from: Cell, ahead: Cell) -> bool {
        required_walk(
            from,
            ahead,
            self.blocked.len(),
            |c| self.distances.get(pusher, c),
            |c| self.distances.get(puller, c),
            |at, back| self.ways_on(at, back),
        )
    }

    /// LaCAM3's `is_swap_possible(v_pusher, v_puller)`: a place to pass behind `v_puller`,
    /// walking away from `v_pusher`.
    fn swap_possible(&self, v_pusher: Cell, v_puller: Cell) -> bool {
        possible_walk(v_pusher, v_puller, self.blocked.len(), |at, back| {
            self.ways_on(at, back)
        })
    }

    /// The agent `i` (at `from`, best cell `best`) should swap with, if any: the undecided
    /// agent on `best`, or (LaCAM3's "clear" case) a neighbour that would have to swap with
    /// `i` once `i` stands on `best`.
    pub(super) fn swap_partner(&self, i: usize, from: Cell, best: Cell) -> Option<u32> {
        if best == from {
            return None;
        }
        let j = self.cell(best).occupant;
        if j != NOBODY
            && self.state[j as usize] == State::Undecided
            && self.swap_required(i, j as usize, from, best)
            && self.swap_possible(best, from)
        {
            return Some(j);
        }
        self.moves(from).find_map(|u| {
            let k = self.cell(u).occupant;
            (k != NOBODY
                && k as usize != i
                && u != best
                && self.swap_required(k as usize, i, from, best)
                && self.swap_possible(best, from))
            .then_some(k)
        })
    }
}

/// LaCAM3's `is_swap_required` over any cells: walking from `from` through `ahead` along the
/// pusher's way (`d_pusher` falls) meets no cell with two `ways_on` before the way ends, and
/// the puller (`d_puller`) wants to come towards the pusher. At most `limit` steps. Shared
/// with LaCAM's generator (`conflict/lacam/swap.rs`).
pub(crate) fn required_walk<C: Copy>(
    from: C,
    ahead: C,
    limit: usize,
    d_pusher: impl Fn(C) -> u32,
    d_puller: impl Fn(C) -> u32,
    ways_on: impl Fn(C, C) -> (usize, C),
) -> bool {
    let (mut v_pusher, mut v_puller) = (from, ahead);
    // The distance to the pusher's goal falls strictly on every step: at most a walk over
    // the map; the cap only guards against a malformed table.
    for _ in 0..limit {
        if d_pusher(v_puller) >= d_pusher(v_pusher) {
            break;
        }
        let (n, next) = ways_on(v_puller, v_pusher);
        if n >= 2 {
            return false;
        }
        if n == 0 {
            break;
        }
        v_pusher = v_puller;
        v_puller = next;
    }
    d_puller(v_pusher) < d_puller(v_puller)
        && (d_pusher(v_pusher) == 0 || d_pusher(v_puller) < d_pusher(v_pusher))
}

/// LaCAM3's `is_swap_possible` over any cells: a cell with two `ways_on` behind
/// `v_puller_origin`, walking away from `v_pusher_origin`, before a dead end. At most `limit`
/// steps.
pub(crate) fn possible_walk<C: Copy + PartialEq>(
    v_pusher_origin: C,
    v_puller_origin: C,
    limit: usize,
    ways_on: impl Fn(C, C) -> (usize, C),
) -> bool {
    let (mut v_pusher, mut v_puller) = (v_pusher_origin, v_puller_origin);
    for _ in 0..limit {
        if v_puller == v_pusher_origin {
            return false;
        }
        let (n, next) = ways_on(v_puller, v_pusher);
        if n >= 2 {
            return true;
        }
        if n == 0 {
            return false;
        }
        v_pusher = v_puller;
        v_puller = next;
    }
    false
}
