//! Priority inheritance with backtracking (PIBT; Okumura et al., IJCAI 2019, AIJ 2022) as one
//! decision round of `[coordinator] rules = "pibt"`, adapted to robots that hold a cell until
//! they have left it.
//!
//! A pure function of the round's rows like the [`Resolver`](super::Resolver), with one piece
//! of state carried from round to round: each agent's waiting time, its dynamic priority.
//!
//! # Who takes part
//!
//! Agents **at rest** (`next == current`) that are [`Active`](AgentMode::Active) (asking for a
//! step, or at rest without one) or [`Finished`](AgentMode::Finished) (on its goal: it may be
//! pushed off and comes back). A driving agent is fixed: it holds `current`, `next` and, with
//! [`Options::sweep`], a diagonal's side cells until it arrives. A
//! [`Standing`](AgentMode::Standing) agent (emergency stop, no path, missing, dead) is a fixed
//! obstacle and is never pushed.
//!
//! # Preferences
//!
//! Each taking part agent ranks its 8 neighbours (the corner rule of [`Options`]) and staying:
//! its own `probable` first when it is one of them (the agent follows its neural map), then
//! by the true octile distance to its goal over the static map ([`distance`]), staying before
//! a neighbour at the same distance, neighbours in [`Direction::ALL`] order.
//!
//! # Priorities
//!
//! The dynamic priority is the rounds since the agent was last on its goal (`waited`), then
//! the scenario's priority, then the lower index: PIBT's `waited + base fraction` without the
//! fraction's rounding. Every agent off its goal gains one per round and an agent on its goal
//! drops to zero, so the order among the agents off their goals never changes until one
//! arrives: the highest keeps its rank, and with it the right to push, until it is home
//! (PIBT's guarantee), and then the next one gets its turn.
//!
//! # The round
//!
//! In descending priority each undecided agent runs `pibt(i, parent)`: it takes its best cell
//! that is free (not a wall, no corner cut, not held by a fixed agent, not claimed by a decided
//! agent's move or its side cells, not a decided agent's current cell, not its parent's: no
//! swap). A cell where an undecided agent stands is a push: that agent inherits the priority
//! and must leave first (recursively); when its chain fails the pusher tries its next cell, and
//! an agent without any option stays. A pushed agent may not stay.
//!
//! Cells are held until left, so a robot never enters a cell that is vacated in the same round:
//! the pushed agent's move is accepted this round and the pusher waits (a
//! [`Hold`](Verdict::Hold), [`Reserved`](ConflictKind::Reserved)) with its priority, and takes
//! the cell once the other has left it. Likewise a cell being left by a driving agent: a root
//! agent whose best cell it is waits for it, a pushed agent takes a free cell if it has one and
//! waits only as its last resort. Either way the pusher's chain has made way, so the push
//! counts as a success for the pusher's own parent.
//!
//! An accepted move other than the agent's `probable` carries
//! [`Pushed`](ConflictKind::Pushed) (moved out of a higher-priority agent's way) or
//! [`Redirected`](ConflictKind::Redirected) (its cell was taken, or it asked for none). An agent
//! that asked and stays gets a Hold: `Reserved` while it waits for a cell being left,
//! [`Crossing`](ConflictKind::Crossing) when every better cell is taken.
//!
//! An agent deciding for itself (not pushed) whose `probable` is no step on the
//! coordinator's map (a wall, a cell an agent saw close, off the grid, not a neighbour) stays
//! with a Hold of kind [`Invalid`](ConflictKind::Invalid), the asked cell as its `cell`. Its
//! map and the coordinator's disagree on that cell, and only the agent can find out which is
//! right: the Hold tells it the coordinator's word, and a robot that sees the cell open reports
//! it (`agent/src/process/sightings.rs`); the agent asks again meanwhile. Redirecting it
//! instead, along the coordinator's distances, made a robot whose map had a door open that the
//! coordinator still held closed walk back and forth beside the door for the rest of the run;
//! a Block (the dissertation's rule 1) made an HNAV agent turn round in a one-cell corridor
//! (its path constructor may step down after a block and then avoids the cells it left).
//!
//! Accepted moves keep the invariants of the [module docs](super): no cell is held by two
//! rows after `next <- cell`, hence no swap, and a diagonal's side cells are free.
//!
//! # Cost
//!
//! [`Pibt::new`] builds the distance tables (one Dijkstra per agent) and sizes every buffer.
//! A round sorts the agents in place and visits each agent's 9 options once per attempt, with
//! generation stamps instead of clearing the per-cell table; it allocates nothing (the
//! caller's `out` keeps its capacity).

