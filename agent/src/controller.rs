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
//!
//! [`FuzzyController`] is seed 004's fine controller (see [`crate::ga_fuzzy::fuzzy`]) at the
//! wheels: it also reads the free space around the robot ([`FreeSpace`]). [`WheelDrive`]
//! makes the two interchangeable: one `command`/`arrived`, the proportional one ignoring the
//! free space.

use hnav_runtime::grid::geometry::wrap_angle_shifted;
use hnav_runtime::grid::Grid;
use hnav_runtime::msg::Pose;
use hnav_runtime::scenario::RobotParams;

use crate::ga_fuzzy::fuzzy::{direction_angle, FuzzyRules, DIRECTIONS};

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
        wheels(p, v, omega)
    }
}

/// Wheel set-points for forward speed `v` and turn rate `omega`, scaled together into the
/// motor limit.
fn wheels(p: &ControllerParams, v: f64, omega: f64) -> WheelSpeeds {
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

/// Free distance from the robot to the nearest blocked cell (or the grid's edge) in each of
/// the eight movement directions ([`direction_angle`] order), metres, capped at the range:
/// the input `A` of the fuzzy controller.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct FreeSpace {
    /// Distances, metres.
    pub metres: [f64; DIRECTIONS],
}

impl FreeSpace {
    /// Nothing within `range_m` in any direction.
    pub fn open(range_m: f64) -> FreeSpace {
        FreeSpace {
            metres: [range_m; DIRECTIONS],
        }
    }

    /// Casts the eight rays from `pose` over `grid` (cells `cell_size_m` wide) in steps of a
    /// tenth of a cell, up to `range_m`. Does not allocate.
    pub fn from_grid(grid: &Grid, cell_size_m: f64, pose: Pose, range_m: f64) -> FreeSpace {
        let mut metres = [range_m; DIRECTIONS];
        let step = 0.1 * cell_size_m;
        for (k, m) in metres.iter_mut().enumerate() {
            let (s, c) = direction_angle(k).sin_cos();
            let mut d = 0.0;
            while d < range_m {
                let (x, y) = (pose.x_m + d * c, pose.y_m + d * s);
                let cell = grid.cell_checked(
                    (x / cell_size_m).floor() as i64,
                    (y / cell_size_m).floor() as i64,
                );
                if cell.is_none_or(|cell| grid.is_blocked(cell)) {
                    break;
                }
                d += step;
            }
            *m = d.min(range_m);
        }
        FreeSpace { metres }
    }
}

/// Seed 004's fuzzy controller at the wheels: `V` scales the proportional controller's
/// distance-limited speed, `phi` is the heading error its turn gain acts on.
#[derive(Clone, Debug)]
pub struct FuzzyController {
    params: ControllerParams,
    rules: FuzzyRules,
    range_m: f64,
}

impl FuzzyController {
    /// A controller with `params` and sensors reaching `range_m` (the free areas are
    /// normalised by it).
    pub fn new(params: ControllerParams, range_m: f64) -> Self {
        FuzzyController {
            params,
            rules: FuzzyRules::default(),
            range_m: range_m.max(f64::MIN_POSITIVE),
        }
    }

    /// The sensor range, metres.
    pub fn range_m(&self) -> f64 {
        self.range_m
    }

    /// Whether `pose` is within the arrival tolerance of `(x, y)`.
    pub fn arrived(&self, pose: Pose, x: f64, y: f64) -> bool {
        (x - pose.x_m).hypot(y - pose.y_m) <= self.params.arrive_tolerance_m
    }

    /// Wheel set-points towards `(x, y)` given the free space around the robot.
    pub fn command(&self, pose: Pose, x: f64, y: f64, free: &FreeSpace) -> WheelSpeeds {
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
        let mut a = [0.0; DIRECTIONS];
        for (n, m) in a.iter_mut().zip(free.metres) {
            *n = (m / self.range_m).clamp(0.0, 1.0);
        }
        let o = self.rules.infer(&a, pose.theta_rad, dy.atan2(dx));
        let v = o.speed * (p.distance_gain * dist).min(p.max_speed_m_s) * o.turn.cos().max(0.0);
        wheels(p, v, p.heading_gain * o.turn)
    }
}

/// The wheel controller an agent drives with: the proportional one or seed 004's fuzzy one.
#[derive(Clone, Debug)]
pub enum WheelDrive {
    /// [`WheelController`].
    Proportional(WheelController),
    /// [`FuzzyController`].
    Fuzzy(FuzzyController),
}

impl WheelDrive {
    /// The fuzzy drive of a robot that travels `speed_cells_s` cells per second, sensing two
    /// cells around it `[inferred]`.
    pub fn fuzzy(robot: &RobotParams, speed_cells_s: f64) -> WheelDrive {
        WheelDrive::Fuzzy(FuzzyController::new(
            ControllerParams::new(robot, speed_cells_s),
            2.0 * robot.cell_size_m,
        ))
    }

    /// Whether [`WheelDrive::command`] reads the free space (so a caller may skip the rays).
    pub fn needs_free_space(&self) -> bool {
        matches!(self, WheelDrive::Fuzzy(_))
    }

