//! The Hopfield "neural map" (dissertation §2.8–2.11, Appendix A; seed 001).
//!
//! One neuron per grid cell on an orthogonal lattice; each neuron is linked to its 8 neighbours
//! with weight `K / d` (straight `K`, diagonal `K / sqrt 2`, self `0`, eq. 3.2). A sweep updates
//! every free neuron synchronously (Jacobi: all inputs from the previous sweep) with the
//! normalised weighted average of its neighbours (eq. 3.3) passed through the activation
//! function (tanh, eq. 3.4, or linear with saturation, §2.11):
//!
//! ```text
//! u_i = (s * E_i + sum_{j linked to i} w_ij * E_j) / D_i        E_i <- phi(u_i)
//! E_target = 1 (clamped), E_obstacle = 0 (clamped)
//! ```
//!
//! `D_i` is `s + sum w_ij` over the neighbours that [`Denominator`] counts. The gain `K` cancels in
//! the quotient (the notes point this out for Appendix A); it is kept as an option because the
//! dissertation names it.
//!
//! | module | what |
//! |---|---|
//! | here | options ([`NeuralMapOptions`] and its enums), [`StopRule`], [`BuildReport`], the [`ActivationField`] and [`NeuralDynamics`] traits |
//! | [`fast`] | [`NeuralMap`]: the `f32` fast path with an extended exponent (no underflow), double buffers, a growing bounding box |
//! | [`reference`](mod@reference) | [`ReferenceMap`]: the plain `f64` reference implementation (exact where `f64` does not underflow) |
//! | [`weights`] | [`Weights`]: the link weights of eq. 3.2 |
//! | [`matrix`] | the dense [`WeightMatrix`] builder (Table 2-2) |
//! | [`repair`] | §2.10: partial correction and rebuild with partial activation |
//! | `topology` (private) | which neurons are linked and each denominator: the one network definition both implementations build from |
//! | `driver` (private) | the stop rules ([`StopRule`]), written once for both implementations |
//! | `kernel` (private) | the fast path's vectorisable sweep over a rectangle of the padded grid |
//! | `xfloat` (private) | the fast path's number format: `f32` mantissa with an `i32` exponent |
//!
//! # Which variant reproduces what
//!
//! * Fig. 2-16 / 2-18 maze: 19 sweeps to full activation and 13 to the start need
//!   synchronous sweeps and diagonals between two blocked corners ([`DiagonalRule::Always`];
//!   with [`DiagonalRule::NoCornerCutting`] it is 25 and 18), tanh or linear, with
//!   [`Denominator::LinkedOnly`] or [`Denominator::InGrid`] ([`Denominator::AllEight`] needs 21
//!   to full activation with the `1e-16` threshold, because its far values stay below it).
//!   The 13-move path 1, 2, 13, 23, 33, 44, ... comes out when obstacles stay out of the
//!   denominator as in Appendix A ([`Denominator::LinkedOnly`], used by
//!   [`NeuralMapOptions::dissertation`], or [`Denominator::OffGridAsZero`]); counting obstacles
//!   as zeros lowers cell 33 (three free neighbours) below 34, and the path takes 34 instead:
//!   also 13 moves of the same length.
//! * Table 2-1 (empty 10x10, target 56): only qualitatively; the closest variant is tanh with
//!   [`Denominator::AllEight`] stopped after 9 sweeps ([`NeuralMapOptions::table_2_1`]), max
//!   error 0.016.
//! * Seed 001's single-robot runs: [`NeuralMapOptions::seed_001`] (self weight 1, obstacles as
//!   zeros, off-grid cells absent).
//! * Table 2-2: [`WeightMatrix::lattice`] with [`Weights::table_2_2`].

mod driver;
pub mod fast;
mod kernel;
pub mod matrix;
pub mod reference;
pub mod repair;
mod topology;
pub mod weights;
mod xfloat;

use hnav_runtime::grid::{Cell, CornerCutting, Direction};
use serde::{Deserialize, Serialize};

