//! Payloads as bytes, for the links that leave shared memory (the Zenoh bridge between hosts).
//!
//! Inside a host a payload never becomes bytes: it is loaned, written in place and read in
//! place. Between hosts it travels as exactly the bytes of its `#[repr(C)]` layout (the table
//! in [the module docs](super)), little-endian on every target HNAV builds for. That is
//! sound because every payload is [`bytemuck::Pod`] (derived: no implicit padding, every bit
//! pattern of every field valid), so a byte string of the right length is always *some*
//! value. Whether it is a *sensible* value is [`Wire::check`]'s question: a receiver drops
//! what fails it instead of handing a process an agent index past the swarm or a NaN speed.

use core::fmt::Debug;

use iceoryx2::prelude::ZeroCopySend;

use super::{
    Candidate, CommitHeader, Decision, Estimate, Heartbeat, LifecycleEvent, MapHeader, Odometry,
    OdometryHeader, Pose, Progress, Role, TruthHeader, Verdict, WheelCommand, WheelsHeader,
    MAX_AGENTS,
};
use crate::msg::Lifecycle;

/// Why bytes from a link are not a payload of the expected type.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum WireError {
    /// The sender named another type.
    #[error("type {got:?} where {expected:?} was expected")]
    TypeName {
        /// The type the topic carries.
        expected: &'static str,
        /// The type the sender named.
        got: String,
    },
    /// The byte count is not the type's size.
    #[error("{len} bytes for {type_name}, which has {size}")]
    Size {
        /// The type.
        type_name: &'static str,
        /// Its size.
        size: usize,
        /// The bytes that came.
        len: usize,
    },
    /// A field is out of its range.
    #[error("{type_name}: {what}")]
    Field {
        /// The type.
        type_name: &'static str,
        /// Which field, and why.
        what: String,
    },
}

/// A payload that may travel as its bytes. See the [module docs](self).
pub trait Wire: bytemuck::Pod + ZeroCopySend + Debug {
    /// Whether the fields a receiver relies on are in range.
    fn check(&self) -> Result<(), String>;

    /// The iceoryx2 type name (`hnav::Candidate`), which also names it on a link.
    fn wire_name() -> &'static str {
        // SAFETY: `type_name` only returns the constant given in `#[type_name(...)]`; the
        // layout it vouches for is the one `Pod` guarantees here.
        unsafe { <Self as ZeroCopySend>::type_name() }
    }

    /// The value's bytes, borrowed (no copy).
    fn bytes(&self) -> &[u8] {
        bytemuck::bytes_of(self)
    }

    /// Overwrites `self` with `bytes` (a loaned sample, written in place) and checks the
    /// result. On an error `self` holds the bytes but must not be sent.
    fn assign(&mut self, bytes: &[u8]) -> Result<(), WireError> {
        let size = core::mem::size_of::<Self>();
        if bytes.len() != size {
            return Err(WireError::Size {
                type_name: Self::wire_name(),
                size,
                len: bytes.len(),
            });
        }
        bytemuck::bytes_of_mut(self).copy_from_slice(bytes);
        self.check().map_err(|what| WireError::Field {
            type_name: Self::wire_name(),
            what,
        })
    }
}

/// The header of a slice payload (a commit's decisions, the truth's poses, a neural map's
/// activations) that travels with its elements as bytes: the header's bytes, then the
/// elements', each in its `#[repr(C)]` layout. [`Wire::check`] checks the header alone,
/// [`WireSlice::check_elements`] the elements against it.
pub trait WireSlice: Wire + Default {
    /// The slice's element.
    type Element: bytemuck::Pod + ZeroCopySend + Debug;

    /// Whether `elements` agree with the header (their count) and are in range.
    fn check_elements(&self, elements: &[Self::Element]) -> Result<(), String>;

