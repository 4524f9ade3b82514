//! The motor energy model: what a wheel's motor draws from the battery while the sim's
//! wheel model drives it, and the energy of a planned path under the same model (the
//! dissertation's "energy intensity": energy spent beside the energy planned).
//!
//! Each wheel is a DC gear motor. The torque at the wheel is what accelerates the half of
//! the robot's mass the wheel carries and what overcomes rolling resistance:
//!
//! `τ = (m/2)·r²·α + C_rr·(m/2)·g·r·sign(ω)`
//!
//! (`α` the wheel's angular acceleration, `ω` its speed; the body's own rotational inertia
//! is left out, so turning in place costs what driving straight the same wheel travel
//! does). The current is `i = τ / k` (`k` the torque per ampere at the wheel, gear
//! included), and the electrical power `P = τ·ω + R·i²`: mechanical power and the
//! winding's copper loss. A motor that brakes (`P < 0`) feeds nothing back: the driver
//! does not regenerate, so the power drawn is `max(P, 0)`. The sim steps each wheel from
//! `ω0` to `ω1` over a step `dt` ([`WheelEnergy::step_j`]): `α = (ω1 − ω0)/dt` and `ω`
//! the mean of the two, the same trapezoid the sim integrates the wheel angle with.
//!
//! The constants ([`MotorModel::S_BOT`]) are the s-bot's mass (the robot the scenario's
//! `[robot]` defaults are sized for) and a small gear motor's: they are not scenario keys,
//! so a run's energy compares with another run's, not with a battery's label.

use crate::scenario::params::RobotParams;

/// Standard gravity, m/s².
pub const GRAVITY: f64 = 9.81;

/// The constants of the motor model (see the [module docs](self)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorModel {
    /// The robot's mass, kg; each wheel carries half.
    pub mass_kg: f64,
    /// Rolling resistance coefficient (rolling force over normal force).
    pub rolling_coefficient: f64,
    /// Winding resistance, Ω.
    pub winding_ohm: f64,
    /// Torque per ampere at the wheel (motor torque constant times gear ratio), N·m/A.
    pub torque_per_amp_nm: f64,
}

impl MotorModel {
    /// The model every run uses: an s-bot (660 g) on a hard floor (`C_rr` 0.03) with a
    /// 5 Ω gear motor giving 0.1 N·m per ampere at the wheel.
    pub const S_BOT: MotorModel = MotorModel {
        mass_kg: 0.66,
        rolling_coefficient: 0.03,
        winding_ohm: 5.0,
        torque_per_amp_nm: 0.1,
    };
}

/// [`MotorModel`] for one wheel of radius `r` and a step `dt`, with its per-step constants
/// worked out once: a step costs a few multiplications and no allocation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WheelEnergy {
    /// `(m/2)·r²`, kg·m².
    inertia: f64,
    /// `C_rr·(m/2)·g·r`, N·m.
    rolling_nm: f64,
    /// `R / k²`, W per (N·m)².
    copper: f64,
    dt: f64,
    inv_dt: f64,
}

impl WheelEnergy {
    /// The wheel of radius `wheel_radius_m` under `model`, stepped every `dt_s` seconds.
    pub fn new(model: &MotorModel, wheel_radius_m: f64, dt_s: f64) -> Self {
        let half = 0.5 * model.mass_kg;
        WheelEnergy {
            inertia: half * wheel_radius_m * wheel_radius_m,
            rolling_nm: model.rolling_coefficient * half * GRAVITY * wheel_radius_m,
            copper: model.winding_ohm / (model.torque_per_amp_nm * model.torque_per_amp_nm),
            dt: dt_s,
            inv_dt: if dt_s > 0.0 { 1.0 / dt_s } else { 0.0 },
        }
    }

    /// Energy in joules the motor draws while its wheel goes from `w0` to `w1` rad/s over
    /// one step.
    #[inline]
    pub fn step_j(&self, w0: f64, w1: f64) -> f64 {
        let w = 0.5 * (w0 + w1);
        let rolling = if w > 0.0 {
            self.rolling_nm
        } else if w < 0.0 {
            -self.rolling_nm
        } else {
            0.0
        };
        let tau = self.inertia * (w1 - w0) * self.inv_dt + rolling;
        (tau * w + self.copper * tau * tau).max(0.0) * self.dt
    }