use crate::error::Error;

pub use fast::NeuralMap;
pub use matrix::WeightMatrix;
pub use reference::ReferenceMap;
pub use weights::Weights;

/// The activation function `phi`.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Activation {
    /// Hyperbolic tangent (eq. 3.4), the dissertation's first choice.
    #[default]
    Tanh,
    /// Linear with saturation: `0` below 0, `u` on `[0, 1]`, `1` above (§2.11).
    Linear,
}

impl Activation {
    /// `phi(u)` in `f64`.
    pub fn apply(self, u: f64) -> f64 {
        match self {
            Activation::Tanh => u.tanh().min(1.0),
            Activation::Linear => u.clamp(0.0, 1.0),
        }
    }

    /// The wire encoding of the runtime's `MapHeader::activation`.
    pub fn to_kind(self) -> hnav_runtime::msg::ActivationKind {
        match self {
            Activation::Tanh => hnav_runtime::msg::ActivationKind::Tanh,
            Activation::Linear => hnav_runtime::msg::ActivationKind::Linear,
        }
    }
}

/// Which neighbours count in the denominator `D_i` of eq. 3.3. Neighbours that do not carry a
/// signal (obstacles, off-grid cells, diagonals cut by [`DiagonalRule`]) add 0 to the
/// numerator either way; this only decides whether their weight lowers the average.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Denominator {
    /// Appendix A's code: only linked free neighbours (obstacles are `-1` and skipped). The
    /// default: it reproduces the published Fig. 2-16 path and gives the shortest paths on
    /// random maps (see the `path_quality` example).
    #[default]
    LinkedOnly,
    /// Chapter 2's text: every in-grid neighbour; obstacles (and cut diagonals) count as
    /// zero-valued neurons, which makes the "reduced potential" margin along walls.
    /// Off-grid neighbours are absent. Seed 001's proxy law uses this too.
    InGrid,
    /// Linked neighbours plus off-grid positions as zeros; obstacles absent (Appendix A's
    /// obstacles with zero-valued borders).
    OffGridAsZero,
    /// All eight neighbours always count (obstacles and off-grid cells as zeros); the closest
    /// variant to Table 2-1 (on an empty map it equals [`Denominator::OffGridAsZero`]).
    AllEight,
}

/// Which diagonal links exist, in propagation (and, by default, in the path).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DiagonalRule {
    /// Every diagonal between two free cells, even between two blocked corners: the
    /// dissertation's reproductions need this (19 / 13 on the Fig. 2-16 maze).
    #[default]
    Always,
    /// A diagonal between two blocked corners is cut; one blocked corner is fine.
    NotBetweenTwoBlocked,
    /// A diagonal is cut if either orthogonal corner is blocked: MovingAI's rule and the
    /// path constructor's Fig. 3-7 rule.
    NoCornerCutting,
}

impl DiagonalRule {
    /// Whether a diagonal with these corner states is allowed.
    pub fn allows(self, corner_a_blocked: bool, corner_b_blocked: bool) -> bool {
        match self {
            DiagonalRule::Always => true,
            DiagonalRule::NotBetweenTwoBlocked => !(corner_a_blocked && corner_b_blocked),
            DiagonalRule::NoCornerCutting => !(corner_a_blocked || corner_b_blocked),
        }
    }
}

impl From<CornerCutting> for DiagonalRule {
    fn from(rule: CornerCutting) -> Self {
        match rule {
            CornerCutting::Allowed => DiagonalRule::Always,
            CornerCutting::Forbidden => DiagonalRule::NoCornerCutting,
        }
    }
}

/// When a neuron counts as "on" (activated).
#[derive(Clone, Copy, PartialEq, Debug, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OnThreshold {
    /// Any positive value. With the fast path's extended exponent this is exactly "the wave
    /// has arrived", so full/partial activation take as many sweeps as the link distance.
    #[default]
    NonZero,
    /// Strictly above a value; the dissertation uses `1e-16` (its double precision).
    Above(f64),
}

