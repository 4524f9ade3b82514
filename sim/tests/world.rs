//! World-level behaviour: collisions (head-on, into a wall, a clear run), the motor watchdog,
//! and bit-for-bit determinism of two runs with one seed.

use hnav_runtime::grid::geometry::cell_centre_pose;
use hnav_runtime::grid::{Cell, Grid};
use hnav_runtime::hash::Fnv1a64;
use hnav_runtime::msg::{Pose, Truth};
use hnav_runtime::scenario::params::{RobotParams, SimParams};
use hnav_sim::{Hit, World};

fn at(cell: Cell, theta: f64) -> Pose {
    cell_centre_pose(RobotParams::default().cell_size_m, cell, theta)
}

/// Runs `steps` steps renewing each robot's command `(l, r)` every 10 steps.
fn run(w: &mut World, cmds: &[(f64, f64)], steps: u64) {
    for _ in 0..steps {
        if w.steps().is_multiple_of(10) {
            let (now, period) = (w.time_ns(), w.steps() / 10);
            for (i, &(l, r)) in cmds.iter().enumerate() {
                w.apply_command(i as u32, period, l, r, now).unwrap();
            }
        }
        w.step();
    }
}

#[test]
fn head_on_robots_collide_once() {
    let starts = [
        at(Cell::new(2, 5), 0.0),
        at(Cell::new(12, 5), std::f64::consts::PI),
    ];
    let grid = Grid::new(15, 10).unwrap();
    let mut w = World::new(
        &RobotParams::default(),
        &SimParams::default(),
        grid,
        &starts,
    )
    .unwrap();
    run(&mut w, &[(10.0, 10.0), (10.0, 10.0)], 4000);
    let robot_hits: Vec<_> = w
        .collisions()
        .iter()
        .filter(|c| matches!(c.hit, Hit::Robot(_)))
        .collect();
    assert_eq!(robot_hits.len(), 1, "{:?}", w.collisions());
    let c = robot_hits[0];
    assert_eq!((c.robot, c.hit), (0, Hit::Robot(1)));
    let d = (c.position - c.other_position).norm();
    assert!(d < 2.0 * RobotParams::default().body_radius_m && d > 0.1);
    assert!(c.time_ns > 0);
    let mut t = Truth::default();
    w.fill_truth(0, &mut t);
    assert_eq!(t.collisions as usize, w.collisions().len());
}

#[test]
fn robot_driven_into_a_wall_collides() {
    let mut grid = Grid::new(10, 5).unwrap();
    grid.set_blocked(Cell::new(6, 2), true);
    let mut w = World::new(
        &RobotParams::default(),
        &SimParams::default(),
        grid,
        &[at(Cell::new(2, 2), 0.0)],
    )
    .unwrap();
    run(&mut w, &[(10.0, 10.0)], 3000);
    let first = w.collisions().first().expect("a wall hit");
    assert_eq!((first.robot, first.hit), (0, Hit::Cell(6, 2)));
    // The disc's front reaches the cell's left edge (x = 6 cells).
    let r = RobotParams::default();
    let edge = 6.0 * r.cell_size_m;
    assert!(
        (first.position.x + r.body_radius_m - edge).abs() < 1e-3,
        "{first:?}"
    );
}

#[test]
fn clear_run_reports_no_collision() {
    let starts = [at(Cell::new(2, 2), 0.0), at(Cell::new(2, 6), 0.0)];
    let mut w = World::new(
        &RobotParams::default(),
        &SimParams::default(),
        Grid::new(30, 9).unwrap(),
        &starts,
    )
    .unwrap();
    run(&mut w, &[(10.0, 10.0), (12.0, 12.0)], 5000);
    assert!(w.collisions().is_empty(), "{:?}", w.collisions());
}

#[test]
fn watchdog_brakes_a_robot_whose_commands_stop() {
    let sim = SimParams {
        watchdog_ms: 100,
        ..SimParams::default()
    };
    let mut w = World::new(
        &RobotParams::default(),
        &sim,
        Grid::new(40, 5).unwrap(),
        &[at(Cell::new(2, 2), 0.0)],
    )
    .unwrap();
    run(&mut w, &[(15.0, 15.0)], 1000);
    let (l, _) = w.wheel_speeds(0).unwrap();
    assert!((l - 15.0).abs() < 1e-6, "at speed: {l}");
    assert!(!w.braking(0));
    // The commands stop: the last one arrived at 990 ms, so it expires once older than
    // 100 ms, from 1091 ms on.
    for _ in 0..90 {
        w.step();
    }
    assert!(!w.braking(0) && w.wheel_speeds(0).unwrap().0 > 14.9);
    for _ in 0..10 {
        w.step();
    }
    assert!(w.braking(0));
    // 15 rad/s at 200 rad/s² stops within 75 ms.
    for _ in 0..80 {
        w.step();
    }
    assert_eq!(w.wheel_speeds(0).unwrap(), (0.0, 0.0));
    let p = w.pose(0).unwrap();
    w.step();
    assert_eq!(w.pose(0).unwrap(), p, "a braked robot stands still");
}