pub mod distance;
pub(crate) mod swap;
#[cfg(test)]
pub(crate) mod tests;

use hnav_runtime::grid::{Cell, Direction, Grid};
use hnav_runtime::msg::{ConflictKind, Verdict};

use super::resolve::cmp_priority;
use super::shared_paths::{side_cells, AgentMode, AgentRow, Options, Outcome};
use distance::{can_step, Distances};

/// A distance as the leading part of a preference key: above the 36 bits of the tie breaks
/// (distances beyond 2^27 - 1, far beyond any map's, and unreachable ones share the top).
fn rank(distance: u32) -> u64 {
    u64::from(distance.min((1 << 27) - 1)) << 36
}

/// "No agent" in the per-cell table.
const NOBODY: u32 = u32::MAX;

/// Where an agent stands in this round's search.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
enum State {
    /// Driving or standing: fixed for the round.
    #[default]
    Fixed,
    /// At rest and not decided yet: may be pushed.
    Undecided,
    /// On the current chain of pushes: its cell is taken.
    InChain,
    /// Decided.
    Decided,
}

/// What one cell holds this round; valid only when `stamp` is the round's.
#[derive(Clone, Copy, Debug)]
struct CellState {
    stamp: u32,
    /// The fixed agent holding it.
    fixed: u32,
    /// Whether `fixed` is driving out of it.
    vacating: bool,
    /// The taking part agent standing on it.
    occupant: u32,
    /// The decided agent moving into it or sweeping it.
    claim: u32,
}

const EMPTY: CellState = CellState {
    stamp: 0,
    fixed: NOBODY,
    vacating: false,
    occupant: NOBODY,
    claim: NOBODY,
};

/// How an agent's attempt ended.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Step {
    /// It moves this round.
    Moved,
    /// It stays this round, but its way is being made (a pushed agent moves, or its cell is
    /// being left).
    Waiting,
    /// It found no way.
    Failed,
}

/// Whether (and how) an agent may enter a cell.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Entry {
    No,
    Free,
    /// The cell is being left by this driving agent.
    Vacating(u32),
    /// This undecided agent stands there.
    Push(u32),
}

/// One agent's decision this round.
#[derive(Clone, Copy, Debug)]
struct Choice {
    to: Cell,
    kind: ConflictKind,
    other: u32,
}

/// PIBT rounds for one grid and one set of goals; see the [module docs](self).
#[derive(Clone, Debug)]
pub struct Pibt {
    width: u32,
    height: u32,
    blocked: Vec<bool>,
    options: Options,
    distances: Distances,
    stamp: u32,
    cells: Vec<CellState>,
    state: Vec<State>,
    choice: Vec<Choice>,
    waited: Vec<u32>,
    /// This round, per agent: the cornered agent it could not push out of its way (it takes
    /// over the pusher's rank), or [`NOBODY`].
    handover: Vec<u32>,
    order: Vec<u32>,
    /// Whether the swap operation ([`swap`]) is on (off by default, see [`Pibt::set_swap`]).
    swap: bool,
}

impl Pibt {
    /// Rounds on `grid` (its blocked cells are copied) for agents with these `goals`, agent
    /// `i` heading for `goals[i]`; rows beyond the goals are fixed obstacles.
    pub fn new(grid: &Grid, goals: &[Cell], options: Options) -> Self {
        let n = goals.len();
        Pibt {
            width: grid.width(),
            height: grid.height(),
            blocked: grid.blocked().to_vec(),
            options,
            distances: Distances::new(grid, goals, options.corner_cutting),
            stamp: 0,
            cells: vec![EMPTY; grid.len()],
            state: vec![State::Fixed; n],
            choice: vec![
                Choice {
                    to: Cell::new(0, 0),
                    kind: ConflictKind::None,
                    other: NOBODY,
                };
                n
            ],
            waited: vec![0; n],
            handover: vec![NOBODY; n],
            order: Vec::with_capacity(n),
            swap: false,
        }
    }

    /// Switches the swap operation (LaCAM3's, in `pibt/swap.rs`) on or off. It is off by
    /// default and not a scenario option yet: on the MovingAI instances it brings more robots home (the
    /// `mapf_table` measurement), but on one random instance of the property test it keeps 4
    /// of 11 agents from ever reaching their goals, which plain PIBT solves.
    pub fn set_swap(&mut self, on: bool) {
        self.swap = on;
    }

    /// Whether exact distance tables were built (else the octile heuristic ranks the cells:
    /// more than [`distance::MAX_TABLE_ENTRIES`] agent-cells).
    pub fn exact_distances(&self) -> bool {
        self.distances.exact()
    }

