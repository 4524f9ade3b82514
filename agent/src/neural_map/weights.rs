//! Link weights (eq. 3.2): below the grid's topology, which sums them per cell, and the
//! dense matrix ([`super::matrix`]) built from both.

use hnav_runtime::grid::Direction;
use serde::{Deserialize, Serialize};

use crate::error::Error;

/// Link weights `w = K / d` (eq. 3.2) and seed 001's self-connection.
#[derive(Clone, Copy, PartialEq, Debug, Serialize, Deserialize)]
pub struct Weights {
    /// Straight (orthogonal) links, `d = 1`: 1.
    pub straight: f64,
    /// Diagonal links, `d = sqrt 2`: `1 / sqrt 2` (Table 2-2 rounds it to 0.7).
    pub diagonal: f64,
    /// The neuron's link to itself: 0 in the dissertation (eq. 3.2, stability rule), 1 in
    /// seed 001 (smoother decay, no "potential wells").
    pub self_weight: f64,
    /// The gain `K` multiplying every weight (Appendix A's `k = 1`; seed 001 varies it up to
    /// 5). It cancels in eq. 3.3's normalised average and in the path constructor's argmax.
    pub gain: f64,
}

impl Default for Weights {
    fn default() -> Self {
        Weights {
            straight: 1.0,
            diagonal: std::f64::consts::FRAC_1_SQRT_2,
            self_weight: 0.0,
            gain: 1.0,
        }
    }
}

impl Weights {
    /// Table 2-2's rounded weights: straight 1, diagonal 0.7, self 0.
    pub fn table_2_2() -> Self {
        Weights {
            diagonal: 0.7,
            ..Weights::default()
        }
    }

    /// The weight of a link in direction `d`, gain applied.
    pub fn link(&self, d: Direction) -> f64 {
        self.gain
            * if d.is_diagonal() {
                self.diagonal
            } else {
                self.straight
            }
    }

    /// Straight, diagonal and gain must be positive and finite, self weight `>= 0`.
    pub fn validate(&self) -> Result<(), Error> {
        let positive = |name: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::option(name, format!("{v} is not a positive number")))
            }
        };
        positive("weights.straight", self.straight)?;
        positive("weights.diagonal", self.diagonal)?;
        positive("weights.gain", self.gain)?;
        if !(self.self_weight.is_finite() && self.self_weight >= 0.0) {
            return Err(Error::option(
                "weights.self_weight",
                format!("{} is not >= 0", self.self_weight),
            ));
        }
        // The fast path sums terms relative to the largest one; weights further apart than
        // this would push the smallest terms towards f32's subnormal range.
        let lo = self.straight.min(self.diagonal);
        let hi = self.straight.max(self.diagonal).max(self.self_weight);
        if hi > 1e6 * lo {
            return Err(Error::option(
                "weights",
                "straight, diagonal and self weights must be within a factor 1e6 of each other",
            ));
        }
        Ok(())
    }
}
