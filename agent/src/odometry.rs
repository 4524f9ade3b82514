//! Dead reckoning from Hall-sensor ticks (reference §D.2): the agent's pose estimate, a pure
//! function of the cumulative tick stream and the robot parameters.
//!
//! Each reading's tick increments become wheel arcs `Δs = 2π·r·Δn/N`; the centre moves
//! `Δs = (Δs_R + Δs_L)/2` while turning `Δθ = (Δs_R − Δs_L)/b`, integrated with the exact-arc
//! update (midpoint when `|Δθ| ≤ 1e-6`).
//!
//! Ticks alone drift without bound: the heading is known only to within a tick pair
//! (`2πr/N/b`, 1.8° for the default robot), so the position error is a random walk of the
//! distance driven (in `scenarios/replicas-lifelong.toml` without fixes it passed the 22 mm
//! between a robot at a cell's centre and the cell's edge after 2 260 s). [`Relocaliser`]
//! bounds it with the sim's localisation fixes.

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

/// When the estimate takes a localisation fix: only when it differs from the fix by more
/// than the gate, in position (m) or heading (rad). A smaller difference is the fix's own
/// noise (or, in heading, the tick pair's quantum that dead reckoning never exceeds without
/// slip) rather than drift: taking it would make a good estimate worse and move the target
/// the wheel controller steers to (see [`hnav_runtime::scenario::localisation::GATE_SIGMAS`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Relocaliser {
    /// Largest position difference kept, m.
    pub gate_m: f64,
    /// Largest heading difference kept, rad.
    pub gate_rad: f64,
}

impl Relocaliser {
    /// The gate of the scenario's `[localisation]` section for a robot with `odo`'s wheels:
    /// the fix's noise gate, and in heading also the tick pair's quantum.
    pub fn new(params: &hnav_runtime::scenario::LocalisationParams, odo: &OdometryParams) -> Self {
        let (gate_m, gate_rad) = params.gate();
        Relocaliser {
            gate_m,
            gate_rad: gate_rad + odo.tick_arc_m() / odo.axle_track_m,
        }
    }

    /// Moves `dr`'s pose to `fix` if they differ by more than the gate, and says whether it
    /// did. A fix with a non-finite coordinate is ignored.
    pub fn apply(&self, dr: &mut DeadReckoning, fix: Pose) -> bool {
        if !(fix.x_m.is_finite() && fix.y_m.is_finite() && fix.theta_rad.is_finite()) {
            return false;
        }
        let p = dr.pose;
        let off = (fix.x_m - p.x_m).hypot(fix.y_m - p.y_m);
        let turned = wrap_angle(fix.theta_rad - p.theta_rad).abs();
        if off <= self.gate_m && turned <= self.gate_rad {
            return false;
        }
        dr.pose = Pose {
            theta_rad: wrap_angle(fix.theta_rad),
            ..fix
        };
        true
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
    fn a_fix_is_taken_only_beyond_the_gate() {
        let r = Relocaliser {
            gate_m: 0.01,
            gate_rad: 0.1,
        };
        let mut e = DeadReckoning::new(params(), Pose::default());
        let near = Pose {
            x_m: 0.006,
            y_m: -0.006,
            theta_rad: 0.05,
        };
        assert!(!r.apply(&mut e, near));
        assert_eq!(e.pose(), Pose::default());
        let nan = Pose {
            x_m: f64::NAN,
            ..near
        };
        assert!(!r.apply(&mut e, nan));
        let turned = Pose {
            theta_rad: -0.2,
            ..Pose::default()
        };
        assert!(r.apply(&mut e, turned));
        assert_eq!(e.pose(), turned);
        let far = Pose {
            x_m: 0.011,
            ..turned
        };
        assert!(r.apply(&mut e, far));
        // Dead reckoning goes on from the fix.
        let ahead = e.update(10, 10);
        assert!(ahead.x_m > far.x_m && ahead.theta_rad == far.theta_rad);
    }

    #[test]
    fn unchanged_counts_keep_the_pose_and_baseline_is_respected() {
        let p = params();
        let mut e = DeadReckoning::with_baseline(p, Pose::default(), (100, 100));
        assert_eq!(e.update(100, 100), Pose::default());
        assert!(e.update(110, 110).x_m > 0.0);
    }
}
