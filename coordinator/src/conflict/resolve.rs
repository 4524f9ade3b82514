//! The [`Resolver`]: per-cell tables with generation stamps, reused every round.

use std::cmp::Ordering;

use hnav_runtime::grid::{Cell, CornerCutting, Direction, Grid};
use hnav_runtime::msg::{ConflictKind, Verdict};

use super::shared_paths::{AgentMode, AgentRow, Options, Outcome};

/// "No agent" in the per-cell tables.
const NOBODY: u32 = u32::MAX;

/// How far an agent's request got through rules 1–5.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
enum Stage {
    /// Nothing asked, or refused by rules 1–3 (not a valid request).
    #[default]
    Idle,
    /// A valid request decided by the head-on rule.
    HeadOn,
    /// A valid request into a cell another active agent holds.
    Waiting,
    /// A valid request left for the crossing check.
    Candidate,
    /// A candidate accepted so far.
    Accepted,
    /// An accepted candidate revoked by an equal-priority one; its claims still stop the
    /// other requests of that priority, so a tie refuses every party whatever the order.
    Revoked,
}

/// The cells a request would sweep: `p` first, then a diagonal's side cells.
#[derive(Clone, Copy, Debug, Default)]
struct Footprint {
    cells: [Cell; 3],
    len: u8,
}

impl Footprint {
    fn cells(&self) -> &[Cell] {
        &self.cells[..usize::from(self.len)]
    }

    fn meets(&self, other: &Footprint) -> bool {
        self.cells().iter().any(|c| other.cells().contains(c))
    }
}

#[derive(Clone, Copy, Debug)]
struct Request {
    stage: Stage,
    /// Bit of the requested direction.
    bit: u8,
    footprint: Footprint,
    /// The head-on partner, or [`NOBODY`].
    partner: u32,
}

impl Default for Request {
    fn default() -> Self {
        Request {
            stage: Stage::Idle,
            bit: 0,
            footprint: Footprint::default(),
            partner: NOBODY,
        }
    }
}

/// Priorities compared with `0.0 == -0.0` and NaN ordered by `total_cmp` (deterministic
/// whatever the caller sends).
pub(super) fn cmp_priority(a: f64, b: f64) -> Ordering {
    if a == b {
        Ordering::Equal
    } else {
        a.total_cmp(&b)
    }
}

/// Decides rounds for one grid; see the [module docs](super).
///
/// Built once for a grid and an agent count. [`Resolver::resolve`] allocates nothing unless a
/// round has more rows than any before (then the per-agent buffers grow once).
#[derive(Clone, Debug)]
pub struct Resolver {
    width: u32,
    height: u32,
    blocked: Vec<bool>,
    options: Options,
    /// Generation of the current round; never 0 (0 marks "not this round").
    stamp: u32,
    /// Per cell: the round in which `held` was written.
    held_stamp: Vec<u32>,
    /// Per cell: the first two agents holding it.
    held: Vec<[u32; 2]>,
    /// Per cell: the round in which `claim` was written (0 after a revocation).
    claim_stamp: Vec<u32>,
    /// Per cell: the accepted request sweeping it.
    claim: Vec<u32>,
    requests: Vec<Request>,
    order: Vec<u32>,
}

impl Resolver {
    /// A resolver for `grid` (its blocked cells are copied) and up to `agents` rows a round.
    pub fn new(grid: &Grid, agents: usize, options: Options) -> Self {
        let cells = grid.len();
        Resolver {
            width: grid.width(),
            height: grid.height(),
            blocked: grid.blocked().to_vec(),
            options,
            stamp: 0,
            held_stamp: vec![0; cells],
            held: vec![[NOBODY; 2]; cells],
            claim_stamp: vec![0; cells],
            claim: vec![NOBODY; cells],
            requests: vec![Request::default(); agents],
            order: Vec::with_capacity(agents),
        }
    }

    /// The options.
    pub fn options(&self) -> &Options {
        &self.options
    }

    /// Follows a changed map (new obstacles found, cells freed). Allocates only when the
    /// grid's shape changed.
    pub fn set_map(&mut self, grid: &Grid) {
        if grid.width() != self.width || grid.height() != self.height {
            *self = Resolver::new(grid, self.requests.len(), self.options);
        } else {
            self.blocked.copy_from_slice(grid.blocked());
        }
    }

