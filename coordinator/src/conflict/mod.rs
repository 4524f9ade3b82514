//! Conflict resolution between agents: one decision round of the dissertation's
//! `shared_paths` check (§3.3.1–3.3.2, Figs. 3-5 to 3-7; seed 001's rules (a) and (b)).
//!
//! A pure function of the round's rows, with no I/O: the coordinator process calls
//! [`Resolver::resolve`] once per decision round, tests call it from a discrete-time loop.
//! [`Pibt`] is another round (`[coordinator] rules = "pibt"`, priority inheritance; see
//! [`pibt`]) over the same rows and outcomes, with the same invariants, and [`Lacam`] a third
//! (`rules = "lacam"`: a whole plan searched with LaCAM and followed; see [`lacam`]).
//!
//! # The model, and why it is this one
//!
//! Each agent has a row of `shared_paths` ([`AgentRow`]): the cell it is in (`current`), the
//! cell it has been committed to and is driving to (`next`, equal to `current` at rest), and
//! the step it asks for (`probable`). The dissertation shifts the row when a probable step is
//! accepted (`next <- probable`) and again when the robot arrives (`current <- next`).
//!
//! The papers check points: two agents conflict when they want the same cell or each other's
//! cells at the same instant. Physical robots occupy a cell's width and take time to cross, so
//! here cells are **reserved until the robot has left them**: a row holds `current` and `next`
//! and, while it drives a diagonal, the two orthogonal side cells of that diagonal too (a
//! robot as wide as a cell sweeps their corners; its body at the shared corner point is
//! `1/sqrt 2` cell from their centres). A move is accepted only into cells nobody holds, and
//! accepted moves never sweep a common cell. So, if no two rows held a common cell before the
//! round, none do after `next <- probable` for every accepted row: no co-location, and hence
//! no swap, which needs one robot to enter a cell the other has not left. This is stronger
//! than the papers' rules, and it costs time exactly where they let two robots touch: a robot
//! may not follow into a cell that is being vacated in the same round, and a robot may not cut
//! the corner of a cell another robot stands in. [`Options::sweep`] switches the side cells
//! off, giving the papers' point robots (the seed-001 reproduction needs that; the
//! no-co-location guarantee then holds for `current` and `next` only).
//!
//! Only an agent **at rest** (`next == current`) asks for a step. A moving agent has nothing
//! to decide: its `next` was verified and "will not change" (§3.3.1), and letting it queue a
//! second step would reserve three cells ahead of a robot that may still stop.
//!
//! # The rules (checked in this order for each agent A asking for `p`, direction `d`)
//!
//! | # | situation | verdict | kind |
//! |---|---|---|---|
//! | 1 | `p` not an 8-neighbour of `current`, off the grid or blocked | Block (bit `d` when `d` exists) | [`Invalid`](ConflictKind::Invalid) |
//! | 2 | diagonal past blocked map corners (Fig. 3-7, per [`CornerCutting`]), or whose side cell another agent holds | Block | [`CornerCut`](ConflictKind::CornerCut) |
//! | 3 | `p` held by a [`Standing`](AgentMode::Standing) or [`Finished`](AgentMode::Finished) agent: type (d), whatever the priorities | Block | [`StableCell`](ConflictKind::StableCell) |
//! | 4 | head-on, type (b): an active agent B at rest asks for A's cell while A asks for B's | lower priority Block, higher Hold, equal both Block | [`HeadOn`](ConflictKind::HeadOn) |
//! | 5 | `p` held by another active agent (moving out, or waiting) | Hold | [`Reserved`](ConflictKind::Reserved) |
//! | 6 | crossing, type (a): the footprints (`p` plus a diagonal's side cells) of two remaining requests meet | lower priority Block, equal both Block | [`Crossing`](ConflictKind::Crossing) |
//! | 7 | no request (moving, nothing asked, standing, finished) | Hold | [`None`](ConflictKind::None) |
//!
//! Anything else is accepted ([`Verdict::Accept`], `cell = p`). A head-on agent whose
//! footprint also meets a third agent's request is reported as
//! [`Combined`](ConflictKind::Combined), type (c); its verdict is the head-on one.
//!
//! Why these choices:
//!
//! * Priorities: larger wins. The caller supplies them (`P = 1 / speed` by default in the
//!   dissertation, so the slower robot wins and the faster, more agile one dodges).
//! * Head-on: the winner is told to **Hold**, not Accept, because its target cell is still
//!   occupied by the loser; it goes once the loser has sidestepped. With equal priorities both
//!   are refused, the dissertation's "both change direction".
//! * Reserved is a Hold, not a Block: the cell will free itself, so the direction stays right
//!   and the agent's map needs no correction.
//! * Crossing requests are decided in descending priority (ties by agent index), each against
//!   the requests already accepted: the order makes the outcome deterministic and independent
//!   of how the rows were gathered. A request that only conflicts with a refused one goes
//!   ahead, so one refusal does not cascade. Equal priorities refuse both (and revoke the
//!   accepted one), as the papers say; a revoked request still stops later requests of its
//!   own priority, so a tie of three for one cell refuses all three whatever their indices.
//! * A refusal sets the refused direction's bit ([`Outcome::refused`]): the agent's "virtual
//!   obstacle" for this step (§3.4, `grad_d = -1`); a Hold sets none.
//!
//! # Cost
//!
//! [`Resolver::new`] sizes every buffer for the grid and the agent count; a round then runs in
//! `O(n log n)` for `n` agents (one in-place sort; the type (c) check adds `O(n)` per head-on
//! agent) with generation stamps instead of clearing per-cell tables, and allocates nothing
//! (the caller's `out` keeps its capacity).