/// FNV-1a over a Truth's fields, one by one, as a sample carries them.
fn hash_truth(h: &mut Fnv1a64, t: &Truth) {
    h.u64(t.sim_time_ns).u64(t.period);
    h.bytes(&(t.poses.len() as u32).to_le_bytes())
        .bytes(&t.collisions.to_le_bytes());
    for p in &t.poses {
        h.f64(p.x_m).f64(p.y_m).f64(p.theta_rad);
    }
}

fn truth_stream_hash(seed: u64) -> u64 {
    let sim = SimParams {
        seed,
        slip_std: 0.02,
        ..SimParams::default()
    };
    let starts: Vec<_> = (0..8)
        .map(|i| at(Cell::new(2 + 3 * i, 4), 0.3 * f64::from(i)))
        .collect();
    let mut w = World::new(
        &RobotParams::default(),
        &sim,
        Grid::new(30, 10).unwrap(),
        &starts,
    )
    .unwrap();
    let cmds: Vec<_> = (0..8)
        .map(|i| (8.0 + f64::from(i), 12.0 - f64::from(i)))
        .collect();
    let (mut h, mut t) = (Fnv1a64::new(), Truth::default());
    for period in 0..300 {
        run(&mut w, &cmds, 10);
        w.fill_truth(period, &mut t);
        hash_truth(&mut h, &t);
    }
    h.finish()
}

#[test]
fn one_seed_gives_identical_truth_streams() {
    let a = truth_stream_hash(42);
    assert_eq!(a, truth_stream_hash(42));
    assert_ne!(a, truth_stream_hash(43), "the seed reaches the slip noise");
}

#[test]
fn scenario_start_headings_and_slip_hold_reach_the_world() {
    use hnav_runtime::scenario::Scenario;
    let text = r#"
name = "headings"
[map]
rows = ["......", "......", "......"]
[sim]
slip_hold_s = 0.05
[[agents]]
start = [1, 1]
goal = [4, 1]
[[agents]]
start = [2, 2]
goal = [4, 2]
start_heading_deg = 90
"#;
    let s = Scenario::from_str(text, "<t>", std::path::Path::new(".")).unwrap();
    let mut w = World::from_scenario(&s).unwrap();
    assert_eq!(w.pose(0).unwrap(), at(Cell::new(1, 1), 0.0));
    let (p1, c1) = (w.pose(1).unwrap(), at(Cell::new(2, 2), 0.0));
    assert_eq!((p1.x_m, p1.y_m), (c1.x_m, c1.y_m));
    assert!((p1.theta_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    // Robot 1 drives towards +y (larger rows); its rigid transform agrees with its pose.
    run(&mut w, &[(0.0, 0.0), (10.0, 10.0)], 200);
    let (p1, iso) = (w.pose(1).unwrap(), w.isometry(1).unwrap());
    assert!(
        p1.y_m > c1.y_m + 0.01 && (p1.x_m - c1.x_m).abs() < 1e-12,
        "{p1:?}"
    );
    assert_eq!(w.position(1).unwrap(), iso.translation.vector.into());
    assert!((iso.rotation.angle() - p1.theta_rad).abs() < 1e-15);

    let bad = SimParams {
        slip_hold_s: 0.0,
        ..SimParams::default()
    };
    let starts = [at(Cell::new(1, 1), 0.0)];
    let grid = Grid::new(5, 5).unwrap();
    assert!(World::new(&RobotParams::default(), &bad, grid, &starts).is_err());
}

#[test]
fn slip_hold_changes_the_noise_not_its_determinism() {
    let truth = |hold: f64| {
        let sim = SimParams {
            seed: 4,
            slip_std: 0.05,
            slip_hold_s: hold,
            ..SimParams::default()
        };
        let starts = [at(Cell::new(3, 3), 0.0)];
        let grid = Grid::new(30, 9).unwrap();
        let mut w = World::new(&RobotParams::default(), &sim, grid, &starts).unwrap();
        run(&mut w, &[(10.0, 10.0)], 1000);
        w.pose(0).unwrap()
    };
    assert_eq!(truth(0.01), truth(0.01));
    assert_ne!(truth(0.01), truth(0.05));
}