    /// Agent `agent` heads for `goal` from now on (a lifelong run's next task, on the `grid`
    /// these rounds were made for).
    pub fn set_goal(&mut self, grid: &Grid, agent: usize, goal: Cell) {
        self.distances
            .set_goal(grid, self.options.corner_cutting, agent, goal);
    }

    /// The map changed (a door closed, a pallet was moved away): `grid` has the shape these
    /// rounds were made for and its blocked cells are copied, and every agent's distance
    /// table is computed again for its current goal. The agents' dynamic priorities stay.
    pub fn set_map(&mut self, grid: &Grid) {
        self.blocked.copy_from_slice(grid.blocked());
        let goals: Vec<Cell> = (0..self.state.len())
            .filter_map(|i| self.distances.goal(i))
            .collect();
        self.distances = Distances::new(grid, &goals, self.options.corner_cutting);
    }

    /// Agent `agent`'s dynamic priority: rounds since it was last on its goal.
    pub fn waited(&self, agent: usize) -> u32 {
        self.waited.get(agent).copied().unwrap_or(0)
    }

    /// The distance from `cell` to agent `agent`'s goal in [`distance::STRAIGHT`] units per
    /// straight step ([`distance::UNREACHABLE`] if cut off).
    pub fn distance(&self, agent: usize, cell: Cell) -> u32 {
        self.distances.get(agent, cell)
    }

    /// Decides one round: `out[i]` is the outcome for `rows[i]` (`i` = agent index). `out` is
    /// cleared first and keeps its capacity.
    pub fn resolve(&mut self, rows: &[AgentRow], out: &mut Vec<Outcome>) {
        out.clear();
        self.next_stamp();
        let n = rows.len().min(self.state.len());
        for (i, row) in rows.iter().enumerate() {
            let takes_part = i < n
                && row.is_at_rest()
                && matches!(row.mode, AgentMode::Active | AgentMode::Finished);
            if i < n {
                self.handover[i] = NOBODY;
            }
            if takes_part {
                self.state[i] = State::Undecided;
                if let Some(c) = self.cell_mut(row.current) {
                    c.occupant = i as u32;
                }
                continue;
            }
            if i < n {
                self.state[i] = State::Fixed;
            }
            let driving = !row.is_at_rest();
            for (k, cell) in row.held(&self.options).into_iter().enumerate() {
                if let Some(c) = cell.and_then(|cell| self.cell_mut(cell)) {
                    c.fixed = i as u32;
                    c.vacating = driving && k == 0;
                }
            }
        }
        self.order.clear();
        let state = &self.state;
        self.order
            .extend((0..n as u32).filter(|&i| state[i as usize] == State::Undecided));
        let waited = &self.waited;
        self.order.sort_unstable_by(|&a, &b| {
            let (ia, ib) = (a as usize, b as usize);
            waited[ib]
                .cmp(&waited[ia])
                .then(cmp_priority(rows[ib].priority, rows[ia].priority))
                .then(a.cmp(&b))
        });
        for k in 0..self.order.len() {
            let i = self.order[k] as usize;
            if self.state[i] == State::Undecided {
                self.attempt(i, None, rows);
            }
        }
        for (i, row) in rows.iter().enumerate() {
            out.push(self.outcome(i, row));
            if i < n {
                let at = if self.state[i] == State::Decided {
                    self.choice[i].to
                } else {
                    row.next
                };
                self.waited[i] = if Some(at) == self.distances.goal(i) {
                    0
                } else {
                    self.waited[i].saturating_add(1)
                };
            }
        }
        for i in 0..n {
            let k = self.handover[i] as usize;
            if k < n {
                self.waited[k] = self.waited[k].max(self.waited[i].saturating_add(1));
            }
        }
    }

