//! The neural-map snapshot's header.

use iceoryx2::prelude::ZeroCopySend;

/// How a neural map's neurons saturate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum ActivationKind {
    /// Linear with saturation at 1.
    Linear = 1,
    /// Hyperbolic tangent.
    Tanh = 2,
    /// Not a neural map: the route of a route-following agent (`planner = "pso"` or
    /// `"ga-fuzzy"`), each remaining route cell valued `1 / (1 + steps from it to the
    /// target)`, every other cell 0, so a viewer shows it on the same colour scale.
    Route = 3,
}

impl ActivationKind {
    /// Decodes an activation byte received from another process.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            1 => Some(Self::Linear),
            2 => Some(Self::Tanh),
            3 => Some(Self::Route),
            _ => None,
        }
    }
}

/// The user header of a neural-map snapshot (`[f32]` slice, one activation per cell).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend, bytemuck::Pod, bytemuck::Zeroable,
)]
#[repr(C)]
#[type_name("hnav::MapHeader")]
pub struct MapHeader {
    /// Decision round after which the map was built or repaired.
    pub round: u64,
    /// Agent index.
    pub agent: u32,
    /// Grid width (cells).
    pub width: u32,
    /// Grid height (cells).
    pub height: u32,
    /// Sweeps the map took.
    pub iterations: u32,
    /// Target cell (goal or current waypoint).
    pub target: u32,
    /// An [`ActivationKind`] as `u8`.
    pub activation: u8,
    /// Zero.
    pub reserved: [u8; 3],
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::mem::{align_of, offset_of, size_of};

    #[test]
    fn map_header_layout() {
        assert_eq!(size_of::<MapHeader>(), 32);
        assert_eq!(align_of::<MapHeader>(), 8);
        assert_eq!(offset_of!(MapHeader, round), 0);
        assert_eq!(offset_of!(MapHeader, agent), 8);
        assert_eq!(offset_of!(MapHeader, width), 12);
        assert_eq!(offset_of!(MapHeader, height), 16);
        assert_eq!(offset_of!(MapHeader, iterations), 20);
        assert_eq!(offset_of!(MapHeader, target), 24);
        assert_eq!(offset_of!(MapHeader, activation), 28);
        assert_eq!(offset_of!(MapHeader, reserved), 29);
    }

    #[test]
    fn activation_round_trips_and_rejects_unknown_bytes() {
        for a in [
            ActivationKind::Linear,
            ActivationKind::Tanh,
            ActivationKind::Route,
        ] {
            assert_eq!(ActivationKind::from_u8(a as u8), Some(a));
        }
        for bad in [0u8, 4, 5, 200, 255] {
            assert_eq!(ActivationKind::from_u8(bad), None);
        }
    }
}
