//! The path constructor (КП, §2.8.5, Table 2-3, §3.3–3.4, seed 001): gradient ascent on a
//! built neural map.
//!
//! From the current neuron `i` it computes the 8 gradients `(E_j - E_i) * w_ij` clockwise
//! from 12 o'clock (N, NE, E, SE, S, SW, W, NW; the ascent form of eq. 3.5, whose printed
//! sign would walk downhill) and moves to the largest. Around that:
//!
//! * **Refused directions** get gradient `-1` and are never taken: outside the grid, an
//!   obstacle, or refused by the caller's [`DirectionMask`] (the coordinator's "virtual
//!   obstacle", §3.4).
//! * **Corners** (Fig. 3-7): with [`DiagonalRule::NoCornerCutting`] a diagonal is refused when
//!   either adjacent orthogonal direction is refused (`grad_d = -1 <= grad_{d±1} = -1`). By
//!   default the path uses the map's own rule, so every link the wave travelled is a legal move.
//! * **Visited cells** ([`VisitedRule`]): seed 001 negates a cell's value once the robot leaves
//!   it, so that it never oscillates between two cells; Chapter 2 sets it to 0.
//! * **Heading** (eq. 3.7, optional): the gradient in the current direction of motion is
//!   multiplied by `sqrt 2`, which favours going straight on (fewer turns).
//! * **Ties**: gradients within `tie_tolerance` times the neighbourhood's largest activation are
//!   equal, and the first one clockwise from north wins. Exactly symmetric neighbours (an open
//!   map) then give the same choice whatever the rounding of the implementation.
//!
//! The map only has to be read through [`ActivationField::local`], which gives the 3x3 values
//! in one common scale; comparisons of scaled values are comparisons of the true values.
//!
//! Why the ascent reaches the target on a map built with a wave-front stop rule: a free
//! neuron's value is at most the weighted average of its linked neighbours (it was computed
//! from their earlier, smaller values), so every non-target neuron that is on has a linked
//! neighbour at least as large, hence some gradient is positive; taking only positive gradients
//! makes the values strictly increase along the path, so no cell repeats and the walk ends at
//! the only neuron without a larger neighbour, the target.

use hnav_runtime::grid::{Cell, Direction};
use serde::{Deserialize, Serialize};

use crate::error::{check_inside, Error, Role};
use crate::neural_map::{ActivationField, DiagonalRule};

/// What happens to a cell's activation once the robot has left it.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VisitedRule {
    /// Nothing.
    Keep,
    /// Set to 0 (§2.8.5: "reset the value of already visited cells").
    Zero,
    /// Set to `-|E|` (seed 001's sign flip against oscillation; idempotent, so a cell
    /// crossed twice does not flip back).
    #[default]
    Negate,
}

/// Options of the path constructor.
#[derive(Clone, Copy, PartialEq, Debug, Serialize, Deserialize)]
pub struct PathOptions {
    /// `w_ij` of straight moves in the gradient.
    pub straight_weight: f64,
    /// `w_ij` of diagonal moves in the gradient (`1 / sqrt 2`: the slope per unit length).
    pub diagonal_weight: f64,
    /// Corner rule for moves; `None` follows the map's [`DiagonalRule`].
    pub corner_rule: Option<DiagonalRule>,
    /// What happens to left cells.
    pub visited: VisitedRule,
    /// Eq. 3.7: multiply the gradient in the current heading by `sqrt 2`.
    pub heading_bonus: bool,
    /// Gradients closer than this times the largest activation of the 3x3 block are ties.
    pub tie_tolerance: f64,
    /// Give up after this many moves; `None` means `2 * width * height + 8`.
    pub max_steps: Option<usize>,
}

impl Default for PathOptions {
    fn default() -> Self {
        PathOptions {
            straight_weight: 1.0,
            diagonal_weight: std::f64::consts::FRAC_1_SQRT_2,
            corner_rule: None,
            visited: VisitedRule::Negate,
            heading_bonus: false,
            tie_tolerance: 1e-5,
            max_steps: None,
        }
    }
}

impl PathOptions {
    /// Rejects weights that are not positive and finite and a negative tolerance.
    pub fn validate(&self) -> Result<(), Error> {
        for (name, v) in [
            ("straight_weight", self.straight_weight),
            ("diagonal_weight", self.diagonal_weight),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::option(name, format!("{v} is not a positive number")));
            }
        }
        if !(self.tie_tolerance.is_finite() && self.tie_tolerance >= 0.0) {
            return Err(Error::option(
                "tie_tolerance",
                format!("{} is not >= 0", self.tie_tolerance),
            ));
        }
        Ok(())
    }
}

/// Directions the caller refuses (bit `d` set = direction `d` refused).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, Serialize, Deserialize)]
pub struct DirectionMask(pub u8);

impl DirectionMask {
    /// Nothing refused.
    pub const NONE: DirectionMask = DirectionMask(0);