    /// The sensor range the free space should be cast to (0 for the proportional drive).
    pub fn range_m(&self) -> f64 {
        match self {
            WheelDrive::Proportional(_) => 0.0,
            WheelDrive::Fuzzy(f) => f.range_m(),
        }
    }

    /// Whether `pose` is within the arrival tolerance of `(x, y)`.
    pub fn arrived(&self, pose: Pose, x: f64, y: f64) -> bool {
        match self {
            WheelDrive::Proportional(c) => c.arrived(pose, x, y),
            WheelDrive::Fuzzy(c) => c.arrived(pose, x, y),
        }
    }

    /// Wheel set-points towards `(x, y)`; the proportional drive ignores `free`.
    pub fn command(&self, pose: Pose, x: f64, y: f64, free: &FreeSpace) -> WheelSpeeds {
        match self {
            WheelDrive::Proportional(c) => c.command(pose, x, y),
            WheelDrive::Fuzzy(c) => c.command(pose, x, y, free),
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

    /// Drives `drive` at 10 ms over `grid` (free space cast every period) until it arrives;
    /// the end pose and the smallest clearance between the robot's centre and a wall cell.
    fn drive_fuzzy(d: &WheelDrive, grid: &Grid, mut pose: Pose, x: f64, y: f64) -> (Pose, f64) {
        let p = RobotParams::default();
        let mut clearance = f64::INFINITY;
        for _ in 0..3000 {
            let free = FreeSpace::from_grid(grid, p.cell_size_m, pose, d.range_m());
            clearance = clearance.min(free.metres.iter().copied().fold(f64::INFINITY, f64::min));
            let w = d.command(pose, x, y, &free);
            if w.arrived {
                break;
            }
            let (sl, sr) = (
                w.left_rad_s * p.wheel_radius_m * 0.01,
                w.right_rad_s * p.wheel_radius_m * 0.01,
            );
            pose = arc_update(pose, 0.5 * (sl + sr), (sr - sl) / p.axle_track_m);
        }
        (pose, clearance)
    }

    #[test]
    fn the_fuzzy_drive_reaches_cell_centres_from_any_heading() {
        let robot = RobotParams::default();
        let cs = robot.cell_size_m;
        let d = WheelDrive::fuzzy(&robot, 1.0);
        let grid = Grid::new(5, 5).unwrap();
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
                    x_m: 2.5 * cs,
                    y_m: 2.5 * cs,
                    theta_rad: theta,
                };
                let (x, y) = ((2.5 + f64::from(dx)) * cs, (2.5 + f64::from(dy)) * cs);
                let (end, _) = drive_fuzzy(&d, &grid, start, x, y);
                assert!(
                    d.arrived(end, x, y),
                    "heading {theta} to ({dx},{dy}): {end:?}"
                );
            }
        }
    }

    #[test]
    fn the_fuzzy_drive_keeps_off_a_wall_next_to_the_path() {
        // Row 0 is a wall; the robot starts in row 1 a little towards it and heading at it,
        // and drives two cells east. The proportional drive heads straight for the target.
        let robot = RobotParams::default();
        let cs = robot.cell_size_m;
        let grid = Grid::from_rows(&["@@@@@", ".....", "....."]).unwrap();
        let start = Pose {
            x_m: 0.5 * cs,
            y_m: 1.45 * cs,
            theta_rad: -0.6,
        };
        let (x, y) = (2.5 * cs, 1.5 * cs);
        let fuzzy = WheelDrive::fuzzy(&robot, 1.0);
        let (end, clear) = drive_fuzzy(&fuzzy, &grid, start, x, y);
        assert!(fuzzy.arrived(end, x, y), "{end:?}");
        // The body (its centre starts 0.45 cells off the wall) never touches the wall.
        assert!(clear >= robot.body_radius_m, "clearance {clear}");
        let prop = WheelDrive::Proportional(controller());
        assert!(!prop.needs_free_space() && fuzzy.needs_free_space());
        let (pend, _) = drive_fuzzy(&prop, &grid, start, x, y);
        assert!(prop.arrived(pend, x, y));
    }

    #[test]
    fn free_space_rays_stop_at_walls_and_the_edge() {
        let cs = 0.16;
        let grid = Grid::from_rows(&["@@@", "...", "..."]).unwrap();
        let pose = Pose {
            x_m: 1.5 * cs,
            y_m: 1.5 * cs,
            theta_rad: 0.0,
        };
        let f = FreeSpace::from_grid(&grid, cs, pose, 2.0 * cs);
        // North: half a cell to the wall row (in tenth-of-a-cell steps).
        assert!((f.metres[0] - 0.5 * cs).abs() <= 0.1 * cs + 1e-12, "{f:?}");
        // South: one and a half cells to the edge.
        assert!((f.metres[4] - 1.5 * cs).abs() <= 0.1 * cs + 1e-12, "{f:?}");
        assert_eq!(FreeSpace::open(1.0).metres, [1.0; 8]);
    }

    #[test]
    fn non_finite_targets_give_zero_speeds() {
        let c = controller();
        let w = c.command(Pose::default(), f64::NAN, 0.0);
        assert_eq!((w.left_rad_s, w.right_rad_s), (0.0, 0.0));
    }
}
