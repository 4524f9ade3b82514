//! A plan of synchronous steps executed by robots that drive at their own pace: an action
//! dependency graph (Hönig et al., RA-L 2019), kept as one queue of visits per cell.
//!
//! Every cell gets the plan's visits in time order: the robot standing in it at the start, then
//! each robot that enters it (at step `t + 1`) or sweeps it with a diagonal (at step `t + ½`).
//! A robot may start a move only when the visits of the cell it enters (and of the side cells
//! it sweeps) have come to its own: every earlier visitor has left. A visit ends when its
//! robot arrives in its next cell (a sweep when the sweeping robot arrives). Dependencies run
//! from earlier steps to later ones, or along a chain of followers within one step (the
//! [generator](super::generator) admits no rotation), so they never form a cycle: every robot
//! reaches the end of its plan, however slowly the others drive. No two robots ever hold one
//! cell: a cell is entered only after its previous visitor has arrived elsewhere.
//!
//! Waiting in place is not an action: a robot's actions are its moves only.

use hnav_runtime::grid::Cell;
use hnav_runtime::msg::{ConflictKind, Verdict};

use super::graph::{Graph, NONE};
use crate::conflict::shared_paths::{AgentMode, AgentRow, Outcome};

/// One move of one robot, with the visits it waits for.
#[derive(Clone, Copy, Debug)]
struct Action {
    from: u32,
    to: u32,
    /// The visit of `to` this move starts.
    visit: u32,
    /// The sweep visits of the side cells (with the cells), [`NONE`] if none.
    sides: [(u32, u32); 2],
}

/// The plan being executed; see the [module docs](self).
#[derive(Clone, Debug)]
pub(super) struct Schedule {
    width: u32,
    /// Per member (robot of the plan), its agent index.
    agents: Vec<u32>,
    actions: Vec<Action>,
    /// `actions[first[k]..first[k + 1]]` are member `k`'s, in order.
    first: Vec<u32>,
    /// Per member, its next action (an index into `actions`).
    cursor: Vec<u32>,
    /// Per member, whether its next action was accepted and it has not arrived yet.
    driving: Vec<bool>,
    /// Per member, its last cell.
    last: Vec<u32>,
    /// Per visit, its member.
    visitor: Vec<u32>,
    /// Per cell, the visit allowed now (its visits are consecutive).
    head: Vec<u32>,
}

/// Kinds of a visit, in time order within one step.
const ENTER: u64 = 0;
const SWEEP: u64 = 1;

impl Schedule {
    /// The schedule of `plan` (configurations of the members, one step apart) for the
    /// members `agents` on `graph`, whose map is `width` cells wide.
    pub fn new(graph: &Graph, width: u32, agents: Vec<u32>, plan: &[Box<[u32]>]) -> Self {
        let n = agents.len();
        let mut actions = Vec::new();
        let mut first = Vec::with_capacity(n + 1);
        // (cell, time key, member, action or NONE for the start, slot 0 enter / 1-2 sides)
        let mut events: Vec<(u32, u64, u32, u32, u8)> = Vec::new();
        for k in 0..n {
            first.push(actions.len() as u32);
            events.push((plan[0][k], 0, k as u32, NONE, 0));
            for (t, pair) in plan.windows(2).enumerate() {
                let (from, to) = (pair[0][k], pair[1][k]);
                if from == to {
                    continue;
                }
                let m = graph
                    .step(from, to)
                    .expect("the search makes moves of the map");
                let a = actions.len() as u32;
                let t = t as u64;
                events.push((to, 2 * (t + 1) + ENTER, k as u32, a, 0));
                for (s, &side) in m.sides.iter().enumerate() {
                    if side != NONE {
                        events.push((side, 2 * t + SWEEP, k as u32, a, s as u8 + 1));
                    }
                }
                actions.push(Action {
                    from,
                    to,
                    visit: NONE,
                    sides: [(NONE, NONE); 2],
                });
            }
        }
        first.push(actions.len() as u32);
        events.sort_unstable_by_key(|&(cell, key, ..)| (cell, key));
        let mut head = vec![NONE; graph.cells()];
        let mut visitor = Vec::with_capacity(events.len());
        for (v, &(cell, _, k, a, slot)) in events.iter().enumerate() {
            let v = v as u32;
            if head[cell as usize] == NONE {
                head[cell as usize] = v;
            }
            visitor.push(k);
            if a == NONE {
                continue;
            }
            let act = &mut actions[a as usize];
            match slot {
                0 => act.visit = v,
                s => act.sides[usize::from(s) - 1] = (cell, v),
            }
        }
        let last = plan.last().map_or_else(Vec::new, |c| c.to_vec());
        Schedule {
            width,
            cursor: first[..n].to_vec(),
            driving: vec![false; n],
            agents,
            actions,
            first,
            last,
            visitor,
            head,
        }
    }

