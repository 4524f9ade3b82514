//! Wheels and ground truth: what agents command, what motor drivers report, where the sim
//! says the robots are.

use iceoryx2::prelude::ZeroCopySend;

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

/// The user header of the sim's ground truth (`truth`, a [`Pose`] slice sized to the run's
/// robots): when, and the collision count so far. The 24 bytes that opened the fixed-size
/// `Truth` of 256 poses before runs were sized to their swarm.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
#[type_name("hnav::TruthHeader")]
pub struct TruthHeader {
    /// Simulated time, ns since the start of the run.
    pub sim_time_ns: u64,
    /// Control period.
    pub period: u64,
    /// How many poses the slice holds, said again for readers whose binding reports a
    /// slice's length in bytes.
    pub robots: u32,
    /// Collisions detected since the start of the run.
    pub collisions: u32,
}

/// Ground truth as it is read: every robot's pose, borrowed from a sample in shared memory
/// (no copy) or from an owned [`Truth`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthView<'a> {
    header: TruthHeader,
    poses: &'a [Pose],
}

impl<'a> TruthView<'a> {
    /// The truth of `header` and `poses`; a header whose count disagrees with the slice reads
    /// as the shorter of the two.
    pub fn new(header: &TruthHeader, poses: &'a [Pose]) -> Self {
        let n = (header.robots as usize).min(poses.len());
        Self {
            header: *header,
            poses: &poses[..n],
        }
    }

    /// Simulated time, ns since the start of the run.
    pub fn sim_time_ns(&self) -> u64 {
        self.header.sim_time_ns
    }

    /// Control period.
    pub fn period(&self) -> u64 {
        self.header.period
    }

    /// Collisions detected since the start of the run.
    pub fn collisions(&self) -> u32 {
        self.header.collisions
    }

    /// The poses, one per robot.
    pub fn poses(&self) -> &'a [Pose] {
        self.poses
    }

    /// The header, its count that of [`TruthView::poses`].
    pub fn header(&self) -> TruthHeader {
        TruthHeader {
            robots: self.poses.len() as u32,
            ..self.header
        }
    }
}

/// Ground truth held in memory (a replay, an export, a test); what travels is a
/// [`TruthHeader`] and its poses, read as a [`TruthView`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Truth {
    /// Simulated time, ns since the start of the run.
    pub sim_time_ns: u64,
    /// Control period.
    pub period: u64,
    /// Collisions detected since the start of the run.
    pub collisions: u32,
    /// The poses, one per robot.
    pub poses: Vec<Pose>,
}

impl Truth {
    /// The truth borrowed as it is read from the topic.
    pub fn view(&self) -> TruthView<'_> {
        TruthView {
            header: TruthHeader {
                sim_time_ns: self.sim_time_ns,
                period: self.period,
                robots: self.poses.len() as u32,
                collisions: self.collisions,
            },
            poses: &self.poses,
        }
    }

    /// The poses, one per robot.
    pub fn poses(&self) -> &[Pose] {
        &self.poses
    }

    /// Holds `v` (copied out of its sample), reusing this truth's memory for the poses.
    pub fn set(&mut self, v: TruthView<'_>) {
        self.sim_time_ns = v.sim_time_ns();
        self.period = v.period();
        self.collisions = v.collisions();
        self.poses.clear();
        self.poses.extend_from_slice(v.poses());
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
        assert_eq!(size_of::<TruthHeader>(), 24);
        assert_eq!(align_of::<TruthHeader>(), 8);
        assert_eq!(offset_of!(TruthHeader, sim_time_ns), 0);
        assert_eq!(offset_of!(TruthHeader, period), 8);
        assert_eq!(offset_of!(TruthHeader, robots), 16);
        assert_eq!(offset_of!(TruthHeader, collisions), 20);
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
        let poses = [Pose::default(); 7];
        let h = TruthHeader {
            robots: 9,
            ..TruthHeader::default()
        };
        assert_eq!(TruthView::new(&h, &poses).poses().len(), 7);
        let h = TruthHeader { robots: 3, ..h };
        assert_eq!(TruthView::new(&h, &poses).header().robots, 3);
        let owned = Truth {
            poses: poses.to_vec(),
            collisions: 2,
            ..Truth::default()
        };
        assert_eq!(owned.view().header().robots, 7);
        assert_eq!(owned.view().collisions(), 2);
    }
}