    /// Reads the header from `bytes` (checked) and returns it with the bytes of its elements,
    /// as many whole elements as the header counts. `Err` says why the bytes are not such a
    /// payload.
    fn from_wire(bytes: &[u8]) -> Result<(Self, &[u8]), WireError> {
        let header = core::mem::size_of::<Self>();
        let element = core::mem::size_of::<Self::Element>().max(1);
        if bytes.len() < header || !(bytes.len() - header).is_multiple_of(element) {
            return Err(Self::field(format!(
                "{} bytes are no {header}-byte header and whole {element}-byte elements",
                bytes.len()
            )));
        }
        let mut h = Self::default();
        h.assign(&bytes[..header])?;
        Ok((h, &bytes[header..]))
    }

    /// Copies the elements' bytes (from [`WireSlice::from_wire`]) into `out`, which has room
    /// for exactly as many (a loaned sample), and checks them against the header. The link's
    /// bytes need not be aligned for the element type, so each is read unaligned: this is the
    /// one copy a sample from another host costs.
    fn elements_from_wire(&self, bytes: &[u8], out: &mut [Self::Element]) -> Result<(), WireError> {
        let size = core::mem::size_of::<Self::Element>().max(1);
        if bytes.len() != out.len() * size {
            return Err(Self::field(format!(
                "{} bytes of elements for {} places",
                bytes.len(),
                out.len()
            )));
        }
        for (slot, b) in out.iter_mut().zip(bytes.chunks_exact(size)) {
            *slot = bytemuck::pod_read_unaligned(b);
        }
        self.check_elements(out).map_err(Self::field)
    }

    /// A field error of this type.
    fn field(what: String) -> WireError {
        WireError::Field {
            type_name: Self::wire_name(),
            what,
        }
    }
}

fn same_count(name: &str, said: u32, len: usize) -> Result<(), String> {
    if said as usize == len {
        Ok(())
    } else {
        Err(format!("{name} {said} but {len} elements follow"))
    }
}

fn agent(name: &str, agent: u32) -> Result<(), String> {
    if (agent as usize) < MAX_AGENTS {
        Ok(())
    } else {
        Err(format!("{name} {agent} is not below {MAX_AGENTS}"))
    }
}

fn finite(name: &str, v: f64) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("{name} is {v}"))
    }
}

impl Wire for Candidate {
    fn check(&self) -> Result<(), String> {
        agent("agent", self.agent)?;
        finite("priority", f64::from(self.priority))?;
        finite("speed", f64::from(self.speed))
    }
}

impl Wire for CommitHeader {
    fn check(&self) -> Result<(), String> {
        if self.count as usize > MAX_AGENTS {
            return Err(format!("count {} is over {MAX_AGENTS}", self.count));
        }
        Ok(())
    }
}

impl WireSlice for CommitHeader {
    type Element = Decision;

    fn check_elements(&self, decisions: &[Decision]) -> Result<(), String> {
        same_count("count", self.count, decisions.len())?;
        for d in decisions {
            agent("a decision's agent", d.agent)?;
            if Verdict::from_u8(d.verdict).is_none() {
                return Err(format!("verdict {} is none of the known ones", d.verdict));
            }
        }
        Ok(())
    }
}

impl Wire for Progress {
    fn check(&self) -> Result<(), String> {
        if self.agents as usize > MAX_AGENTS || self.at_goal > self.agents {
            return Err(format!("{} agents, {} at goal", self.agents, self.at_goal));
        }
        Ok(())
    }
}

impl Wire for Lifecycle {
    fn check(&self) -> Result<(), String> {
        if Role::from_u8(self.role).is_none() {
            return Err(format!("role {} is none of the known ones", self.role));
        }
        if LifecycleEvent::from_u8(self.event).is_none() {
            return Err(format!("event {} is none of the known ones", self.event));
        }
        Ok(())
    }
}

impl Wire for Heartbeat {
    fn check(&self) -> Result<(), String> {
        match Role::from_u8(self.role) {
            Some(_) => Ok(()),
            None => Err(format!("role {} is none of the known ones", self.role)),
        }
    }
}

