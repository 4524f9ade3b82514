//! The stepper benchmark behind `hnav-bench sim`: robot-steps per second of [`World::step`].

use std::time::Instant;

use hnav_runtime::grid::geometry::cell_centre_pose;
use hnav_runtime::grid::{Cell, Grid};
use hnav_runtime::scenario::params::{RobotParams, SimParams};
use hnav_sim::{SimError, World};
use serde::Serialize;

/// What [`robot_steps_per_second`] measured.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BenchResult {
    /// Robots in the world.
    pub robots: usize,
    /// Physics steps taken.
    pub steps: u64,
    /// Wall time of the stepping, s.
    pub elapsed_s: f64,
    /// `robots * steps / elapsed_s`.
    pub robot_steps_per_s: f64,
    /// Physics step, ms.
    pub step_ms: u32,
    /// Collisions that began during the run.
    pub collisions: usize,
}

/// Smallest arena edge in cells, so that a small swarm is not boxed in by walls.
const MIN_SIDE: u32 = 9;

/// Steps a world of `robots` default robots for about `seconds` of wall time and reports
/// robot-steps per second. Robots start on every other cell of a free square grid (at least
/// `MIN_SIDE` cells across) and drive
/// arcs of different curvature (slip noise off, collision checks on), with commands renewed
/// every 10 ms of sim time as an agent would.
pub fn robot_steps_per_second(robots: usize, seconds: f64) -> Result<BenchResult, SimError> {
    let robot = RobotParams::default();
    let sim = SimParams::default();
    let side = (((robots as f64).sqrt().ceil() as u32).max(1) * 2 + 1).max(MIN_SIDE);
    let grid = Grid::new(side, side).map_err(|_| SimError::BadParam {
        name: "robots",
        value: robots as f64,
        why: "too many robots for a benchmark grid",
    })?;
    let per_row = (side - 1) / 2;
    let starts: Vec<_> = (0..robots as u32)
        .map(|i| {
            let c = Cell::new(1 + 2 * (i % per_row), 1 + 2 * (i / per_row));
            cell_centre_pose(robot.cell_size_m, c, f64::from(i) * 0.7)
        })
        .collect();
    let mut world = World::new(&robot, &sim, grid, &starts)?;
    let command = |w: &mut World, period: u64| {
        let now = w.time_ns();
        for i in 0..robots as u32 {
            let k = f64::from(i % 7) - 3.0;
            // Agent indices come from 0..robots and the speeds are finite: cannot fail.
            let _ = w.apply_command(i, period, 10.0 - k, 10.0 + k, now);
        }
    };
    command(&mut world, 0);
    let start = Instant::now();
    let mut steps = 0u64;
    let mut elapsed;
    loop {
        for _ in 0..10 {
            world.step();
        }
        steps += 10;
        command(&mut world, steps / 10);
        elapsed = start.elapsed().as_secs_f64();
        if elapsed >= seconds {
            break;
        }
    }
    Ok(BenchResult {
        robots,
        steps,
        elapsed_s: elapsed,
        robot_steps_per_s: (robots as u64 * steps) as f64 / elapsed,
        step_ms: sim.step_ms,
        collisions: world.collisions().len(),
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn bench_runs_and_reports() {
        let r = super::robot_steps_per_second(16, 0.01).unwrap();
        assert_eq!(r.robots, 16);
        assert!(r.steps >= 10 && r.robot_steps_per_s > 0.0);
    }
}