    /// Energy in joules one wheel draws driving `length_m` of ground straight from rest to
    /// rest: up to `speed` rad/s at `accel` rad/s² (a triangle when the path is too short to
    /// reach it), cruise, and down again, each step priced by [`WheelEnergy::step_j`].
    pub fn straight_j(&self, radius_m: f64, length_m: f64, speed: f64, accel: f64) -> f64 {
        if !(length_m > 0.0 && speed > 0.0 && accel > 0.0 && radius_m > 0.0 && self.dt > 0.0) {
            return 0.0;
        }
        let dw = accel * self.dt;
        // Ramp up in whole steps until the speed, or until half the length is used.
        let (mut w, mut ramp_j, mut ramp_m) = (0.0f64, 0.0, 0.0);
        while w < speed && 2.0 * ramp_m < length_m {
            let next = (w + dw).min(speed);
            ramp_j += self.step_j(w, next);
            ramp_m += 0.5 * (w + next) * self.dt * radius_m;
            w = next;
        }
        // The ramp down mirrors the ramp up: the same torques with the sign of the inertial
        // part turned, so it is priced step by step as well.
        let mut down_j = 0.0;
        let mut v = w;
        while v > 0.0 {
            let next = (v - dw).max(0.0);
            down_j += self.step_j(v, next);
            v = next;
        }
        let cruise_m = (length_m - 2.0 * ramp_m).max(0.0);
        let cruise_s = cruise_m / (w * radius_m);
        let cruise_j = self.step_j(w, w) / self.dt * cruise_s;
        ramp_j + cruise_j + down_j
    }
}

/// The energy budget of a path of `length_cells` cells: both wheels of a robot of `robot`'s
/// geometry driving it straight from rest to rest at `speed_cells_s` (its nominal speed),
/// accelerating at the wheels' limit, under [`MotorModel::S_BOT`] with a `dt_s` step. Turns
/// and stops on the way are not priced: it is the least a robot can spend on that path.
pub fn path_budget_j(robot: &RobotParams, length_cells: f64, speed_cells_s: f64, dt_s: f64) -> f64 {
    let r = robot.wheel_radius_m;
    let wheel = WheelEnergy::new(&MotorModel::S_BOT, r, dt_s);
    let speed = (speed_cells_s * robot.cell_size_m / r).min(robot.max_wheel_speed_rad_s);
    2.0 * wheel.straight_j(
        r,
        length_cells * robot.cell_size_m,
        speed,
        robot.max_wheel_accel_rad_s2,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wheel() -> WheelEnergy {
        WheelEnergy::new(&MotorModel::S_BOT, 0.02, 1e-3)
    }

    #[test]
    fn a_standing_wheel_draws_nothing_and_a_cruising_one_pays_rolling_and_copper() {
        let w = wheel();
        assert_eq!(w.step_j(0.0, 0.0), 0.0);
        // 0.03 * 0.33 kg * 9.81 * 0.02 m = 1.9424e-3 N·m at 10 rad/s for 1 ms:
        // mechanical 1.9424e-2 W, copper 5 / 0.01 * tau² = 1.8864e-3 W.
        let tau = 0.03 * 0.33 * GRAVITY * 0.02;
        let p = tau * 10.0 + 500.0 * tau * tau;
        assert!((w.step_j(10.0, 10.0) - p * 1e-3).abs() < 1e-15);
        // Backwards costs the same.
        assert!((w.step_j(-10.0, -10.0) - w.step_j(10.0, 10.0)).abs() < 1e-18);
    }

    #[test]
    fn a_known_ramp_integrates_to_its_closed_form() {
        // 0 -> 20 rad/s at 200 rad/s² in 100 steps of 1 ms: τ = J·α + rolling, constant;
        // ∫τ·ω dt = τ · (mean speed 10 rad/s) · 0.1 s; copper 500 · τ² · 0.1 s.
        let w = wheel();
        let mut e = 0.0;
        for k in 0..100 {
            e += w.step_j(0.2 * f64::from(k), 0.2 * f64::from(k + 1));
        }
        let tau = 0.33 * 0.02 * 0.02 * 200.0 + 0.03 * 0.33 * GRAVITY * 0.02;
        let closed = tau * 10.0 * 0.1 + 500.0 * tau * tau * 0.1;
        assert!((e - closed).abs() < 1e-12, "{e} vs {closed}");
        // A brake that fights no rolling gets nothing back: never negative.
        assert!(w.step_j(20.0, 0.0) >= 0.0);
    }

    #[test]
    fn the_budget_grows_with_the_path_and_prices_a_straight_run_as_the_steps_do() {
        let robot = RobotParams::default();
        let short = path_budget_j(&robot, 1.0, 1.0, 1e-3);
        let long = path_budget_j(&robot, 10.0, 1.0, 1e-3);
        assert!(short > 0.0 && long > short, "{short} {long}");
        assert_eq!(path_budget_j(&robot, 0.0, 1.0, 1e-3), 0.0);
        // 10 cells of 16 cm at 1 cell/s: the cruise dominates, rolling power times 1.6 s
        // over 2 wheels is a lower bound.
        let r = robot.wheel_radius_m;
        let cruise = wheel_rolling_w(r, 0.16 / r) * 2.0 * 10.0;
        assert!(long > cruise * 0.95, "{long} vs {cruise}");
    }

    fn wheel_rolling_w(r: f64, w: f64) -> f64 {
        let tau = 0.03 * 0.33 * GRAVITY * r;
        tau * w + 500.0 * tau * tau
    }
}
