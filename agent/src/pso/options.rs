//! The swarm's options: the paper's parameters (§2.6 of the notes) and one explicit option for
//! every choice the notes mark \[A\] (the paper leaves it open), each defaulting to the notes'
//! recommendation except one: [`CornerRule`] defaults to a virtual obstacle at every detected
//! minimum, because that rule reproduces the paper's own success rates (89.3 % -> 96 %; ours
//! 96.7 %) where the notes' corner analysis does not (72.3 %; `docs/experiments/pso.md`).
//! [`PsoOptions::original`] and [`PsoOptions::modified`] are the two
//! algorithms of Tables 1 and 2; the modified algorithm's changes are separate options
//! ([`Variant`] for the blocked-move noise, [`WeightLaw`], [`Escape`]) so that each one can be
//! switched off alone (the `pso` experiment's ablation).

use crate::error::Error;

/// Which of the paper's two algorithms runs: its noise on a blocked move. The velocity law and
/// the local-minimum handling are [`WeightLaw`] and [`Escape`], which
/// [`PsoOptions::original`] and [`PsoOptions::modified`] set to each algorithm's.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Variant {
    /// Table 1: noise (20) of amplitude `r_max` ([`NoiseForm`], [`NoiseWhen`]); `original()`
    /// adds [`WeightLaw::Fixed`], [`Escape::Off`] and [`Alternative::Sum`].
    Original,
    /// Table 2: noise -1, 0 or +1 with equal probability, on blocked moves; `modified()` adds
    /// [`WeightLaw::Adaptive`], [`Escape::VirtualObstacles`] and [`Alternative::Noise`].
    Modified,
}

/// The velocity law, i.e. how the local and global weights are set.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum WeightLaw {
    /// Velocity (2) with fixed k1 = `k_initial`, k2 = 1 - `k_initial` and the complementary
    /// random factors (5), r2 = 1 - r1: the original algorithm's.
    Fixed,
    /// Velocity (9) with the adaptive tanh weights (10)-(19): the modified algorithm's.
    Adaptive,
}

/// What the swarm does about local minima (Pseudocode 2).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Escape {
    /// Nothing, not even the detector: the original algorithm.
    Off,
    /// The detector runs and its detections are counted, but nothing is placed: the swarm
    /// moves exactly as with [`Escape::Off`] (the ablation's "no virtual obstacles").
    DetectOnly,
    /// Detection, the [`CornerRule`] and virtual obstacles: the modified algorithm.
    VirtualObstacles,
}

/// How a real-valued velocity becomes a whole number of cells before the clamp (3). \[A\]
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Rounding {
    /// Nearest integer, halves away from zero (the notes' recommendation).
    Nearest,
    /// Toward zero.
    Truncate,
}

/// The distribution of the original algorithm's noise, eq. (20). \[A\]
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum NoiseForm {
    /// `round(-r_max + 2 r_max rand)`: the symmetric reading of the OCR (recommended); not
    /// uniform: for `r_max = 1`, P(-1) = P(1) = 1/4 and P(0) = 1/2.
    Symmetric,
    /// A uniform integer in `[-r_max, r_max]`.
    Uniform,
}

/// When the original algorithm adds its noise (20) to the move (8). \[A\]
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum NoiseWhen {
    /// Only when the intended cell is blocked: the paper's rule for the discrete grid (§2.3,
    /// "zero when moving through free space"), which both tables ran on (default).
    OnBlocked,
    /// On every move, as eq. (8) reads when taken alone.
    Always,
}

/// The cell tried when the intended cell `x + v` is blocked. \[A\]
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Alternative {
    /// `x + r`: stays in the 8-neighbourhood for `r` in {-1, 0, 1} (the modified default).
    Noise,
    /// `x + v + r` clamped to one cell per coordinate.
    ClampedSum,
    /// `x + v + r` as printed (the original default): jumps of more than one cell, which is
    /// what makes the gaps of Fig. 1 at `r_max > 1`.
    Sum,
}