pub mod lacam;
pub mod pibt;
mod resolve;
#[cfg(test)]
mod tests;

use hnav_runtime::grid::{Cell, CornerCutting, Direction, Grid};
use hnav_runtime::msg::{ConflictKind, Decision, Verdict, NO_CELL};

pub use lacam::Lacam;
pub use pibt::Pibt;
pub use resolve::Resolver;

/// Whether an agent takes part in the round.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub enum AgentMode {
    /// Driving or deciding; may ask for a step when at rest.
    #[default]
    Active,
    /// Standing still: an emergency stop, waiting for a task, missing from the round or dead.
    /// A "stable position" (type d) for the others.
    Standing,
    /// At its goal, staying there; also a stable position.
    Finished,
}

impl AgentMode {
    /// Whether the agent is a fixed obstacle for the others (type d).
    pub fn is_stable(self) -> bool {
        !matches!(self, AgentMode::Active)
    }
}

/// One agent's row of `shared_paths`, as the coordinator knows it at the start of a round.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct AgentRow {
    /// The cell the robot is in.
    pub current: Cell,
    /// The committed cell it is driving to; equal to `current` at rest.
    pub next: Cell,
    /// The step asked for (only honoured from an active agent at rest).
    pub probable: Option<Cell>,
    /// Conflict priority: larger wins.
    pub priority: f64,
    /// Whether it takes part.
    pub mode: AgentMode,
}

impl AgentRow {
    /// An active agent at rest in `cell` asking for `probable`.
    pub fn at_rest(cell: Cell, probable: Option<Cell>, priority: f64) -> Self {
        AgentRow {
            current: cell,
            next: cell,
            probable,
            priority,
            mode: AgentMode::Active,
        }
    }

    /// Whether the agent is at rest (`next == current`).
    pub fn is_at_rest(&self) -> bool {
        self.next == self.current
    }

    /// The cells this row holds under `options`: `current`, `next` and, while driving a
    /// diagonal with [`Options::sweep`], its two side cells. Unused slots are `None`.
    pub fn held(&self, options: &Options) -> [Option<Cell>; 4] {
        let mut cells = [Some(self.current), None, None, None];
        if self.next != self.current {
            cells[1] = Some(self.next);
            if options.sweep {
                if let Some([a, b]) = side_cells(self.current, self.next) {
                    cells[2] = Some(a);
                    cells[3] = Some(b);
                }
            }
        }
        cells
    }
}

/// The two orthogonal side cells of a diagonal move `from -> to` (`None` unless the cells are
/// diagonal neighbours).
pub fn side_cells(from: Cell, to: Cell) -> Option<[Cell; 2]> {
    let d = Direction::between(from, to)?;
    d.is_diagonal()
        .then_some([Cell::new(to.x, from.y), Cell::new(from.x, to.y)])
}

/// Options of a [`Resolver`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct Options {
    /// Diagonals past blocked **map** cells (Fig. 3-7): [`CornerCutting::Forbidden`] refuses a
    /// diagonal when either side cell is blocked (the dissertation's strict rule),
    /// [`CornerCutting::Allowed`] only when both are (a robot never squeezes between two
    /// blocked cells that touch at a corner).
    pub corner_cutting: CornerCutting,
    /// Whether a diagonal move holds its two side cells (physical robots, the default). Off,
    /// agents are points as in the papers: only `current` and `next` are held and a diagonal
    /// may pass a cell another agent stands in.
    pub sweep: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            corner_cutting: CornerCutting::Forbidden,
            sweep: true,
        }
    }
}

/// The decision for one agent.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Outcome {
    /// Accept (`next <- probable`), Block (correct the step) or Hold (wait).
    pub verdict: Verdict,
    /// Refused directions, bit `d` for [`Direction::index`] `d`; 0 unless blocked.
    pub refused: u8,
    /// Why it was blocked or held ([`ConflictKind::None`] when accepted or nothing was asked).
    pub kind: ConflictKind,
    /// The accepted cell, or for a refused or held request the requested cell (the contested
    /// one, seed 001's "crossing" position) when it lies on the grid.
    pub cell: Option<Cell>,
    /// The other agent of the conflict, when there is one.
    pub other: Option<u32>,
}

impl Default for Outcome {
    fn default() -> Self {
        Outcome {
            verdict: Verdict::Hold,
            refused: 0,
            kind: ConflictKind::None,
            cell: None,
            other: None,
        }
    }
}

impl Outcome {
    /// Whether the move was accepted.
    pub fn accepted(&self) -> bool {
        self.verdict == Verdict::Accept
    }

    /// Whether the move was refused (the agent must correct its step).
    pub fn blocked(&self) -> bool {
        self.verdict == Verdict::Block
    }

    /// The wire form for agent `agent`: the committed cell as a row-major index of `grid`
    /// when accepted, [`NO_CELL`] otherwise; no waypoint.
    pub fn decision(&self, agent: u32, grid: &Grid) -> Decision {
        let cell = match (self.verdict, self.cell) {
            (Verdict::Accept, Some(c)) => grid
                .checked_index(c)
                .and_then(|i| u32::try_from(i).ok())
                .unwrap_or(NO_CELL),
            _ => NO_CELL,
        };
        Decision {
            agent,
            verdict: self.verdict as u8,
            refused: self.refused,
            kind: self.kind as u8,
            reserved: 0,
            cell,
            waypoint: NO_CELL,
        }
    }
}
