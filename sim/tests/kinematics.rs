//! Kinematics against closed forms (noise off, ideal motors started at speed): straight line,
//! rotation in place and a constant arc, within 1e-9.

use hnav_runtime::grid::geometry::wrap_angle;
use hnav_runtime::grid::Grid;
use hnav_runtime::msg::Pose;
use hnav_runtime::scenario::params::{RobotParams, SimParams};
use hnav_sim::World;

const TOL: f64 = 1e-9;

/// Drives one robot from `start` with constant wheel speeds for `steps` 1 ms steps.
fn drive(start: Pose, wl: f64, wr: f64, steps: u64) -> (Pose, RobotParams) {
    let robot = RobotParams {
        motor_lag_s: 0.0,
        ..RobotParams::default()
    };
    let sim = SimParams {
        watchdog_ms: u32::MAX,
        ..SimParams::default()
    };
    let mut w = World::new(&robot, &sim, Grid::new(200, 200).unwrap(), &[start]).unwrap();
    w.apply_command(0, 0, wl, wr, 0).unwrap();
    w.set_wheel_speeds(0, wl, wr).unwrap();
    for _ in 0..steps {
        w.step();
    }
    (w.pose(0).unwrap(), robot)
}

fn start() -> Pose {
    Pose {
        x_m: 12.0,
        y_m: 12.0,
        theta_rad: 0.4,
    }
}

#[test]
fn straight_line_matches_closed_form() {
    let (p, r) = drive(start(), 15.0, 15.0, 5000);
    let d = 15.0 * r.wheel_radius_m * 5.0;
    let s = start();
    assert!((p.x_m - (s.x_m + d * s.theta_rad.cos())).abs() < TOL);
    assert!((p.y_m - (s.y_m + d * s.theta_rad.sin())).abs() < TOL);
    assert!((p.theta_rad - s.theta_rad).abs() < TOL);
}

#[test]
fn rotation_in_place_matches_closed_form() {
    let (p, r) = drive(start(), -8.0, 8.0, 7000);
    let omega = 2.0 * 8.0 * r.wheel_radius_m / r.axle_track_m;
    let s = start();
    assert!((p.x_m - s.x_m).abs() < TOL && (p.y_m - s.y_m).abs() < TOL);
    let want = wrap_angle(s.theta_rad + omega * 7.0);
    assert!(wrap_angle(p.theta_rad - want).abs() < TOL, "{p:?} {want}");
}

#[test]
fn constant_arc_matches_closed_form() {
    let (wl, wr) = (6.0, 14.0);
    let t = 9.0;
    let (p, r) = drive(start(), wl, wr, 9000);
    let v = r.wheel_radius_m * (wl + wr) / 2.0;
    let omega = r.wheel_radius_m * (wr - wl) / r.axle_track_m;
    let s = start();
    let th = s.theta_rad + omega * t;
    let x = s.x_m + v / omega * (th.sin() - s.theta_rad.sin());
    let y = s.y_m - v / omega * (th.cos() - s.theta_rad.cos());
    assert!((p.x_m - x).abs() < TOL, "{} vs {x}", p.x_m);
    assert!((p.y_m - y).abs() < TOL, "{} vs {y}", p.y_m);
    assert!(wrap_angle(p.theta_rad - th).abs() < TOL);
}