    fn next_stamp(&mut self) {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.cells.fill(EMPTY);
            self.stamp = 1;
        }
    }

    fn index(&self, cell: Cell) -> Option<usize> {
        (cell.x < self.width && cell.y < self.height)
            .then(|| cell.y as usize * self.width as usize + cell.x as usize)
    }

    /// The cell's state this round (reset on first touch), `None` off the grid.
    fn cell_mut(&mut self, cell: Cell) -> Option<&mut CellState> {
        let i = self.index(cell)?;
        let c = &mut self.cells[i];
        if c.stamp != self.stamp {
            *c = CellState {
                stamp: self.stamp,
                ..EMPTY
            };
        }
        Some(c)
    }

    fn cell(&self, cell: Cell) -> CellState {
        match self.index(cell) {
            Some(i) if self.cells[i].stamp == self.stamp => self.cells[i],
            _ => EMPTY,
        }
    }

    /// Agent `i`'s options, best first: `(cell, key)` with staying included; see the module
    /// docs.
    fn preferences(&self, i: usize, row: &AgentRow, parent: Option<u32>) -> ([Cell; 9], usize) {
        let from = row.current;
        // A pushed agent prefers, among equally good cells, the one farthest from its
        // pusher's goal: it makes way rather than stepping onto the pusher's path, where the
        // pusher would push it again (two agents in each other's goal pockets did so for ever).
        let out_of_way = |to: Cell| -> u64 {
            parent.map_or(0, |p| {
                let d = self.distances.get(p as usize, to);
                u64::from(u32::MAX - d.min(u32::MAX - 1))
            })
        };
        // Ties between equally distant neighbours rotate with the round and the agent: a
        // fixed order lets two agents push each other off their goals in turn for ever, and
        // PIBT breaks such ties at random; this is deterministic.
        let salt = (self.stamp as usize).wrapping_add(i) % 8;
        let mut keyed = [(u64::MAX, from); 9];
        keyed[0] = (rank(self.distances.get(i, from)), from);
        let mut len = 1;
        for d in Direction::ALL {
            let step = can_step(
                &self.blocked,
                self.width,
                self.height,
                self.options.corner_cutting,
                from,
                d,
            );
            let Some(to) = step else { continue };
            let key = if row.probable == Some(to) && row.mode == AgentMode::Active {
                0
            } else {
                rank(self.distances.get(i, to))
                    + (out_of_way(to) << 4)
                    + 1
                    + ((d.index() + salt) % 8) as u64
            };
            keyed[len] = (key, to);
            len += 1;
        }
        keyed[..len].sort_unstable_by_key(|&(key, _)| key);
        let mut cells = [from; 9];
        for (c, &(_, cell)) in cells.iter_mut().zip(&keyed[..len]) {
            *c = cell;
        }
        (cells, len)
    }

    /// Whether agent `i` in `from` may enter `to` this round.
    fn entry(&self, i: usize, from: Cell, to: Cell) -> Entry {
        let me = i as u32;
        let target = self.cell(to);
        if let Some([a, b]) = side_cells(from, to).filter(|_| self.options.sweep) {
            for side in [a, b] {
                let s = self.cell(side);
                let taken = |x: u32| x != NOBODY && x != me;
                if taken(s.fixed) || taken(s.claim) || taken(s.occupant) {
                    return Entry::No;
                }
            }
        }
        if target.claim != NOBODY {
            return Entry::No;
        }
        if target.fixed != NOBODY {
            return if target.vacating {
                Entry::Vacating(target.fixed)
            } else {
                Entry::No
            };
        }
        match target.occupant {
            NOBODY => Entry::Free,
            k if self.state[k as usize] == State::Undecided => Entry::Push(k),
            _ => Entry::No,
        }
    }

    /// `pibt(i, parent)`: decides agent `i` (undecided, at rest); see the module docs.
    fn attempt(&mut self, i: usize, parent: Option<u32>, rows: &[AgentRow]) -> Step {
        self.state[i] = State::InChain;
        let row = &rows[i];
        if parent.is_none() && self.invalid_request(row) {
            self.stay(i, row.current, ConflictKind::Invalid, NOBODY);
            return Step::Failed;
        }
        let (mut prefs, len) = self.preferences(i, row, parent);
        let partner = self
            .swap
            .then(|| self.swap_partner(i, row.current, prefs[0]))
            .flatten();
        if partner.is_some() {
            prefs[..len].reverse();
        }
        let mut last_resort = NOBODY;
        let mut resort_cell = row.current;
        let mut failed_push = NOBODY;
        for (rank, &to) in prefs[..len].iter().enumerate() {
            // The swap's pull: on its first (reversed) choice the partner takes over the
            // rank, see `swap`.
            let pull = if rank == 0 { partner } else { None };
            if to == row.current {
                if parent.is_none() {
                    self.handover[i] = failed_push;
                    let kind = if row.probable.is_some() {
                        ConflictKind::Crossing
                    } else {
                        ConflictKind::None
                    };
                    let other = row.probable.map_or(NOBODY, |p| self.blocker(p));
                    self.stay(i, row.current, kind, other);
                    return Step::Failed;
                }
                continue;
            }
            match self.entry(i, row.current, to) {
                Entry::No => {}
                Entry::Free => {
                    self.take(i, row, to, parent);
                    if let Some(j) = pull {
                        self.handover[i] = j;
                    }
                    return Step::Moved;
                }
                Entry::Vacating(by) if parent.is_none() => {
                    self.claim_sides(row.current, to, i as u32);
                    self.stay(i, row.current, ConflictKind::Reserved, by);
                    return Step::Waiting;
                }
                Entry::Vacating(by) => {
                    if last_resort == NOBODY {
                        last_resort = by;
                        resort_cell = to;
                    }
                }
                Entry::Push(k) => {
                    // The pushed agent must not escape into the sides of the move it makes
                    // way for, nor may anyone else take them while the pusher waits.
                    self.claim_sides(row.current, to, i as u32);
                    if self.attempt(k as usize, Some(i as u32), rows) != Step::Failed {
                        if let Some(j) = pull {
                            self.handover[i] = j;
                        }
                        self.stay(i, row.current, ConflictKind::Reserved, k);
                        return Step::Waiting;
                    }
                    self.claim_sides(row.current, to, NOBODY);
                    if failed_push == NOBODY {
                        failed_push = k;
                    }
                }
            }
        }
        if last_resort != NOBODY {
            self.claim_sides(row.current, resort_cell, i as u32);
            self.stay(i, row.current, ConflictKind::Reserved, last_resort);
            return Step::Waiting;
        }
        if parent.is_none() {
            self.handover[i] = failed_push;
        }
        self.stay(
            i,
            row.current,
            ConflictKind::Crossing,
            parent.unwrap_or(NOBODY),
        );
        Step::Failed
    }

    /// Whether the row asks for a step that is none on this map: a blocked or off-grid cell, a
    /// diagonal past a blocked corner, or no neighbour.
    fn invalid_request(&self, row: &AgentRow) -> bool {
        let Some(p) = row.probable.filter(|_| row.mode == AgentMode::Active) else {
            return false;
        };
        let Some(d) = Direction::between(row.current, p) else {
            return true;
        };
        let (blocked, w, h) = (&self.blocked, self.width, self.height);
        can_step(blocked, w, h, self.options.corner_cutting, row.current, d).is_none()
    }

    /// Who keeps agent `i` from `cell` (for the outcome's `other`), if anyone.
    fn blocker(&self, cell: Cell) -> u32 {
        let c = self.cell(cell);
        [c.claim, c.fixed, c.occupant]
            .into_iter()
            .find(|&x| x != NOBODY)
            .unwrap_or(NOBODY)
    }

    fn stay(&mut self, i: usize, at: Cell, kind: ConflictKind, other: u32) {
        self.state[i] = State::Decided;
        self.choice[i] = Choice {
            to: at,
            kind,
            other,
        };
    }

    /// Marks the side cells of the diagonal `from -> to` as claimed by `by` ([`NOBODY`] to
    /// release them: they were free before, [`Pibt::entry`] checked).
    fn claim_sides(&mut self, from: Cell, to: Cell, by: u32) {
        let Some(sides) = side_cells(from, to).filter(|_| self.options.sweep) else {
            return;
        };
        for side in sides {
            if let Some(c) = self.cell_mut(side) {
                c.claim = by;
            }
        }
    }

    fn take(&mut self, i: usize, row: &AgentRow, to: Cell, parent: Option<u32>) {
        self.state[i] = State::Decided;
        let kind = match parent {
            Some(_) => ConflictKind::Pushed,
            None if row.probable == Some(to) && row.mode == AgentMode::Active => ConflictKind::None,
            None => ConflictKind::Redirected,
        };
        self.choice[i] = Choice {
            to,
            kind,
            other: parent.unwrap_or(NOBODY),
        };
        let sides = side_cells(row.current, to).filter(|_| self.options.sweep);
        for cell in [Some(to)]
            .into_iter()
            .chain(sides.into_iter().flatten().map(Some))
            .flatten()
        {
            if let Some(c) = self.cell_mut(cell) {
                c.claim = i as u32;
            }
        }
    }

    fn outcome(&self, i: usize, row: &AgentRow) -> Outcome {
        if self.state.get(i) != Some(&State::Decided) {
            return Outcome::default();
        }
        let c = self.choice[i];
        let other = (c.other != NOBODY).then_some(c.other);
        if c.to != row.current {
            return Outcome {
                verdict: Verdict::Accept,
                refused: 0,
                kind: c.kind,
                cell: Some(c.to),
                other,
            };
        }
        let asked = row.probable.filter(|_| row.mode == AgentMode::Active);
        Outcome {
            verdict: Verdict::Hold,
            refused: 0,
            kind: if asked.is_some() {
                c.kind
            } else {
                ConflictKind::None
            },
            cell: asked.filter(|&p| self.index(p).is_some()),
            other: asked.and(other),
        }
    }
}
