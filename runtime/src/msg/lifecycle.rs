//! The lifecycle protocol's payload: which process, what happened to it.

use iceoryx2::prelude::ZeroCopySend;

/// Which kind of process a [`Lifecycle`] event is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Role {
    /// The physics stepper `hnav-sim`.
    Sim = 1,
    /// The central compute block `hnav-coordinator`.
    Coordinator = 2,
    /// One robot's `hnav-agent`.
    Agent = 3,
}

impl Role {
    /// Decodes a role byte received from another process.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            1 => Some(Self::Sim),
            2 => Some(Self::Coordinator),
            3 => Some(Self::Agent),
            _ => None,
        }
    }
}

/// What happened to a process.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum LifecycleEvent {
    /// Started and attached to the run.
    Up = 1,
    /// Exited or was killed.
    Down = 2,
    /// Started again by the supervisor after a `Down`.
    Restarted = 3,
    /// Supervisor to all: every process is up, begin the run.
    Start = 4,
    /// Supervisor to all: finish cleanly and exit.
    Stop = 5,
}

impl LifecycleEvent {
    /// Decodes an event byte received from another process.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            1 => Some(Self::Up),
            2 => Some(Self::Down),
            3 => Some(Self::Restarted),
            4 => Some(Self::Start),
            5 => Some(Self::Stop),
            _ => None,
        }
    }
}

/// A process came up, went down or was restarted (published by the supervisor).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("hnav::Lifecycle")]
pub struct Lifecycle {
    /// Wall-clock time of the event, ns since the Unix epoch.
    pub time_ns: u64,
    /// OS process id.
    pub pid: u32,
    /// Agent index for [`Role::Agent`], else 0.
    pub index: u32,
    /// A [`Role`] as `u8`.
    pub role: u8,
    /// A [`LifecycleEvent`] as `u8`.
    pub event: u8,
    /// Zero.
    pub reserved: u16,
    /// Restarts of this process so far.
    pub restarts: u32,
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::mem::{align_of, offset_of, size_of};

    #[test]
    fn lifecycle_layout() {
        assert_eq!(size_of::<Lifecycle>(), 24);
        assert_eq!(align_of::<Lifecycle>(), 8);
        assert_eq!(offset_of!(Lifecycle, time_ns), 0);
        assert_eq!(offset_of!(Lifecycle, pid), 8);
        assert_eq!(offset_of!(Lifecycle, index), 12);
        assert_eq!(offset_of!(Lifecycle, role), 16);
        assert_eq!(offset_of!(Lifecycle, event), 17);
        assert_eq!(offset_of!(Lifecycle, reserved), 18);
        assert_eq!(offset_of!(Lifecycle, restarts), 20);
    }

    #[test]
    fn enums_round_trip_and_reject_unknown_bytes() {
        for r in [Role::Sim, Role::Coordinator, Role::Agent] {
            assert_eq!(Role::from_u8(r as u8), Some(r));
        }
        for e in [
            LifecycleEvent::Up,
            LifecycleEvent::Down,
            LifecycleEvent::Restarted,
            LifecycleEvent::Start,
            LifecycleEvent::Stop,
        ] {
            assert_eq!(LifecycleEvent::from_u8(e as u8), Some(e));
        }
        assert_eq!(LifecycleEvent::from_u8(6), None);
        for bad in [0u8, 5, 200, 255] {
            assert_eq!(Role::from_u8(bad), None);
            assert_eq!(LifecycleEvent::from_u8(bad.max(6)), None);
        }
    }
}