    /// Decides one round: `out[i]` is the outcome for `rows[i]` (`i` = agent index). `out`
    /// is cleared first and keeps its capacity.
    pub fn resolve(&mut self, rows: &[AgentRow], out: &mut Vec<Outcome>) {
        out.clear();
        let n = rows.len();
        if self.requests.len() < n {
            self.requests.resize(n, Request::default());
        }
        self.next_stamp();
        for (i, row) in rows.iter().enumerate() {
            for cell in row.held(&self.options).into_iter().flatten() {
                self.hold(cell, i as u32);
            }
        }
        for i in 0..n {
            let (outcome, request) = self.check(i, rows);
            out.push(outcome);
            self.requests[i] = request;
        }
        // Rule 6 in descending priority, ties by index.
        self.order.clear();
        let requests = &self.requests;
        self.order
            .extend((0..n as u32).filter(|&i| requests[i as usize].stage == Stage::Candidate));
        self.order.sort_unstable_by(|&a, &b| {
            cmp_priority(rows[b as usize].priority, rows[a as usize].priority).then(a.cmp(&b))
        });
        for k in 0..self.order.len() {
            let c = self.order[k] as usize;
            self.cross(c, rows, out);
        }
        for (i, o) in out.iter_mut().enumerate() {
            if self.requests[i].stage == Stage::HeadOn && self.meets_third(i, n) {
                o.kind = ConflictKind::Combined;
            }
        }
    }

