//! The emulated map-based localiser: now and then, a robot's ground-truth pose with seeded
//! Gaussian noise, carried by its odometry reading ([`Odometry::fix`]).
//!
//! Dead reckoning from Hall ticks drifts without bound (a heading known only to a tick pair
//! makes the position error a random walk of the distance driven); a real robot bounds it by
//! localising against the known map. The noise of fix `period` of robot `i` is a pure function
//! of the run's seed, `i` and `period` (a ChaCha stream apart from the slip noise's, sought to
//! the period), so a lockstep run repeats itself, a restarted sim publishes the same fix again,
//! and neither the slip noise nor the checkpoint depends on it.
//!
//! [`Odometry::fix`]: hnav_runtime::msg::Odometry::fix

use hnav_runtime::grid::geometry::wrap_angle;
use hnav_runtime::msg::Pose;
use hnav_runtime::scenario::LocalisationParams;

use crate::hall::SlipNoise;

/// Set apart from the run's seed so the fixes' stream is not the slip noise's.
const FIX_STREAM_SALT: u64 = 0x4c4f_4341_4c49_5345; // "LOCALISE"

/// ChaCha words one fix draws: two pairs of normals, two 64-bit draws each.
const WORDS_PER_FIX: u128 = 8;

/// When fixes are due and how noisy they are.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Localiser {
    params: LocalisationParams,
    odometry_hz: u32,
    seed: u64,
}

impl Localiser {
    /// Fixes of a run seeded with `seed` whose odometry comes at `odometry_hz`.
    pub fn new(params: LocalisationParams, odometry_hz: u32, seed: u64) -> Localiser {
        Localiser {
            params,
            odometry_hz,
            seed,
        }
    }

    /// Robot `robot`'s fix for the reading of control period `period`, if one is due then:
    /// `truth` with noise of `std_m` on x and y and `std_deg` on the heading.
    pub fn fix(&self, robot: u32, period: u64, truth: Pose) -> Option<Pose> {
        if !self.params.fix_due(self.odometry_hz, period) {
            return None;
        }
        let mut n = SlipNoise::new(self.seed ^ FIX_STREAM_SALT, u64::from(robot), 1.0);
        n.set_word_pos(u128::from(period) * WORDS_PER_FIX);
        let (nx, ny) = n.draw();
        let (nth, _) = n.draw();
        let p = &self.params;
        Some(Pose {
            x_m: truth.x_m + nx * p.std_m,
            y_m: truth.y_m + ny * p.std_m,
            theta_rad: wrap_angle(truth.theta_rad + nth * p.std_deg.to_radians()),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixes_are_due_at_the_rate_seeded_and_as_noisy_as_asked() {
        let params = LocalisationParams {
            rate_hz: 10.0,
            std_m: 0.002,
            std_deg: 0.5,
        };
        let l = Localiser::new(params, 100, 7);
        let truth = Pose {
            x_m: 1.0,
            y_m: 2.0,
            theta_rad: 0.5,
        };
        assert_eq!(l.fix(0, 0, truth), None);
        let a = l.fix(0, 9, truth).unwrap();
        assert_eq!(Some(a), l.fix(0, 9, truth), "a fix repeats");
        assert_ne!(Some(a), l.fix(1, 9, truth), "robots differ");
        assert_ne!(Some(a), Localiser::new(params, 100, 8).fix(0, 9, truth));
        let n = 20_000u64;
        let (mut sx, mut sx2, mut sth2) = (0.0, 0.0, 0.0);
        for k in 0..n {
            let f = l.fix(3, 10 * k + 9, truth).unwrap();
            let (dx, dth) = (f.x_m - truth.x_m, f.theta_rad - truth.theta_rad);
            sx += dx;
            sx2 += dx * dx;
            sth2 += dth * dth;
        }
        let mean = sx / n as f64;
        let std = (sx2 / n as f64 - mean * mean).sqrt();
        let std_deg = (sth2 / n as f64).sqrt().to_degrees();
        assert!(
            mean.abs() < 1e-4 && (std - 0.002).abs() < 1e-4,
            "{mean} {std}"
        );
        assert!((std_deg - 0.5).abs() < 0.02, "{std_deg}");
        let off = Localiser::new(
            LocalisationParams {
                rate_hz: 0.0,
                ..params
            },
            100,
            7,
        );
        assert!((0..1000).all(|p| off.fix(0, p, truth).is_none()));
    }
}