    /// This mask with `d` refused too.
    pub fn refuse(self, d: Direction) -> DirectionMask {
        DirectionMask(self.0 | (1 << d.index()))
    }

    /// Whether `d` is refused.
    pub fn is_refused(self, d: Direction) -> bool {
        self.0 & (1 << d.index()) != 0
    }
}

/// The 8 gradients of one step, clockwise from north.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Gradients {
    /// `(E_j - E_i) * w_ij` in the map's local scale (true value times `2^-log2_scale`),
    /// `-1` for refused directions.
    pub values: [f64; 8],
    /// Bit `d` set when direction `d` may be taken.
    pub allowed: u8,
    /// Power of two the values are scaled by.
    pub log2_scale: i64,
    /// Largest absolute activation of the 3x3 block, in the same scale (for tie tolerance).
    pub scale: f64,
}

impl Gradients {
    /// Whether direction `d` may be taken.
    pub fn is_allowed(&self, d: Direction) -> bool {
        self.allowed & (1 << d.index()) != 0
    }
}

/// How a traced path ended.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PathOutcome {
    /// The target was reached.
    Reached,
    /// The start's neuron is 0: the wave never reached it (checked before moving).
    Unreachable,
    /// Every direction was refused.
    Stuck,
    /// The step limit was hit.
    StepLimit,
}

/// A traced path.
#[derive(Clone, PartialEq, Debug, Serialize, Deserialize)]
pub struct Path {
    /// Cells from the start to where the walk ended (the target when reached).
    pub cells: Vec<Cell>,
    /// How it ended.
    pub outcome: PathOutcome,
    /// Moves made (`cells.len() - 1`).
    pub steps: usize,
    /// Changes of direction between consecutive moves.
    pub turns: usize,
    /// Length with straight moves 1 and diagonal moves `sqrt 2` (the "encoder" of §2.10).
    pub length: f64,
}

impl Path {
    /// Whether the target was reached.
    pub fn reached(&self) -> bool {
        self.outcome == PathOutcome::Reached
    }
}

/// The gradient-ascent planner. Holds only options; every call is independent.
#[derive(Clone, Copy, PartialEq, Debug, Default)]
pub struct PathConstructor {
    options: PathOptions,
}

impl PathConstructor {
    /// A constructor with validated options.
    pub fn new(options: PathOptions) -> Result<PathConstructor, Error> {
        options.validate()?;
        Ok(PathConstructor { options })
    }

    /// The options.
    pub fn options(&self) -> &PathOptions {
        &self.options
    }

    /// The 8 gradients at `cell`. `heading` is the direction of the last move (for eq. 3.7),
    /// `visited` tells which cells the robot has left (for [`VisitedRule`]).
    pub fn gradients<F: ActivationField + ?Sized>(
        &self,
        map: &F,
        cell: Cell,
        heading: Option<Direction>,
        mask: DirectionMask,
        visited: impl Fn(Cell) -> bool,
    ) -> Gradients {
        let o = &self.options;
        let local = map.local(cell);
        let rule = o.corner_rule.unwrap_or_else(|| map.diagonal_rule());
        let adjust = |v: f64, c: Cell| match o.visited {
            VisitedRule::Keep => v,
            _ if !visited(c) => v,
            VisitedRule::Zero => 0.0,
            VisitedRule::Negate => -v.abs(),
        };
        let centre = adjust(local.centre(), cell);
        let mut scale = centre.abs();
        let neighbour = |d: Direction| {
            cell.offset(d.dx(), d.dy())
                .filter(|&c| c.x < map.width() && c.y < map.height())
        };
        let refused =
            |d: Direction| mask.is_refused(d) || neighbour(d).is_none_or(|c| map.is_blocked(c));
        let mut g = Gradients {
            values: [-1.0; 8],
            allowed: 0,
            log2_scale: local.log2_scale,
            scale: 0.0,
        };
        for d in Direction::ALL {
            let Some(n) = neighbour(d) else { continue };
            if refused(d) {
                continue;
            }
            if d.is_diagonal() {
                let a = Direction::ALL[(d.index() + 7) % 8];
                let b = Direction::ALL[(d.index() + 1) % 8];
                if !rule.allows(refused(a), refused(b)) {
                    continue;
                }
            }
            let v = adjust(local.neighbour(d), n);
            scale = scale.max(v.abs());
            let w = if d.is_diagonal() {
                o.diagonal_weight
            } else {
                o.straight_weight
            };
            let bonus = if o.heading_bonus && heading == Some(d) {
                std::f64::consts::SQRT_2
            } else {
                1.0
            };
            g.values[d.index()] = (v - centre) * w * bonus;
            g.allowed |= 1 << d.index();
        }
        g.scale = scale;
        g
    }