impl Wire for WheelCommand {
    fn check(&self) -> Result<(), String> {
        agent("agent", self.agent)?;
        finite("left_rad_s", self.left_rad_s)?;
        finite("right_rad_s", self.right_rad_s)
    }
}

impl Wire for Odometry {
    fn check(&self) -> Result<(), String> {
        agent("agent", self.agent)?;
        if self.flags & !Odometry::FIX != 0 {
            return Err(format!("flags {:#x} has unknown bits", self.flags));
        }
        let Some(fix) = self.fix() else {
            return Ok(());
        };
        finite("the fix's x_m", fix.x_m)?;
        finite("the fix's y_m", fix.y_m)?;
        finite("the fix's theta_rad", fix.theta_rad)
    }
}

impl Wire for TruthHeader {
    fn check(&self) -> Result<(), String> {
        if self.robots as usize > MAX_AGENTS {
            return Err(format!("{} robots, over {MAX_AGENTS}", self.robots));
        }
        Ok(())
    }
}

impl WireSlice for TruthHeader {
    type Element = Pose;

    fn check_elements(&self, poses: &[Pose]) -> Result<(), String> {
        same_count("robots", self.robots, poses.len())?;
        for p in poses {
            finite("a pose's x_m", p.x_m)?;
            finite("a pose's y_m", p.y_m)?;
            finite("a pose's theta_rad", p.theta_rad)?;
        }
        Ok(())
    }
}

impl Wire for Estimate {
    fn check(&self) -> Result<(), String> {
        agent("agent", self.agent)?;
        finite("pose x_m", self.pose.x_m)?;
        finite("pose y_m", self.pose.y_m)
    }
}

/// A batch's header: its first robot is one, and it holds no more elements than a swarm.
fn batch_header(first: u32, count: u32) -> Result<(), String> {
    agent("first", first)?;
    if count as usize > MAX_AGENTS {
        return Err(format!("count {count} is over {MAX_AGENTS}"));
    }
    Ok(())
}

/// A batch's elements: as many as the header says, each sound, none for a robot before the
/// process's first.
fn batch_elements<E: Wire>(
    (first, count): (u32, u32),
    elements: &[E],
    robot: impl Fn(&E) -> u32,
) -> Result<(), String> {
    same_count("count", count, elements.len())?;
    for e in elements {
        e.check()?;
        if robot(e) < first {
            return Err(format!(
                "robot {} before the batch's first, {first}",
                robot(e)
            ));
        }
    }
    Ok(())
}

impl Wire for WheelsHeader {
    fn check(&self) -> Result<(), String> {
        batch_header(self.first, self.count)
    }
}

impl WireSlice for WheelsHeader {
    type Element = WheelCommand;

    fn check_elements(&self, commands: &[WheelCommand]) -> Result<(), String> {
        batch_elements((self.first, self.count), commands, |c| c.agent)
    }
}

impl Wire for OdometryHeader {
    fn check(&self) -> Result<(), String> {
        batch_header(self.first, self.count)
    }
}

impl WireSlice for OdometryHeader {
    type Element = Odometry;

    fn check_elements(&self, readings: &[Odometry]) -> Result<(), String> {
        batch_elements((self.first, self.count), readings, |o| o.agent)
    }
}

impl Wire for MapHeader {
    fn check(&self) -> Result<(), String> {
        agent("agent", self.agent)
    }
}

impl WireSlice for MapHeader {
    type Element = f32;

    /// Any activation goes: a viewer draws what it gets, and nothing decides by it.
    fn check_elements(&self, _: &[f32]) -> Result<(), String> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msg::{Decision, Pose};

    #[test]
    fn a_payload_comes_back_from_its_bytes() {
        let c = Candidate {
            round: 7,
            agent: 3,
            priority: 2.0,
            speed: 0.5,
            ..Candidate::default()
        };
        let mut back = Candidate::default();
        back.assign(c.bytes()).unwrap();
        assert_eq!(back, c);
        assert_eq!(Candidate::wire_name(), "hnav::Candidate");
    }

