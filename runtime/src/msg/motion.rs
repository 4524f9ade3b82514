//! Wheels and ground truth: what agents command, what motor drivers report, where the sim
//! says the robots are.

use iceoryx2::prelude::ZeroCopySend;

use super::MAX_AGENTS;

/// Wheel speed set-points for one robot and one control period.
#[derive(
    Debug, Clone, Copy, PartialEq, Default, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
#[type_name("hnav::WheelCommand")]
pub struct WheelCommand {
    /// Control period this command is for (lockstep) or the sender's counter (realtime).
    pub period: u64,
    /// Agent (robot) index.
    pub agent: u32,
    /// Zero for now; reserved for brake requests and similar.
    pub flags: u32,
    /// Left wheel angular speed set-point, rad/s.
    pub left_rad_s: f64,
    /// Right wheel angular speed set-point, rad/s.
    pub right_rad_s: f64,
}

/// Cumulative Hall-sensor counts of one robot, as a motor driver reports them, and now and
/// then a localisation fix: where a map-based localiser puts the robot at the same instant.
#[derive(
    Debug, Clone, Copy, PartialEq, Default, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
#[type_name("hnav::Odometry")]
pub struct Odometry {
    /// Simulated time of the reading, ns since the start of the run.
    pub sim_time_ns: u64,
    /// Control period the reading closes.
    pub period: u64,
    /// Agent (robot) index.
    pub agent: u32,
    /// [`Odometry::FIX`] when `fix` holds a fix; no other bit is used.
    pub flags: u32,
    /// Signed cumulative ticks of the left wheel.
    pub ticks_left: i64,
    /// Signed cumulative ticks of the right wheel.
    pub ticks_right: i64,
    /// The localisation fix if `flags` has [`Odometry::FIX`], else zero.
    pub fix: Pose,
}

impl Odometry {
    /// `flags` bit: the reading carries a localisation fix.
    pub const FIX: u32 = 1;

    /// The localisation fix, if the reading carries one.
    pub fn fix(&self) -> Option<Pose> {
        (self.flags & Self::FIX != 0).then_some(self.fix)
    }
}

/// A planar pose in metres and radians (x right, y down the map's rows, as the grid).
#[derive(
    Debug, Clone, Copy, PartialEq, Default, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
#[type_name("hnav::Pose")]
pub struct Pose {
    /// x, metres.
    pub x_m: f64,
    /// y, metres.
    pub y_m: f64,
    /// Heading, radians.
    pub theta_rad: f64,
}

/// Ground truth from the sim: every robot's pose and the collision count so far.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
#[type_name("hnav::Truth")]
pub struct Truth {
    /// Simulated time, ns since the start of the run.
    pub sim_time_ns: u64,
    /// Control period.
    pub period: u64,
    /// How many entries of `poses` are valid.
    pub robots: u32,
    /// Collisions detected since the start of the run.
    pub collisions: u32,
    /// The poses, `poses[..robots]`.
    pub poses: [Pose; MAX_AGENTS],
}

impl Default for Truth {
    fn default() -> Self {
        Self {
            sim_time_ns: 0,
            period: 0,
            robots: 0,
            collisions: 0,
            poses: [Pose::default(); MAX_AGENTS],
        }
    }
}

/// An agent's dead-reckoned pose: where it believes its robot is, published at most once
/// per control period (`estimate` topic) for the recorder and viewers; nothing in the swarm
/// decides by it.
#[derive(
    Debug, Clone, Copy, PartialEq, Default, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
#[type_name("hnav::Estimate")]
pub struct Estimate {
    /// Simulated time of the odometry reading the pose folds in, ns since the start of the run.
    pub sim_time_ns: u64,
    /// Agent (robot) index.
    pub agent: u32,
    /// Zero.
    pub reserved: u32,
    /// The estimated pose.
    pub pose: Pose,
}

impl Truth {
    /// The valid poses (`robots` clamped to [`MAX_AGENTS`]).
    pub fn poses(&self) -> &[Pose] {
        &self.poses[..(self.robots as usize).min(MAX_AGENTS)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::mem::{align_of, offset_of, size_of};

    #[test]
    fn wheel_and_odometry_layout() {
        assert_eq!(size_of::<WheelCommand>(), 32);
        assert_eq!(align_of::<WheelCommand>(), 8);
        assert_eq!(offset_of!(WheelCommand, period), 0);
        assert_eq!(offset_of!(WheelCommand, agent), 8);
        assert_eq!(offset_of!(WheelCommand, flags), 12);
        assert_eq!(offset_of!(WheelCommand, left_rad_s), 16);
        assert_eq!(offset_of!(WheelCommand, right_rad_s), 24);
        assert_eq!(size_of::<Odometry>(), 64);
        assert_eq!(align_of::<Odometry>(), 8);
        assert_eq!(offset_of!(Odometry, sim_time_ns), 0);
        assert_eq!(offset_of!(Odometry, period), 8);
        assert_eq!(offset_of!(Odometry, agent), 16);
        assert_eq!(offset_of!(Odometry, flags), 20);
        assert_eq!(offset_of!(Odometry, ticks_left), 24);
        assert_eq!(offset_of!(Odometry, ticks_right), 32);
        assert_eq!(offset_of!(Odometry, fix), 40);
    }

    #[test]
    fn truth_layout() {
        assert_eq!(size_of::<Pose>(), 24);
        assert_eq!(offset_of!(Pose, x_m), 0);
        assert_eq!(offset_of!(Pose, y_m), 8);
        assert_eq!(offset_of!(Pose, theta_rad), 16);
        assert_eq!(size_of::<Truth>(), 24 + 24 * MAX_AGENTS);
        assert_eq!(size_of::<Truth>(), 6168);
        assert_eq!(align_of::<Truth>(), 8);
        assert_eq!(offset_of!(Truth, sim_time_ns), 0);
        assert_eq!(offset_of!(Truth, period), 8);
        assert_eq!(offset_of!(Truth, robots), 16);
        assert_eq!(offset_of!(Truth, collisions), 20);
        assert_eq!(offset_of!(Truth, poses), 24);
    }

    #[test]
    fn estimate_layout() {
        assert_eq!(size_of::<Estimate>(), 40);
        assert_eq!(align_of::<Estimate>(), 8);
        assert_eq!(offset_of!(Estimate, sim_time_ns), 0);
        assert_eq!(offset_of!(Estimate, agent), 8);
        assert_eq!(offset_of!(Estimate, reserved), 12);
        assert_eq!(offset_of!(Estimate, pose), 16);
    }

    #[test]
    fn a_corrupt_count_does_not_index_out_of_bounds() {
        let t = Truth {
            robots: 7,
            ..Truth::default()
        };
        assert_eq!(t.poses().len(), 7);
    }
}
