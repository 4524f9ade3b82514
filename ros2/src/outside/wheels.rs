//! A robot outside HNAV's motion as its agent reads motion: cumulative Hall ticks per wheel.
//!
//! From `joint_states` the two wheels' positions (rad, cumulative, as ros2_control's joint
//! state broadcaster publishes a `diff_drive_controller`'s wheels) become ticks at the
//! scenario's `ticks_per_rev`: the agent's dead reckoning then does what it does with the
//! sim's Hall ticks. From `odom` the motion between two messages becomes the wheel turns
//! that make it (the exact inverse of the arc model the agent integrates), because an odom
//! frame's origin is where the robot's driver started, not HNAV's map.

use std::f64::consts::TAU;

use crate::msgs::{JointState, Odometry};

/// Why a message of a robot outside HNAV was dropped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Malformed {
    /// `joint_states` without the wheel joints' positions.
    #[error("no position for joint {0:?} (names {1:?}, {2} positions)")]
    NoWheel(String, Vec<String>, usize),
    /// A position or pose that is not a finite number.
    #[error("a value that is not a finite number")]
    NotFinite,
}

/// The wheel joints' positions in a `joint_states`, (left, right), rad.
pub fn wheel_positions(js: &JointState, joints: &[String; 2]) -> Result<(f64, f64), Malformed> {
    let at = |name: &String| {
        let i = js.name.iter().position(|n| n == name);
        i.and_then(|i| js.position.get(i).copied())
            .ok_or_else(|| Malformed::NoWheel(name.clone(), js.name.clone(), js.position.len()))
    };
    let (l, r) = (at(&joints[0])?, at(&joints[1])?);
    if l.is_finite() && r.is_finite() {
        Ok((l, r))
    } else {
        Err(Malformed::NotFinite)
    }
}

/// A wheel angle as whole Hall ticks (rounded toward the nearest).
pub fn ticks(angle_rad: f64, ticks_per_rev: f64) -> i64 {
    (angle_rad / TAU * ticks_per_rev).round() as i64
}

/// Turns a robot's successive odometry poses into cumulative wheel angles.
#[derive(Debug, Clone, Copy, Default)]
pub struct OdomWheels {
    /// The last pose taken: x, y, yaw.
    last: Option<(f64, f64, f64)>,
    /// Cumulative wheel angles, rad.
    pub angles: (f64, f64),
}

impl OdomWheels {
    /// Takes `odom` in, for wheels of `radius_m` on an axle of `axle_m`; returns the
    /// cumulative (left, right) angles.
    pub fn take(
        &mut self,
        odom: &Odometry,
        radius_m: f64,
        axle_m: f64,
    ) -> Result<(f64, f64), Malformed> {
        let now = odom.planar().ok_or(Malformed::NotFinite)?;
        if let Some((x, y, th)) = self.last {
            let dth = wrap(now.2 - th);
            // The chord of an arc of turn dth is ds * sinc(dth / 2) long, along the mid
            // heading: invert it for the arc length ds (signed by the chord's direction).
            let (dx, dy) = (now.0 - x, now.1 - y);
            let mid = th + dth / 2.0;
            let along = dx * mid.cos() + dy * mid.sin();
            let half = dth / 2.0;
            let sinc = if half.abs() < 1e-9 {
                1.0
            } else {
                half.sin() / half
            };
            let ds = along / sinc;
            let half_turn = dth * axle_m / 2.0;
            self.angles.0 += (ds - half_turn) / radius_m;
            self.angles.1 += (ds + half_turn) / radius_m;
        }
        self.last = Some(now);
        Ok(self.angles)
    }
}

/// An angle in (-pi, pi].
fn wrap(a: f64) -> f64 {
    let w = a.rem_euclid(TAU);
    if w > std::f64::consts::PI {
        w - TAU
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msgs::Quaternion;

    fn names() -> [String; 2] {
        ["left_wheel_joint".into(), "right_wheel_joint".into()]
    }

    #[test]
    fn joint_positions_by_name_in_any_order() {
        let js = JointState {
            name: vec![
                "caster".into(),
                "right_wheel_joint".into(),
                "left_wheel_joint".into(),
            ],
            position: vec![9.0, 2.0, 1.0],
            ..JointState::default()
        };
        assert_eq!(wheel_positions(&js, &names()), Ok((1.0, 2.0)));
        let short = JointState {
            position: vec![9.0, 2.0],
            ..js.clone()
        };
        assert!(matches!(
            wheel_positions(&short, &names()),
            Err(Malformed::NoWheel(n, _, 2)) if n == "left_wheel_joint"
        ));
        let nan = JointState {
            position: vec![9.0, f64::NAN, 1.0],
            ..js
        };
        assert_eq!(wheel_positions(&nan, &names()), Err(Malformed::NotFinite));
    }

    #[test]
    fn a_turn_of_the_wheel_is_ticks_per_rev_ticks() {
        assert_eq!(ticks(TAU, 42.0), 42);
        assert_eq!(ticks(-TAU / 2.0, 42.0), -21);
        assert_eq!(ticks(0.01, 42.0), 0);
    }

    fn odom(x: f64, y: f64, yaw: f64) -> Odometry {
        let mut o = Odometry::default();
        o.pose.pose.position.x = x;
        o.pose.pose.position.y = y;
        o.pose.pose.orientation = Quaternion::yaw(yaw);
        o
    }

    #[test]
    fn odom_poses_become_the_wheel_turns_that_drive_them() {
        let (r, axle) = (0.02, 0.1);
        let mut w = OdomWheels::default();
        // The first pose only sets the origin, wherever the odom frame has it.
        assert_eq!(w.take(&odom(5.0, -3.0, 1.0), r, axle).unwrap(), (0.0, 0.0));
        // Straight ahead 0.1 m along the heading: both wheels 0.1 / r.
        let (l, rr) = w
            .take(
                &odom(5.0 + 0.1 * 1f64.cos(), -3.0 + 0.1 * 1f64.sin(), 1.0),
                r,
                axle,
            )
            .unwrap();
        assert!(
            (l - 5.0).abs() < 1e-9 && (rr - 5.0).abs() < 1e-9,
            "{l} {rr}"
        );
        // A quarter turn on the spot: opposite wheels, axle/2 * pi/2 / r each.
        let mut w = OdomWheels::default();
        w.take(&odom(0.0, 0.0, 3.0), r, axle).unwrap();
        let (l, rr) = w.take(&odom(0.0, 0.0, 3.0 + TAU / 4.0), r, axle).unwrap();
        let want = axle / 2.0 * TAU / 4.0 / r;
        assert!(
            (l + want).abs() < 1e-9 && (rr - want).abs() < 1e-9,
            "{l} {rr}"
        );
        // An arc: radius 1 m, a quarter circle, from (0,0) heading 0 to (1,1) heading pi/2.
        let mut w = OdomWheels::default();
        w.take(&odom(0.0, 0.0, 0.0), r, axle).unwrap();
        let (l, rr) = w.take(&odom(1.0, 1.0, TAU / 4.0), r, axle).unwrap();
        let arc = TAU / 4.0;
        assert!((l - (1.0 - axle / 2.0) * arc / r).abs() < 1e-9, "{l}");
        assert!((rr - (1.0 + axle / 2.0) * arc / r).abs() < 1e-9, "{rr}");
    }

    #[test]
    fn a_turn_across_pi_is_the_short_way() {
        assert!((wrap(3.0 * TAU / 4.0) + TAU / 4.0).abs() < 1e-12);
        assert!((wrap(-3.0 * TAU / 4.0) - TAU / 4.0).abs() < 1e-12);
    }
}