    fn next_stamp(&mut self) {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.held_stamp.fill(0);
            self.claim_stamp.fill(0);
            self.stamp = 1;
        }
    }

    fn index(&self, cell: Cell) -> Option<usize> {
        (cell.x < self.width && cell.y < self.height)
            .then(|| cell.y as usize * self.width as usize + cell.x as usize)
    }

    fn is_blocked(&self, cell: Cell) -> bool {
        self.index(cell).is_none_or(|i| self.blocked[i])
    }

    fn hold(&mut self, cell: Cell, agent: u32) {
        let Some(i) = self.index(cell) else { return };
        if self.held_stamp[i] != self.stamp {
            self.held_stamp[i] = self.stamp;
            self.held[i] = [agent, NOBODY];
        } else {
            let h = &mut self.held[i];
            if h[0] != agent && h[1] == NOBODY {
                h[1] = agent;
            }
        }
    }

    /// Up to two agents other than `me` holding `cell` ([`NOBODY`] for none).
    fn others_holding(&self, cell: Cell, me: u32) -> [u32; 2] {
        let Some(i) = self.index(cell) else {
            return [NOBODY; 2];
        };
        if self.held_stamp[i] != self.stamp {
            return [NOBODY; 2];
        }
        let [a, b] = self.held[i];
        match (a != me, b != me && b != NOBODY) {
            (true, true) => [a, b],
            (true, false) => [a, NOBODY],
            (false, true) => [b, NOBODY],
            (false, false) => [NOBODY; 2],
        }
    }

    /// Rules 1–5 (and 7) for agent `i`.
    fn check(&self, i: usize, rows: &[AgentRow]) -> (Outcome, Request) {
        let row = &rows[i];
        let me = i as u32;
        let mut o = Outcome::default();
        let mut r = Request::default();
        if row.mode != AgentMode::Active || !row.is_at_rest() {
            return (o, r);
        }
        let Some(p) = row.probable else {
            return (o, r);
        };
        let on_grid = self.index(p).is_some();
        o.cell = on_grid.then_some(p);
        let block = |mut o: Outcome, bit: u8, kind: ConflictKind, other: u32| {
            o.verdict = Verdict::Block;
            o.refused = bit;
            o.kind = kind;
            o.other = (other != NOBODY).then_some(other);
            o
        };
        // Rule 1.
        let Some(d) = Direction::between(row.current, p) else {
            return (block(o, 0, ConflictKind::Invalid, NOBODY), r);
        };
        let bit = 1u8 << d.index();
        if self.is_blocked(p) {
            return (block(o, bit, ConflictKind::Invalid, NOBODY), r);
        }
        let mut footprint = Footprint {
            cells: [p; 3],
            len: 1,
        };
        // Rule 2.
        if d.is_diagonal() {
            let sides = [Cell::new(p.x, row.current.y), Cell::new(row.current.x, p.y)];
            let (a, b) = (self.is_blocked(sides[0]), self.is_blocked(sides[1]));
            let cut = match self.options.corner_cutting {
                CornerCutting::Forbidden => a || b,
                CornerCutting::Allowed => a && b,
            };
            if cut {
                return (block(o, bit, ConflictKind::CornerCut, NOBODY), r);
            }
            if self.options.sweep {
                for s in sides {
                    let [h, _] = self.others_holding(s, me);
                    if h != NOBODY {
                        return (block(o, bit, ConflictKind::CornerCut, h), r);
                    }
                }
                footprint = Footprint {
                    cells: [p, sides[0], sides[1]],
                    len: 3,
                };
            }
        }
        // Rule 3.
        let holders = self.others_holding(p, me);
        let mut active = NOBODY;
        for h in holders.into_iter().filter(|&h| h != NOBODY) {
            if rows[h as usize].mode.is_stable() {
                return (block(o, bit, ConflictKind::StableCell, h), r);
            }
            if active == NOBODY {
                active = h;
            }
        }
        r.bit = bit;
        r.footprint = footprint;
        if active == NOBODY {
            r.stage = Stage::Candidate;
            return (o, r);
        }
        // Rule 4.
        let partner = holders.into_iter().find(|&h| {
            h != NOBODY && {
                let b = &rows[h as usize];
                b.is_at_rest() && b.current == p && b.probable == Some(row.current)
            }
        });
        if let Some(b) = partner {
            r.stage = Stage::HeadOn;
            r.partner = b;
            o.kind = ConflictKind::HeadOn;
            o.other = Some(b);
            match cmp_priority(row.priority, rows[b as usize].priority) {
                Ordering::Greater => o.verdict = Verdict::Hold,
                _ => {
                    o.verdict = Verdict::Block;
                    o.refused = bit;
                }
            }
            return (o, r);
        }
        // Rule 5.
        r.stage = Stage::Waiting;
        o.kind = ConflictKind::Reserved;
        o.other = Some(active);
        (o, r)
    }

    /// Rule 6 for candidate `c`, against the requests accepted (or revoked) so far.
    fn cross(&mut self, c: usize, rows: &[AgentRow], out: &mut [Outcome]) {
        let request = self.requests[c];
        let mut higher = NOBODY;
        let mut equal = [NOBODY; 3];
        let mut tie = NOBODY;
        for &cell in request.footprint.cells() {
            let Some(i) = self.index(cell) else { continue };
            if self.claim_stamp[i] != self.stamp {
                continue;
            }
            let owner = self.claim[i];
            let revoked = self.requests[owner as usize].stage == Stage::Revoked;
            // The order makes the owner's priority at least the candidate's.
            match cmp_priority(rows[owner as usize].priority, rows[c].priority) {
                Ordering::Greater if !revoked && higher == NOBODY => higher = owner,
                Ordering::Greater => {}
                _ if revoked => tie = owner,
                _ => {
                    if let Some(slot) = equal.iter_mut().find(|s| **s == NOBODY || **s == owner) {
                        *slot = owner;
                    }
                }
            }
        }
        let refuse = |out: &mut [Outcome], agent: usize, bit: u8, other: u32| {
            let o = &mut out[agent];
            o.verdict = Verdict::Block;
            o.refused = bit;
            o.kind = ConflictKind::Crossing;
            o.other = Some(other);
        };
        if higher != NOBODY {
            refuse(out, c, request.bit, higher);
        } else if equal[0] != NOBODY || tie != NOBODY {
            refuse(
                out,
                c,
                request.bit,
                if equal[0] != NOBODY { equal[0] } else { tie },
            );
            for e in equal.into_iter().filter(|&e| e != NOBODY) {
                self.requests[e as usize].stage = Stage::Revoked;
                refuse(out, e as usize, self.requests[e as usize].bit, c as u32);
            }
        } else {
            out[c].verdict = Verdict::Accept;
            self.requests[c].stage = Stage::Accepted;
            for &cell in request.footprint.cells() {
                if let Some(i) = self.index(cell) {
                    self.claim_stamp[i] = self.stamp;
                    self.claim[i] = c as u32;
                }
            }
        }
    }

    /// Whether head-on agent `i`'s footprint meets the valid request of a third agent.
    fn meets_third(&self, i: usize, n: usize) -> bool {
        let r = &self.requests[i];
        (0..n).any(|j| {
            let q = &self.requests[j];
            j != i
                && j as u32 != r.partner
                && q.stage != Stage::Idle
                && q.footprint.meets(&r.footprint)
        })
    }
}
