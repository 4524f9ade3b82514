//! The wheel controller: drives the robot from its dead-reckoned pose to the centre of the
//! committed cell (`next`) and stops there.
//!
//! A grid step is a short straight segment, so the controller is the simplest one that keeps
//! the robot on it: turn in place while the heading error is large (a differential drive can,
//! and it keeps the robot inside its two reserved cells), then drive with a proportional
//! heading correction, slowing down in proportion to the remaining distance so it stops at
//! the centre without overshooting into the next cell. Speeds are capped by the agent's
//! nominal speed (cells/s) and by the motors' limit; the sim adds the acceleration limit and
//! the motor lag, which the slow-down leaves room for.

use hnav_runtime::grid::geometry::wrap_angle_shifted;
use hnav_runtime::msg::Pose;
use hnav_runtime::scenario::RobotParams;

/// Gains and limits of the controller.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct ControllerParams {
    /// Wheel radius in metres.
    pub wheel_radius_m: f64,
    /// Track width in metres.
    pub axle_track_m: f64,
    /// Largest wheel speed in rad/s.
    pub max_wheel_rad_s: f64,
    /// Largest forward speed in m/s (the agent's nominal speed).
    pub max_speed_m_s: f64,
    /// Distance to the target below which the robot counts as arrived, in metres.
    pub arrive_tolerance_m: f64,
    /// Heading error above which the robot turns in place, in radians.
    pub turn_in_place_rad: f64,
    /// Forward speed per metre of remaining distance, 1/s.
    pub distance_gain: f64,
    /// Turn rate per radian of heading error, 1/s.
    pub heading_gain: f64,
}

impl ControllerParams {
    /// The controller of a robot that travels `speed_cells_s` cells per second.
    pub fn new(robot: &RobotParams, speed_cells_s: f64) -> Self {
        let motor_limit = robot.max_wheel_speed_rad_s * robot.wheel_radius_m;
        ControllerParams {
            wheel_radius_m: robot.wheel_radius_m,
            axle_track_m: robot.axle_track_m,
            max_wheel_rad_s: robot.max_wheel_speed_rad_s,
            max_speed_m_s: (speed_cells_s * robot.cell_size_m).min(motor_limit),
            arrive_tolerance_m: 0.05 * robot.cell_size_m,
            turn_in_place_rad: 0.3,
            distance_gain: 3.0,
            heading_gain: 6.0,
        }
    }
}

/// One control decision.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct WheelSpeeds {
    /// Left wheel set-point in rad/s.
    pub left_rad_s: f64,
    /// Right wheel set-point in rad/s.
    pub right_rad_s: f64,
    /// Whether the robot is within the arrival tolerance (the set-points are then zero).
    pub arrived: bool,
}

/// Drives to a point.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct WheelController {
    params: ControllerParams,
}

impl WheelController {
    /// A controller with `params`.
    pub fn new(params: ControllerParams) -> Self {
        WheelController { params }
    }

    /// The parameters.
    pub fn params(&self) -> &ControllerParams {
        &self.params
    }

    /// Whether `pose` is within the arrival tolerance of `(x, y)`.
    pub fn arrived(&self, pose: Pose, x: f64, y: f64) -> bool {
        (x - pose.x_m).hypot(y - pose.y_m) <= self.params.arrive_tolerance_m
    }

    /// Wheel set-points that take the robot from `pose` towards `(x, y)` (metres).
    pub fn command(&self, pose: Pose, x: f64, y: f64) -> WheelSpeeds {
        let p = &self.params;
        let (dx, dy) = (x - pose.x_m, y - pose.y_m);
        let dist = dx.hypot(dy);
        if dist <= p.arrive_tolerance_m || !dist.is_finite() {
            return WheelSpeeds {
                left_rad_s: 0.0,
                right_rad_s: 0.0,
                arrived: dist <= p.arrive_tolerance_m,
            };
        }
        let err = wrap_angle_shifted(dy.atan2(dx) - pose.theta_rad);
        let omega = p.heading_gain * err;
        let v = if err.abs() > p.turn_in_place_rad {
            0.0
        } else {
            (p.distance_gain * dist).min(p.max_speed_m_s) * err.cos()
        };
        let half = 0.5 * p.axle_track_m;
        let (mut l, mut r) = (
            (v - omega * half) / p.wheel_radius_m,
            (v + omega * half) / p.wheel_radius_m,
        );
        // Scale both wheels together so the turn rate keeps its share of the motor limit.
        let peak = l.abs().max(r.abs());
        if peak > p.max_wheel_rad_s {
            let k = p.max_wheel_rad_s / peak;
            l *= k;
            r *= k;
        }
        WheelSpeeds {
            left_rad_s: l,
            right_rad_s: r,
            arrived: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::odometry::arc_update;

    fn controller() -> WheelController {
        WheelController::new(ControllerParams::new(&RobotParams::default(), 1.0))
    }

    /// Integrates the commanded wheel speeds directly (no motor dynamics) at 10 ms.
    fn drive(c: &WheelController, mut pose: Pose, x: f64, y: f64, periods: usize) -> Pose {
        let p = *c.params();
        for _ in 0..periods {
            let w = c.command(pose, x, y);
            if w.arrived {
                break;
            }
            let (sl, sr) = (
                w.left_rad_s * p.wheel_radius_m * 0.01,
                w.right_rad_s * p.wheel_radius_m * 0.01,
            );
            pose = arc_update(pose, 0.5 * (sl + sr), (sr - sl) / p.axle_track_m);
        }
        pose
    }

    #[test]
    fn reaches_every_neighbour_centre_from_any_heading() {
        let c = controller();
        let cs = RobotParams::default().cell_size_m;
        for h in 0..8 {
            let theta = f64::from(h) * std::f64::consts::FRAC_PI_4 - 3.0;
            for (dx, dy) in [
                (1, 0),
                (1, 1),
                (0, 1),
                (-1, 1),
                (-1, 0),
                (-1, -1),
                (0, -1),
                (1, -1),
            ] {
                let start = Pose {
                    x_m: 0.0,
                    y_m: 0.0,
                    theta_rad: theta,
                };
                let (x, y) = (f64::from(dx) * cs, f64::from(dy) * cs);
                let end = drive(&c, start, x, y, 2000);
                assert!(
                    c.arrived(end, x, y),
                    "heading {theta} to ({dx},{dy}): {end:?}"
                );
            }
        }
    }

    #[test]
    fn respects_the_wheel_limit_and_stops_at_the_target() {
        let c = controller();
        let p = *c.params();
        let pose = Pose {
            x_m: 0.0,
            y_m: 0.0,
            theta_rad: 2.0,
        };
        let w = c.command(pose, 10.0, 0.0);
        assert!(w.left_rad_s.abs() <= p.max_wheel_rad_s + 1e-12);
        assert!(w.right_rad_s.abs() <= p.max_wheel_rad_s + 1e-12);
        let stop = c.command(pose, 0.0, 0.001);
        assert!(stop.arrived && stop.left_rad_s == 0.0 && stop.right_rad_s == 0.0);
    }

    #[test]
    fn non_finite_targets_give_zero_speeds() {
        let c = controller();
        let w = c.command(Pose::default(), f64::NAN, 0.0);
        assert_eq!((w.left_rad_s, w.right_rad_s), (0.0, 0.0));
    }
}