    #[test]
    fn a_batch_of_another_process_or_miscounted_is_refused() {
        let c = |agent| WheelCommand {
            agent,
            ..WheelCommand::default()
        };
        let h = WheelsHeader { first: 4, count: 2 };
        assert_eq!(h.check_elements(&[c(4), c(5)]), Ok(()));
        assert_eq!(
            h.check_elements(&[c(4), c(3)]).unwrap_err(),
            "robot 3 before the batch's first, 4"
        );
        assert_eq!(
            h.check_elements(&[c(4)]).unwrap_err(),
            "count 2 but 1 elements follow"
        );
        let mut bad = c(5);
        bad.left_rad_s = f64::NAN;
        assert!(h.check_elements(&[c(4), bad]).is_err());
        let far = OdometryHeader {
            first: MAX_AGENTS as u32,
            count: 0,
        };
        assert!(far.check().is_err());
    }

    #[test]
    fn bytes_of_the_wrong_size_or_range_are_refused() {
        let mut c = Candidate::default();
        assert_eq!(
            c.assign(&[0u8; 39]),
            Err(WireError::Size {
                type_name: "hnav::Candidate",
                size: 40,
                len: 39
            })
        );
        let bad = Candidate {
            agent: MAX_AGENTS as u32,
            ..Candidate::default()
        };
        let e = c.assign(bad.bytes()).unwrap_err().to_string();
        assert_eq!(e, "hnav::Candidate: agent 4096 is not below 4096");
        let nan = Candidate {
            speed: f32::NAN,
            ..Candidate::default()
        };
        assert!(c.assign(nan.bytes()).is_err());

        let header = CommitHeader {
            round: 1,
            count: 1,
            term: 0,
        };
        let bad = [Decision {
            verdict: 200,
            ..Decision::default()
        }];
        let e = header.check_elements(&bad).unwrap_err();
        assert!(e.contains("verdict 200"), "{e}");
        let e = header.check_elements(&[]).unwrap_err();
        assert_eq!(e, "count 1 but 0 elements follow");

        let l = Lifecycle {
            role: 9,
            ..Lifecycle::default()
        };
        assert!(Lifecycle::default().assign(l.bytes()).is_err());

        let t = TruthHeader {
            robots: 1,
            ..TruthHeader::default()
        };
        let inf = [Pose {
            x_m: f64::INFINITY,
            ..Pose::default()
        }];
        assert!(t.check_elements(&inf).is_err());
        assert!(t.check_elements(&[Pose::default()]).is_ok());
    }

    #[test]
    fn a_slice_comes_back_from_its_bytes_and_a_short_one_is_refused() {
        let header = CommitHeader {
            round: 3,
            count: 2,
            term: 1,
        };
        let decisions = [
            Decision {
                agent: 0,
                ..Decision::default()
            },
            Decision {
                agent: 1,
                cell: 7,
                verdict: Verdict::Accept as u8,
                ..Decision::default()
            },
        ];
        // As a link carries it, one byte off any alignment.
        let mut wire = [0u8; 1 + 16 + 32];
        wire[1..17].copy_from_slice(header.bytes());
        wire[17..].copy_from_slice(bytemuck::cast_slice(&decisions));
        let (h, rest) = CommitHeader::from_wire(&wire[1..]).unwrap();
        assert_eq!(h, header);
        let mut out = [Decision::default(); 2];
        h.elements_from_wire(rest, &mut out).unwrap();
        assert_eq!(out, decisions);
        let e = CommitHeader::from_wire(&wire[1..41])
            .unwrap_err()
            .to_string();
        assert!(e.contains("40 bytes are no 16-byte header"), "{e}");
        let (h, rest) = CommitHeader::from_wire(&wire[1..33]).unwrap();
        let e = h.elements_from_wire(rest, &mut out[..1]).unwrap_err();
        assert!(
            e.to_string().contains("count 2 but 1 elements follow"),
            "{e}"
        );
    }
}
