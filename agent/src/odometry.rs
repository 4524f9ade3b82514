//! Dead reckoning from Hall-sensor ticks (reference §D.2): the agent's pose estimate, a pure
//! function of the cumulative tick stream and the robot parameters.
//!
//! Each reading's tick increments become wheel arcs `Δs = 2π·r·Δn/N`; the centre moves
//! `Δs = (Δs_R + Δs_L)/2` while turning `Δθ = (Δs_R − Δs_L)/b`, integrated with the exact-arc
//! update (midpoint when `|Δθ| ≤ 1e-6`).

use hnav_runtime::grid::geometry::wrap_angle;
use hnav_runtime::msg::Pose;
use hnav_runtime::scenario::params::RobotParams;

/// Below this heading change the arc radius is ill-conditioned; the midpoint update is used.
const EXACT_ARC_MIN_DTHETA: f64 = 1e-6;

/// The robot parameters the estimator needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdometryParams {
    /// Wheel radius, m.
    pub wheel_radius_m: f64,
    /// Track width, m.
    pub axle_track_m: f64,
    /// Hall ticks per wheel revolution.
    pub ticks_per_rev: f64,
}

impl From<&RobotParams> for OdometryParams {
    fn from(r: &RobotParams) -> Self {
        OdometryParams {
            wheel_radius_m: r.wheel_radius_m,
            axle_track_m: r.axle_track_m,
            ticks_per_rev: r.ticks_per_rev,
        }
    }
}

impl OdometryParams {
    /// Ground travel of one tick, m.
    pub fn tick_arc_m(&self) -> f64 {
        std::f64::consts::TAU * self.wheel_radius_m / self.ticks_per_rev
    }
}

/// A dead-reckoning estimator fed cumulative tick counts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeadReckoning {
    params: OdometryParams,
    pose: Pose,
    last: (i64, i64),
}

impl DeadReckoning {
    /// An estimator starting at `start`, with cumulative counts `(0, 0)` there (as the sim's
    /// counters start).
    pub fn new(params: OdometryParams, start: Pose) -> DeadReckoning {
        Self::with_baseline(params, start, (0, 0))
    }

    /// An estimator starting at `start` where the counters read `baseline` (e.g. after an
    /// agent restart).
    pub fn with_baseline(params: OdometryParams, start: Pose, baseline: (i64, i64)) -> Self {
        DeadReckoning {
            params,
            pose: start,
            last: baseline,
        }
    }

    /// Feeds the cumulative counts `(left, right)` of a new reading and returns the pose.
    /// Counters are signed 64-bit and never wrap in a run; a wrapping difference is used
    /// anyway so a corrupt reading cannot panic.
    pub fn update(&mut self, ticks_left: i64, ticks_right: i64) -> Pose {
        let dl = ticks_left.wrapping_sub(self.last.0);
        let dr = ticks_right.wrapping_sub(self.last.1);
        self.last = (ticks_left, ticks_right);
        if dl == 0 && dr == 0 {
            return self.pose;
        }
        let k = self.params.tick_arc_m();
        let (sl, sr) = (dl as f64 * k, dr as f64 * k);
        let ds = 0.5 * (sr + sl);
        let dth = (sr - sl) / self.params.axle_track_m;
        self.pose = arc_update(self.pose, ds, dth);
        self.pose
    }

    /// The current estimate.
    pub fn pose(&self) -> Pose {
        self.pose
    }
}

/// The exact-arc update of §D.2 (midpoint for tiny heading changes); `theta` is wrapped to
/// `(-π, π]`.
pub fn arc_update(p: Pose, ds: f64, dtheta: f64) -> Pose {
    let t2 = p.theta_rad + dtheta;
    let (x, y) = if dtheta.abs() > EXACT_ARC_MIN_DTHETA {
        let r = ds / dtheta;
        let (s1, c1) = p.theta_rad.sin_cos();
        let (s2, c2) = t2.sin_cos();
        (p.x_m + r * (s2 - s1), p.y_m - r * (c2 - c1))
    } else {
        let (s, c) = (p.theta_rad + 0.5 * dtheta).sin_cos();
        (p.x_m + ds * c, p.y_m + ds * s)
    };
    Pose {
        x_m: x,
        y_m: y,
        theta_rad: wrap_angle(t2),
    }
}

/// Dead reckoning over a whole stream of cumulative readings from `(0, 0)` at `start`.
pub fn integrate(
    params: OdometryParams,
    start: Pose,
    readings: impl IntoIterator<Item = (i64, i64)>,
) -> Pose {
    let mut e = DeadReckoning::new(params, start);
    for (l, r) in readings {
        e.update(l, r);
    }
    e.pose()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> OdometryParams {
        OdometryParams::from(&RobotParams::default())
    }

    #[test]
    fn straight_and_turn_in_place() {
        let p = params();
        let start = Pose::default();
        let end = integrate(p, start, [(10, 10), (42, 42)]);
        assert!((end.x_m - 42.0 * p.tick_arc_m()).abs() < 1e-12);
        assert!(end.y_m.abs() < 1e-12 && end.theta_rad == 0.0);
        let end = integrate(p, start, [(-5, 5)]);
        assert!(end.x_m.abs() < 1e-12 && end.y_m.abs() < 1e-12);
        let want = 10.0 * p.tick_arc_m() / p.axle_track_m;
        assert!((end.theta_rad - want).abs() < 1e-12);
    }

    #[test]
    fn unchanged_counts_keep_the_pose_and_baseline_is_respected() {
        let p = params();
        let mut e = DeadReckoning::with_baseline(p, Pose::default(), (100, 100));
        assert_eq!(e.update(100, 100), Pose::default());
        assert!(e.update(110, 110).x_m > 0.0);
    }
}
