//! The heartbeat: proof, every few tens of milliseconds, that a process's main loop still
//! turns (see `health` for who sends it and `supervisor::run::hang` for who reads it).

use iceoryx2::prelude::ZeroCopySend;

use super::Role;

/// One beat of one process, on the `heartbeat` topic.
///
/// The beat carries its own time (`CLOCK_MONOTONIC`, [`crate::clock::monotonic_ns`]) so that
/// the supervisor judges a process's silence by when it last beat, not by when the supervisor
/// happened to read it: a supervisor that was itself paused does not mistake its own pause for
/// its children's.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
#[type_name("hnav::Heartbeat")]
pub struct Heartbeat {
    /// When the beat was sent, `CLOCK_MONOTONIC` nanoseconds.
    pub t_ns: u64,
    /// Beats this process has sent before this one.
    pub seq: u64,
    /// OS process id of the sender: a beat of an earlier incarnation is not the current one's.
    pub pid: u32,
    /// Agent index for [`Role::Agent`], else 0.
    pub index: u32,
    /// A [`Role`] as `u8`.
    pub role: u8,
    /// Zero.
    pub reserved: [u8; 7],
}

impl Heartbeat {
    /// Beat number `seq` of the calling process (`role`, `index`), stamped `t_ns`.
    pub fn new(role: Role, index: u32, seq: u64, t_ns: u64) -> Self {
        Self {
            t_ns,
            seq,
            pid: std::process::id(),
            index,
            role: role as u8,
            reserved: [0; 7],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::mem::{align_of, offset_of, size_of};

    #[test]
    fn heartbeat_layout() {
        assert_eq!(size_of::<Heartbeat>(), 32);
        assert_eq!(align_of::<Heartbeat>(), 8);
        assert_eq!(offset_of!(Heartbeat, t_ns), 0);
        assert_eq!(offset_of!(Heartbeat, seq), 8);
        assert_eq!(offset_of!(Heartbeat, pid), 16);
        assert_eq!(offset_of!(Heartbeat, index), 20);
        assert_eq!(offset_of!(Heartbeat, role), 24);
        assert_eq!(offset_of!(Heartbeat, reserved), 25);
    }

    #[test]
    fn a_beat_names_its_sender() {
        let b = Heartbeat::new(Role::Agent, 3, 7, 42);
        assert_eq!(Role::from_u8(b.role), Some(Role::Agent));
        assert_eq!((b.index, b.seq, b.t_ns), (3, 7, 42));
        assert_eq!(b.pid, std::process::id());
    }
}
