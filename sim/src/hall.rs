//! Hall-sensor odometry: quantisation of wheel angle to signed cumulative ticks, and the
//! seeded wheel-slip noise that makes ground travel differ from what the ticks say.

use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Signed cumulative ticks of a wheel that has turned `angle_rad` since the start.
/// `floor` (not truncation) so that a wheel rocking around its start counts consistently.
#[inline]
pub fn ticks(angle_rad: f64, ticks_per_rev: f64) -> i64 {
    (angle_rad * ticks_per_rev / std::f64::consts::TAU).floor() as i64
}

/// Per-robot slip noise: relative slip factors `N(0, std)` per wheel, from a ChaCha stream
/// keyed by the run seed and the robot index (so a robot's noise does not depend on how many
/// other robots exist).
#[derive(Debug, Clone)]
pub struct SlipNoise {
    rng: ChaCha8Rng,
    std: f64,
}

impl SlipNoise {
    /// Noise of robot `robot` in a run seeded with `seed`.
    pub fn new(seed: u64, robot: u64, std: f64) -> SlipNoise {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(robot);
        SlipNoise { rng, std }
    }

    /// How far into its stream the generator is (in 32-bit words), for a checkpoint.
    pub fn word_pos(&self) -> u128 {
        self.rng.get_word_pos()
    }

    /// Moves the generator to `pos` of its stream ([`SlipNoise::word_pos`]).
    pub fn set_word_pos(&mut self, pos: u128) {
        self.rng.set_word_pos(pos);
    }

    /// The next pair of slip factors `(left, right)`; ground travel is wheel travel times
    /// `1 + factor`. Zero when the standard deviation is zero.
    pub fn draw(&mut self) -> (f64, f64) {
        if self.std == 0.0 {
            return (0.0, 0.0);
        }
        let (a, b) = self.gaussian_pair();
        (a * self.std, b * self.std)
    }

    /// Two independent standard normals (Box-Muller; `rand_distr` is not a workspace dep).
    fn gaussian_pair(&mut self) -> (f64, f64) {
        // 53 random bits in (0, 1]: never 0, so the log is finite.
        let u1 = ((self.rng.next_u64() >> 11) + 1) as f64 / (1u64 << 53) as f64;
        let u2 = (self.rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
        (r * c, r * s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_quantise_with_floor() {
        let n = 42.0;
        let tick = std::f64::consts::TAU / n;
        assert_eq!(ticks(0.0, n), 0);
        assert_eq!(ticks(0.999 * tick, n), 0);
        assert_eq!(ticks(1.001 * tick, n), 1);
        assert_eq!(ticks(-0.001 * tick, n), -1);
        assert_eq!(ticks(std::f64::consts::TAU * 10.0 + 1e-9, n), 420);
    }

    #[test]
    fn slip_noise_is_seeded_and_has_the_given_std() {
        let mut a = SlipNoise::new(7, 3, 0.01);
        let mut b = SlipNoise::new(7, 3, 0.01);
        let mut c = SlipNoise::new(7, 4, 0.01);
        assert_eq!(a.draw(), b.draw());
        assert_ne!(a.draw(), c.draw());
        let n = 20000;
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let (l, r) = a.draw();
            s += l + r;
            s2 += l * l + r * r;
        }
        let mean = s / (2 * n) as f64;
        let std = (s2 / (2 * n) as f64 - mean * mean).sqrt();
        assert!(
            mean.abs() < 3e-4 && (std - 0.01).abs() < 3e-4,
            "{mean} {std}"
        );
        assert_eq!(SlipNoise::new(1, 0, 0.0).draw(), (0.0, 0.0));
    }
}