/// When a build stops.
#[derive(Clone, Copy, PartialEq, Debug, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopRule {
    /// Every reachable free neuron is on (Fig. 2-18a, seed 001's first modification).
    FullActivation,
    /// The start neuron is on (§2.10 Б, Appendix A's `while E[start] < 1e-15`).
    PartialActivation {
        /// The robot's cell.
        start: Cell,
    },
    /// No neuron changes by `tolerance` or more in a sweep (eq. 1.3 when 0).
    Converged {
        /// Largest change that still counts as converged (absolute).
        tolerance: f64,
    },
    /// Exactly this many sweeps (partial correction runs `n` more sweeps).
    Sweeps(u32),
}

/// How a build ended.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// [`StopRule::FullActivation`] held.
    FullyActivated,
    /// [`StopRule::PartialActivation`] held.
    StartReached,
    /// [`StopRule::Converged`] held.
    Converged,
    /// [`StopRule::Sweeps`] ran its sweeps.
    SweepsDone,
    /// The start can never turn on: the wave stopped growing without reaching it.
    Unreachable,
    /// The sweep cap was hit first.
    SweepLimit,
}

/// What a build (or a continuation) did.
#[derive(Clone, Copy, PartialEq, Debug, Serialize, Deserialize)]
pub struct BuildReport {
    /// Sweeps that the returned map has had ("cycles" in the dissertation).
    pub sweeps: u32,
    /// Why the build stopped.
    pub outcome: Outcome,
    /// Neuron updates computed, including sweeps whose result was only a check (the full
    /// activation test needs one sweep past the last one that turned a neuron on).
    pub cells_updated: u64,
    /// Neurons above the on-threshold in the returned map (target included).
    pub cells_on: u64,
}

/// Every option of a neural map. [`Default`] is tanh, Appendix A's denominator, every
/// diagonal, no self weight and the wave-front threshold; see the presets for the published
/// variants.
#[derive(Clone, Copy, PartialEq, Debug, Default, Serialize, Deserialize)]
pub struct NeuralMapOptions {
    /// The activation function.
    pub activation: Activation,
    /// Which neighbours count in eq. 3.3's denominator.
    pub denominator: Denominator,
    /// Which diagonal links exist.
    pub diagonals: DiagonalRule,
    /// Link weights.
    pub weights: Weights,
    /// When a neuron counts as on.
    pub on_threshold: OnThreshold,
    /// Sweep cap; `None` means `max(width * height + 2, 100_000)`, which the activation stop
    /// rules with [`OnThreshold::NonZero`] can never hit.
    pub max_sweeps: Option<u32>,
}

impl NeuralMapOptions {
    /// The Fig. 2-16 / 2-18 reproduction: tanh, Appendix A's denominator (linked neighbours
    /// only), every diagonal, `1e-16`.
    pub fn dissertation() -> Self {
        NeuralMapOptions {
            on_threshold: OnThreshold::Above(1e-16),
            ..Self::default()
        }
    }

    /// Closest variant to Table 2-1 (run it with `StopRule::Sweeps(9)`).
    pub fn table_2_1() -> Self {
        NeuralMapOptions {
            denominator: Denominator::AllEight,
            on_threshold: OnThreshold::Above(1e-16),
            ..Self::default()
        }
    }

    /// Appendix A's code: linear, only linked neighbours averaged, threshold `1e-15`.
    pub fn appendix_a() -> Self {
        NeuralMapOptions {
            activation: Activation::Linear,
            on_threshold: OnThreshold::Above(1e-15),
            ..Self::default()
        }
    }

    /// Seed 001's proxy law: self weight 1, obstacles as zeros, off-grid absent.
    pub fn seed_001() -> Self {
        NeuralMapOptions {
            activation: Activation::Linear,
            denominator: Denominator::InGrid,
            weights: Weights {
                self_weight: 1.0,
                ..Weights::default()
            },
            ..Self::default()
        }
    }

