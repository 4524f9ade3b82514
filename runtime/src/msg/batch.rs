//! The robots' own streams between the sim and the agent processes (wheel commands up,
//! odometry and views down) travel as one slice sample per agent process, not one topic per
//! robot: a process hosting K robots (`[run] agents_per_process`) reads one odometry topic and
//! writes one wheel topic. The sim then holds two or three services per process instead of
//! per robot; each iceoryx2 port keeps about six file descriptors open (its shared memory,
//! its event socket, its cleanup tag), and at 1 000 robots one port per robot in the sim went
//! past the 20 000 a process may hold. With one robot a process nothing changes but the
//! header: `odom/<i>` carries a slice of one.
//!
//! Each header names the first robot of the process (the topic's index) and how many
//! elements follow; each element still names its own robot, so a reader takes the ones for
//! the robots it hosts and drops the rest.

use iceoryx2::prelude::ZeroCopySend;

macro_rules! batch_header {
    ($(#[$doc:meta])* $name:ident, $type_name:literal) => {
        $(#[$doc])*
        #[derive(
            Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend, bytemuck::Pod,
            bytemuck::Zeroable,
        )]
        #[repr(C)]
        #[type_name($type_name)]
        pub struct $name {
            /// The first robot of the agent process the batch is to or from (the topic's
            /// index).
            pub first: u32,
            /// How many elements follow.
            pub count: u32,
        }
    };
}

batch_header!(
    /// The user header of `wheels/<first>`: a slice of [`WheelCommand`](super::WheelCommand),
    /// the latest command of each robot of the process that has sent one.
    WheelsHeader,
    "hnav::WheelsHeader"
);

batch_header!(
    /// The user header of `odom/<first>`: a slice of [`Odometry`](super::Odometry), one reading
    /// per robot of the process, all of one control period.
    OdometryHeader,
    "hnav::OdometryHeader"
);

batch_header!(
    /// The user header of `view/<first>`: a slice of [`View`](super::View), one per robot of
    /// the process, all of one control period.
    ViewsHeader,
    "hnav::ViewsHeader"
);

#[cfg(test)]
mod tests {
    use super::*;
    use core::mem::{align_of, offset_of, size_of};

    #[test]
    fn batch_header_layouts() {
        assert_eq!(size_of::<WheelsHeader>(), 8);
        assert_eq!(align_of::<WheelsHeader>(), 4);
        assert_eq!(offset_of!(WheelsHeader, first), 0);
        assert_eq!(offset_of!(WheelsHeader, count), 4);
        assert_eq!(size_of::<OdometryHeader>(), 8);
        assert_eq!(offset_of!(OdometryHeader, count), 4);
        assert_eq!(size_of::<ViewsHeader>(), 8);
        assert_eq!(offset_of!(ViewsHeader, count), 4);
    }
}
