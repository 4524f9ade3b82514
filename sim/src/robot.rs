//! The robot model: validated geometry and drive limits, and the motor (first-order lag,
//! acceleration and speed limits, braking).

use crate::error::SimError;
use hnav_runtime::scenario::params::{RobotParams, SimParams};

/// Validated robot and step parameters, with per-step constants precomputed.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotModel {
    /// Wheel radius, m.
    pub wheel_radius_m: f64,
    /// Track width, m.
    pub axle_track_m: f64,
    /// Body radius, m.
    pub body_radius_m: f64,
    /// Wheel speed limit, rad/s.
    pub max_wheel_speed: f64,
    /// Wheel acceleration limit, rad/s².
    pub max_wheel_accel: f64,
    /// Motor time constant, s (0 = ideal).
    pub motor_lag_s: f64,
    /// Hall ticks per wheel revolution.
    pub ticks_per_rev: f64,
    /// Grid cell edge, m.
    pub cell_size_m: f64,
    /// Physics step, s.
    pub dt: f64,
    /// Largest speed change in one step, rad/s.
    pub(crate) max_dw: f64,
    /// `exp(-dt / lag)`, 0 for an ideal motor.
    pub(crate) decay: f64,
}

fn positive(name: &'static str, v: f64) -> Result<f64, SimError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(SimError::BadParam {
            name,
            value: v,
            why: "must be finite and > 0",
        })
    }
}

impl RobotModel {
    /// Validates the scenario's robot parameters for a step of `sim.step_ms`.
    pub fn new(robot: &RobotParams, sim: &SimParams) -> Result<RobotModel, SimError> {
        let dt = positive("sim.step_ms", f64::from(sim.step_ms))? * 1e-3;
        let lag = robot.motor_lag_s;
        if !(lag.is_finite() && lag >= 0.0) {
            return Err(SimError::BadParam {
                name: "robot.motor_lag_s",
                value: lag,
                why: "must be finite and >= 0",
            });
        }
        let body = positive("robot.body_radius_m", robot.body_radius_m)?;
        let cell = positive("robot.cell_size_m", robot.cell_size_m)?;
        if 2.0 * body > cell {
            return Err(SimError::BadParam {
                name: "robot.cell_size_m",
                value: cell,
                why: "a cell must be at least the robot's footprint (2 * body_radius_m)",
            });
        }
        let accel = positive("robot.max_wheel_accel_rad_s2", robot.max_wheel_accel_rad_s2)?;
        let ticks = positive("robot.ticks_per_rev", robot.ticks_per_rev)?;
        if !(sim.slip_std.is_finite() && sim.slip_std >= 0.0 && sim.slip_std < 0.5) {
            return Err(SimError::BadParam {
                name: "sim.slip_std",
                value: sim.slip_std,
                why: "must be in [0, 0.5)",
            });
        }
        Ok(RobotModel {
            wheel_radius_m: positive("robot.wheel_radius_m", robot.wheel_radius_m)?,
            axle_track_m: positive("robot.axle_track_m", robot.axle_track_m)?,
            body_radius_m: body,
            max_wheel_speed: positive("robot.max_wheel_speed_rad_s", robot.max_wheel_speed_rad_s)?,
            max_wheel_accel: accel,
            motor_lag_s: lag,
            ticks_per_rev: ticks,
            cell_size_m: cell,
            dt,
            max_dw: accel * dt,
            decay: if lag > 0.0 { (-dt / lag).exp() } else { 0.0 },
        })
    }

    /// Ground travel of one Hall tick, m.
    pub fn tick_arc_m(&self) -> f64 {
        std::f64::consts::TAU * self.wheel_radius_m / self.ticks_per_rev
    }

    /// One step of one motor: the wheel speed after `dt` from `w` towards `target`.
    /// `target` is clamped to the speed limit; the first-order lag is integrated exactly and
    /// the change is then clamped to the acceleration limit.
    #[inline]
    pub fn motor_step(&self, w: f64, target: f64) -> f64 {
        let target = target.clamp(-self.max_wheel_speed, self.max_wheel_speed);
        let lagged = target + (w - target) * self.decay;
        w + (lagged - w).clamp(-self.max_dw, self.max_dw)
    }

    /// One step of a braking motor: decelerate to standstill at the acceleration limit, as a
    /// driver short-circuiting the windings does (no lag, no overshoot).
    #[inline]
    pub fn brake_step(&self, w: f64) -> f64 {
        w - w.clamp(-self.max_dw, self.max_dw)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_parameters_without_panicking() {
        let sim = SimParams::default();
        for f in [
            |r: &mut RobotParams| r.wheel_radius_m = 0.0,
            |r: &mut RobotParams| r.axle_track_m = f64::NAN,
            |r: &mut RobotParams| r.motor_lag_s = -1.0,
            |r: &mut RobotParams| r.body_radius_m = 0.6 * r.cell_size_m,
            |r: &mut RobotParams| r.ticks_per_rev = f64::INFINITY,
        ] {
            let mut r = RobotParams::default();
            f(&mut r);
            assert!(matches!(
                RobotModel::new(&r, &sim),
                Err(SimError::BadParam { .. })
            ));
        }
        let bad_step = SimParams {
            step_ms: 0,
            ..SimParams::default()
        };
        assert!(RobotModel::new(&RobotParams::default(), &bad_step).is_err());
    }

    #[test]
    fn motor_respects_limits_and_lag() {
        let m = RobotModel::new(&RobotParams::default(), &SimParams::default()).unwrap();
        // Acceleration limit: 200 rad/s² * 1 ms = 0.2 rad/s per step.
        let w = m.motor_step(0.0, 100.0);
        assert!((w - 0.2).abs() < 1e-12);
        // Speed limit and lag: converges to the clamped target, never above it.
        let mut w = 0.0;
        for _ in 0..2000 {
            w = m.motor_step(w, 100.0);
            assert!(w <= m.max_wheel_speed + 1e-12);
        }
        assert!((w - m.max_wheel_speed).abs() < 1e-9);
        // Braking stops without overshoot.
        for _ in 0..200 {
            w = m.brake_step(w);
        }
        assert_eq!(w, 0.0);
    }
}