    fn index(&self, c: Cell) -> u32 {
        c.y * self.width + c.x
    }

    /// The member's next action, if any is left.
    fn pending(&self, k: usize) -> Option<Action> {
        (self.cursor[k] < self.first[k + 1]).then(|| self.actions[self.cursor[k] as usize])
    }

    /// Whether the rows are where the plan has its members (and nobody else moves): a robot
    /// that stopped, is missing, or is not where it should be breaks the plan, and so does an
    /// agent outside it that takes part again.
    pub fn follows(&self, rows: &[AgentRow]) -> bool {
        let mut members = 0;
        for (k, &a) in self.agents.iter().enumerate() {
            let Some(row) = rows.get(a as usize) else {
                return false;
            };
            if row.mode == AgentMode::Standing {
                return false;
            }
            let (cur, next) = (self.index(row.current), self.index(row.next));
            let ok = match self.pending(k) {
                Some(act) if self.driving[k] => {
                    (cur == act.from && (next == act.to || next == act.from))
                        || (cur == act.to && next == act.to)
                }
                Some(act) => cur == act.from && next == cur,
                None => cur == self.last[k] && next == cur,
            };
            if !ok {
                return false;
            }
            members += 1;
        }
        let standing = rows
            .iter()
            .filter(|r| r.mode == AgentMode::Standing)
            .count();
        members + standing == rows.len()
    }

    /// The plan's moves, in all.
    pub fn moves(&self) -> usize {
        self.actions.len()
    }

    /// Whether every member has made every move.
    pub fn done(&self) -> bool {
        (0..self.agents.len()).all(|k| self.pending(k).is_none())
    }

    /// One round: the arrivals end their visits, then every member whose next cells have come
    /// to it is accepted there. Call after [`Schedule::follows`] said yes.
    pub fn decide(&mut self, rows: &[AgentRow], out: &mut Vec<Outcome>) {
        out.clear();
        out.resize(rows.len(), Outcome::default());
        for k in 0..self.agents.len() {
            let row = &rows[self.agents[k] as usize];
            match self.pending(k) {
                Some(act)
                    if self.driving[k] && row.is_at_rest() && self.index(row.current) == act.to =>
                {
                    self.head[act.from as usize] += 1;
                    for (cell, _) in act.sides.into_iter().filter(|&(c, _)| c != NONE) {
                        self.head[cell as usize] += 1;
                    }
                    self.cursor[k] += 1;
                    self.driving[k] = false;
                }
                _ => {}
            }
        }
        for k in 0..self.agents.len() {
            let a = self.agents[k] as usize;
            let row = &rows[a];
            let Some(act) = self.pending(k) else {
                out[a] = self.waiting(row, None);
                continue;
            };
            if self.driving[k] {
                // Accepted and not yet on its way (the commit was missed): say it again.
                if row.is_at_rest() {
                    out[a] = self.accept(row, act.to);
                }
                continue;
            }
            let blocker = std::iter::once((act.to, act.visit))
                .chain(act.sides.into_iter().filter(|&(c, _)| c != NONE))
                .find(|&(cell, visit)| self.head[cell as usize] != visit);
            match blocker {
                None => {
                    self.driving[k] = true;
                    out[a] = self.accept(row, act.to);
                }
                Some((cell, _)) => {
                    let v = self.head[cell as usize];
                    let other = self.agents[self.visitor[v as usize] as usize];
                    out[a] = self.waiting(row, Some(other));
                }
            }
        }
    }

    fn cell(&self, index: u32) -> Cell {
        Cell::new(index % self.width, index / self.width)
    }

    fn accept(&self, row: &AgentRow, to: u32) -> Outcome {
        let to = self.cell(to);
        let asked = row.probable.filter(|_| row.mode == AgentMode::Active);
        Outcome {
            verdict: Verdict::Accept,
            refused: 0,
            kind: match asked {
                Some(p) if p == to => ConflictKind::None,
                Some(_) => ConflictKind::Redirected,
                None => ConflictKind::Pushed,
            },
            cell: Some(to),
            other: None,
        }
    }

    /// A member that stays this round: held while it waits for `other`, if it asked.
    fn waiting(&self, row: &AgentRow, other: Option<u32>) -> Outcome {
        let asked = row.probable.filter(|_| row.mode == AgentMode::Active);
        Outcome {
            verdict: Verdict::Hold,
            refused: 0,
            kind: match (asked, other) {
                (Some(_), Some(_)) => ConflictKind::Reserved,
                _ => ConflictKind::None,
            },
            cell: asked,
            other: asked.and(other),
        }
    }
}