/// Which particles Pseudocode 2 step 2.2 displaces after a virtual obstacle is placed. \[A\]
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Relocate {
    /// Particles on the minimum's cell (which the obstacle now occupies) or next to it
    /// (Chebyshev 1): the notes' suggested reading (default).
    Near,
    /// Only the particles on the minimum's cell.
    OnCell,
}

/// How a personal best that lies on a new virtual obstacle is replaced (steps 2.3-2.4). \[A\]
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum BestReset {
    /// The particle's current position (default: lets the swarm forget the trap).
    Current,
    /// The best cell the particle has visited that is not blocked now.
    BestVisited,
}

/// The 24-cell (5 x 5 minus centre) analysis that gates the virtual obstacle (§3.5). \[A\]
///
/// The paper does not give its corner-detection rule. The default follows the paper's numbers
/// rather than the notes' inference: only [`CornerRule::Always`] reproduces the modified
/// algorithm's success rate (96.7 % pooled against the paper's 96 %), while the notes'
/// [`CornerRule::Sides`] gives 72.3 %, below the original's 81.3 % (the `pso` experiment,
/// seed 1, 100 runs a setting).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum CornerRule {
    /// Pseudocode 2 alone ("Variant 1"): place the obstacle on every detection (default).
    Always,
    /// The notes' suggested rule (an option): place only when blocked cells lie on two
    /// perpendicular sides, or on three sides, of the window (a corner or a dead end). It
    /// refuses a straight wall, the typical trap of the paper's maps, so the swarm stays
    /// trapped more often (72.3 % success against the default's 96.7 %).
    Sides,
}

/// Which cells get virtual obstacles once the rule has accepted a minimum. \[A\]
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Footprint {
    /// The minimum's cell alone (Fig. 3 circles one cell; default).
    Single,
    /// The minimum's cell and the free cells of its 3 x 3 block that lie toward a blocked
    /// side of the window ("virtual obstacles are added to the local-minimum area").
    TowardCorner,
}

/// How a run decides that the swarm's trace is broken (a "gap" makes a success a failure).
/// \[A\]: the paper's Fig. 1 gaps are jumps, its conclusions speak of a trace graph falling
/// into disconnected subgraphs.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum GapRule {
    /// The start and the goal are not connected through the cells the swarm visited (8-
    /// neighbours, under the planner's corner rule): the robot could not follow the trace
    /// (default; the one the route planner needs).
    Graph,
    /// The arriving particle's own trajectory has a step of more than one cell per
    /// coordinate, or steps through an obstacle (the notes' §6.1 item 9).
    Steps,
}

/// Everything the swarm runs with. Distances are in cells.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct PsoOptions {
    /// The algorithm's blocked-move noise.
    pub variant: Variant,
    /// See [`WeightLaw`].
    pub weight_law: WeightLaw,
    /// See [`Escape`].
    pub escape: Escape,
    /// Swarm size N (9): the start cell and its 8 neighbours, then the start again.
    pub particles: usize,
    /// Inertia w (1.0).
    pub inertia: f64,
    /// Initial k^L = k^G (0.5); the original keeps them fixed.
    pub k_initial: f64,
    /// v_max (1): per-coordinate speed limit.
    pub v_max: i32,
    /// r_max of eq. (20) (original only; the modified draws from {-1, 0, 1}).
    pub r_max: i32,
    /// Local-minimum threshold n_lm (5).
    pub n_lm: u32,
    /// k_max (1200).
    pub k_max: u32,
    /// ε \[A\]: success when a particle's J is below it (0.5: the goal cell itself).
    pub epsilon: f64,
    /// η_min \[A\] (0.5 per cell): the paper gives no value.
    pub eta_min: f64,
    /// η_max \[A\] (2.0 per cell).
    pub eta_max: f64,
    /// Chebyshev sensing radius of a particle \[A\] (2, the least the 24-cell analysis needs).
    pub sensing_radius: u32,
    /// See [`Rounding`].
    pub rounding: Rounding,
    /// See [`NoiseForm`].
    pub noise_form: NoiseForm,
    /// See [`NoiseWhen`].
    pub noise_when: NoiseWhen,
    /// See [`Alternative`].
    pub alternative: Alternative,
    /// See [`Relocate`].
    pub relocate: Relocate,
    /// See [`BestReset`].
    pub best_reset: BestReset,
    /// See [`CornerRule`].
    pub corner_rule: CornerRule,
    /// See [`Footprint`].
    pub footprint: Footprint,
    /// See [`GapRule`].
    pub gap_rule: GapRule,
}