    /// The direction to take: the largest gradient, near-ties to the first clockwise from
    /// north, and only a positive gradient when one exists. `None` if all are refused.
    pub fn choose(&self, g: &Gradients) -> Option<Direction> {
        let allowed = Direction::ALL.into_iter().filter(|d| g.is_allowed(*d));
        let best = allowed
            .clone()
            .map(|d| g.values[d.index()])
            .fold(f64::NEG_INFINITY, f64::max);
        let tol = self.options.tie_tolerance * g.scale;
        let mut candidates = allowed.filter(|d| g.values[d.index()] >= best - tol);
        if best > 0.0 {
            candidates.find(|d| g.values[d.index()] > 0.0)
        } else {
            candidates.next()
        }
    }

    /// One step from `cell` without any memory of visited cells: the direction and the
    /// gradients it was chosen from.
    pub fn next_step<F: ActivationField + ?Sized>(
        &self,
        map: &F,
        cell: Cell,
        heading: Option<Direction>,
        mask: DirectionMask,
    ) -> (Option<Direction>, Gradients) {
        let g = self.gradients(map, cell, heading, mask, |_| false);
        (self.choose(&g), g)
    }

    /// Climbs from `start` to the map's target with no direction refused by a caller.
    pub fn trace<F: ActivationField + ?Sized>(&self, map: &F, start: Cell) -> Result<Path, Error> {
        let Some(target) = map.target() else {
            return Err(Error::option("map", "build the map before tracing a path"));
        };
        check_inside(start, Role::Start, map.width(), map.height())?;
        if map.is_blocked(start) {
            return Err(Error::Blocked {
                role: Role::Start,
                cell: start,
            });
        }
        let mut path = Path {
            cells: vec![start],
            outcome: PathOutcome::Reached,
            steps: 0,
            turns: 0,
            length: 0.0,
        };
        if start == target {
            return Ok(path);
        }
        if !map.is_on(start) {
            path.outcome = PathOutcome::Unreachable;
            return Ok(path);
        }
        let max_steps = self
            .options
            .max_steps
            .unwrap_or_else(|| 2 * map.width() as usize * map.height() as usize + 8);
        let mut walker = Walker::new(map.width(), map.height(), start);
        while walker.cell() != target {
            if path.steps >= max_steps {
                path.outcome = PathOutcome::StepLimit;
                return Ok(path);
            }
            let (choice, _) = walker.propose(self, map, DirectionMask::NONE);
            let Some(d) = choice else {
                path.outcome = PathOutcome::Stuck;
                return Ok(path);
            };
            if walker.heading().is_some_and(|h| h != d) {
                path.turns += 1;
            }
            path.cells.push(walker.advance(d));
            path.steps += 1;
            path.length += d.cost();
        }
        Ok(path)
    }
}

/// A robot climbing a map one step at a time: its cell, heading and the cells it has left
/// (for [`VisitedRule`]). The coordinator's loop: [`Walker::propose`] with the directions it
/// refuses, then [`Walker::advance`] once the move is committed (or nothing, to wait).
#[derive(Clone, Debug)]
pub struct Walker {
    cell: Cell,
    heading: Option<Direction>,
    width: usize,
    /// One bit per cell, row-major.
    left: Vec<u64>,
}

impl Walker {
    /// A walker at `start` on a `width x height` map.
    pub fn new(width: u32, height: u32, start: Cell) -> Walker {
        let cells = width as usize * height as usize;
        Walker {
            cell: start,
            heading: None,
            width: width as usize,
            left: vec![0; cells.div_ceil(64)],
        }
    }

    /// The current cell.
    pub fn cell(&self) -> Cell {
        self.cell
    }

    /// The direction of the last move.
    pub fn heading(&self) -> Option<Direction> {
        self.heading
    }

    /// Whether the walker has left `cell` at some point (`false` outside the map).
    pub fn has_left(&self, cell: Cell) -> bool {
        let i = cell.y as usize * self.width + cell.x as usize;
        cell.x < self.width as u32
            && self
                .left
                .get(i / 64)
                .is_some_and(|w| w & (1 << (i % 64)) != 0)
    }

    /// The next direction under `mask` and the gradients it was chosen from.
    pub fn propose<F: ActivationField + ?Sized>(
        &self,
        constructor: &PathConstructor,
        map: &F,
        mask: DirectionMask,
    ) -> (Option<Direction>, Gradients) {
        let g = constructor.gradients(map, self.cell, self.heading, mask, |c| self.has_left(c));
        (constructor.choose(&g), g)
    }

    /// Forgets every cell left so far (a new climb from where the walker stands), without
    /// allocating.
    pub fn forget_visited(&mut self) {
        self.left.fill(0);
    }

    /// Makes the move `d`: the current cell becomes "left" and the walker steps. Returns the
    /// new cell. The move is not checked against the map (the coordinator has done that).
    pub fn advance(&mut self, d: Direction) -> Cell {
        let i = self.cell.y as usize * self.width + self.cell.x as usize;
        if let Some(w) = self.left.get_mut(i / 64) {
            *w |= 1 << (i % 64);
        }
        self.heading = Some(d);
        self.cell = Cell::new(
            self.cell.x.wrapping_add_signed(d.dx()),
            self.cell.y.wrapping_add_signed(d.dy()),
        );
        self.cell
    }
}