    /// Rejects weights that are not positive and finite, and thresholds that are not.
    pub fn validate(&self) -> Result<(), Error> {
        self.weights.validate()?;
        if let OnThreshold::Above(t) = self.on_threshold {
            if !(t.is_finite() && (0.0..1.0).contains(&t)) {
                return Err(Error::option(
                    "on_threshold",
                    format!("{t} is not in [0, 1)"),
                ));
            }
        }
        if self.max_sweeps == Some(0) {
            return Err(Error::option("max_sweeps", "must be at least 1"));
        }
        Ok(())
    }

    /// The sweep cap for a grid of `cells` neurons.
    pub(crate) fn sweep_cap(&self, cells: usize) -> u32 {
        self.max_sweeps
            .unwrap_or_else(|| u32::try_from(cells + 2).unwrap_or(u32::MAX).max(100_000))
    }
}

pub(crate) fn validate_stop(stop: &StopRule) -> Result<(), Error> {
    if let StopRule::Converged { tolerance } = stop {
        if !(tolerance.is_finite() && *tolerance >= 0.0) {
            return Err(Error::option(
                "tolerance",
                format!("{tolerance} is not >= 0"),
            ));
        }
    }
    Ok(())
}

/// A cell's 3x3 neighbourhood of activations in a common scale.
///
/// `values[d]` is the neighbour in direction `d` ([`Direction::index`]) and `values[8]` the
/// centre; the true activation is `values[k] * 2^log2_scale`. Blocked and off-grid neighbours
/// are 0. One positive factor for all nine values keeps every comparison and every sign of
/// `(E_j - E_i) * w_ij` exact, which is all the path constructor needs.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Local {
    /// The eight neighbours clockwise from north, then the centre.
    pub values: [f64; 9],
    /// Power of two the values are scaled by.
    pub log2_scale: i64,
}

impl Local {
    /// The value of the neighbour in direction `d`.
    pub fn neighbour(&self, d: Direction) -> f64 {
        self.values[d.index()]
    }

    /// The centre's value.
    pub fn centre(&self) -> f64 {
        self.values[8]
    }
}

/// Read access to a built map: what the path constructor needs.
pub trait ActivationField {
    /// Grid width.
    fn width(&self) -> u32;
    /// Grid height.
    fn height(&self) -> u32;
    /// Whether a cell is an obstacle (including ones added by repair) or outside the grid.
    fn is_blocked(&self, cell: Cell) -> bool;
    /// The diagonal rule the map propagated with.
    fn diagonal_rule(&self) -> DiagonalRule;
    /// The map's target, if it has been built.
    fn target(&self) -> Option<Cell>;
    /// The 3x3 neighbourhood of an inside cell in a common scale (all zeros outside).
    fn local(&self, cell: Cell) -> Local;
    /// `log2` of a cell's activation, `-inf` when it is 0 (never underflows).
    fn log2_value(&self, cell: Cell) -> f64;
    /// A cell's activation as `f64` (0 when it is below `f64`'s range).
    fn value(&self, cell: Cell) -> f64 {
        self.log2_value(cell).exp2()
    }
    /// Whether a cell's activation is positive.
    fn is_on(&self, cell: Cell) -> bool {
        self.log2_value(cell) > f64::NEG_INFINITY
    }
}

/// A map that can be (re)built, continued and repaired: [`NeuralMap`] and [`ReferenceMap`].
pub trait NeuralDynamics: ActivationField {
    /// Resets to the initial state (target 1, everything else 0) and sweeps until `stop`.
    fn build(&mut self, target: Cell, stop: StopRule) -> Result<BuildReport, Error>;
    /// Sweeps on from the current state until `stop` (the target must have been built).
    fn continue_sweeps(&mut self, stop: StopRule) -> Result<BuildReport, Error>;
    /// Turns cells into obstacles: their neurons are zeroed and their links removed. Cells
    /// already blocked are ignored; the target cannot be blocked.
    fn add_obstacles(&mut self, cells: &[Cell]) -> Result<(), Error>;
}