impl PsoOptions {
    /// The original algorithm of Table 1 at noise amplitude `r_max`.
    pub fn original(r_max: i32) -> PsoOptions {
        PsoOptions {
            variant: Variant::Original,
            weight_law: WeightLaw::Fixed,
            escape: Escape::Off,
            r_max,
            alternative: Alternative::Sum,
            ..PsoOptions::modified(5)
        }
    }

    /// The modified algorithm of Table 2 at threshold `n_lm`.
    pub fn modified(n_lm: u32) -> PsoOptions {
        PsoOptions {
            variant: Variant::Modified,
            weight_law: WeightLaw::Adaptive,
            escape: Escape::VirtualObstacles,
            particles: 9,
            inertia: 1.0,
            k_initial: 0.5,
            v_max: 1,
            r_max: 1,
            n_lm,
            k_max: 1200,
            epsilon: 0.5,
            eta_min: 0.5,
            eta_max: 2.0,
            sensing_radius: 2,
            rounding: Rounding::Nearest,
            noise_form: NoiseForm::Symmetric,
            noise_when: NoiseWhen::OnBlocked,
            alternative: Alternative::Noise,
            relocate: Relocate::Near,
            best_reset: BestReset::Current,
            corner_rule: CornerRule::Always,
            footprint: Footprint::Single,
            gap_rule: GapRule::Graph,
        }
    }

    /// The noise amplitude a move uses: `r_max` for the original, 1 for the modified.
    pub fn noise_amplitude(&self) -> i32 {
        match self.variant {
            Variant::Original => self.r_max,
            Variant::Modified => 1,
        }
    }

    /// Checks every option's domain.
    pub fn validate(&self) -> Result<(), Error> {
        let finite = |name, v: f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(Error::option(name, format!("{v} is not finite")))
            }
        };
        finite("inertia", self.inertia)?;
        finite("epsilon", self.epsilon)?;
        if !(1..=64).contains(&self.particles) {
            return Err(Error::option("particles", "must be 1..=64"));
        }
        if !(0.0..=1.0).contains(&self.k_initial) {
            return Err(Error::option("k_initial", "must lie in [0, 1]"));
        }
        if !(1..=16).contains(&self.v_max) || !(0..=16).contains(&self.r_max) {
            return Err(Error::option("v_max/r_max", "v_max 1..=16, r_max 0..=16"));
        }
        if self.k_max == 0 || self.epsilon <= 0.0 {
            return Err(Error::option("k_max/epsilon", "both must be positive"));
        }
        if !(self.eta_min > 0.0 && self.eta_max >= self.eta_min && self.eta_max.is_finite()) {
            return Err(Error::option(
                "eta_min/eta_max",
                "need 0 < eta_min <= eta_max",
            ));
        }
        if self.sensing_radius < 2 {
            return Err(Error::option(
                "sensing_radius",
                "the 24-cell analysis needs a radius of at least 2",
            ));
        }
        Ok(())
    }
}

impl Default for PsoOptions {
    /// The modified algorithm at the paper's default n_lm = 5.
    fn default() -> Self {
        PsoOptions::modified(5)
    }
}
