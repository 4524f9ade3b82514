//! One round of `shared_paths` as every rule set sees it: an [`AgentRow`] per agent in, an
//! [`Outcome`] per agent out, under the round's [`Options`].

use hnav_runtime::grid::{Cell, CornerCutting, Direction, Grid};
use hnav_runtime::msg::{ConflictKind, Decision, Verdict, NO_CELL};

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

/// Options of a round of any rule set (`Resolver`, `Pibt`, `Lacam`).
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
