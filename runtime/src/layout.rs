//! The layout table of every payload: what a client in another language (the Python client's
//! `ctypes` mirrors, `clients/python/hnav/msg.py`) must reproduce byte for byte, and which
//! topic carries which type. Above both [`crate::msg`] and [`crate::topics`], which it
//! joins.
//!
//! Printed by the hidden `hnav layout --json`; the Python client's layout test compares its
//! mirrors with it field by field (`tests/tests/python_client.rs`).

use core::mem::{align_of, offset_of, size_of};

use iceoryx2::prelude::ZeroCopySend;
use serde::Serialize;

use crate::msg::{
    Candidate, CommitHeader, Decision, Estimate, Heartbeat, Lifecycle, MapHeader, MoverPlace,
    MoversHeader, Odometry, OdometryHeader, Pose, Progress, Sighting, TruthHeader, View,
    ViewsHeader, WheelCommand, WheelsHeader, WorldHeader, MAX_AGENTS,
};
use crate::topics;

/// One field of a payload.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct FieldLayout {
    /// The field's name, as in the Rust struct.
    pub name: &'static str,
    /// Its byte offset in the struct.
    pub offset: usize,
    /// Its size in bytes.
    pub size: usize,
    /// Its Rust type, as written in the struct (`u32`, `[u32; 32]`).
    pub ty: &'static str,
}

/// One payload type.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct TypeLayout {
    /// The Rust name (`Candidate`).
    pub name: &'static str,
    /// The iceoryx2 type name every process and client must use (`hnav::Candidate`).
    pub type_name: &'static str,
    /// Size in bytes.
    pub size: usize,
    /// Alignment in bytes.
    pub align: usize,
    /// Every field, in declaration order.
    pub fields: Vec<FieldLayout>,
}

/// One topic's payload and user header, by iceoryx2 type name.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct TopicLayout {
    /// The topic (`commit`, `map/<i>` for one per agent), below `hnav/<run-id>/`.
    pub topic: &'static str,
    /// The payload's type name; of the element for a slice topic.
    pub payload: &'static str,
    /// Whether the payload is a slice of `payload` elements.
    pub slice: bool,
    /// The user header's type name (`()` for none).
    pub user_header: &'static str,
}

/// The whole table: payload types and topics.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Layouts {
    /// [`MAX_AGENTS`]: the largest run, and the bound on an agent index a reader accepts.
    pub max_agents: usize,
    /// Every payload type.
    pub types: Vec<TypeLayout>,
    /// Every topic.
    pub topics: Vec<TopicLayout>,
}

/// The iceoryx2 type name of `T`, the one its services are created with.
fn type_name_of<T: ZeroCopySend + ?Sized>() -> &'static str {
    // SAFETY: `type_name` only returns a constant string; what its safety contract asks (the
    // same layout in every language) is what this table is for.
    unsafe { <T as ZeroCopySend>::type_name() }
}

/// The layout of `$t`, with each field's type checked against the struct at compile time.
macro_rules! layout {
    ($t:ident { $($f:ident : $ft:ty),* $(,)? }) => {{
        $(let _: fn(&$t) -> &$ft = |v| &v.$f;)*
        TypeLayout {
            name: stringify!($t),
            type_name: type_name_of::<$t>(),
            size: size_of::<$t>(),
            align: align_of::<$t>(),
            fields: vec![$(FieldLayout {
                name: stringify!($f),
                offset: offset_of!($t, $f),
                size: size_of::<$ft>(),
                ty: stringify!($ft),
            }),*],
        }
    }};
}

/// The layout table of every payload and topic.
pub fn layouts() -> Layouts {
    let types = vec![
        layout!(Candidate {
            round: u64,
            agent: u32,
            current: u32,
            next: u32,
            probable: u32,
            priority: f32,
            speed: f32,
            flags: u32,
            reserved: u32
        }),
        layout!(Decision {
            agent: u32,
            verdict: u8,
            refused: u8,
            kind: u8,
            reserved: u8,
            cell: u32,
            waypoint: u32
        }),
        layout!(CommitHeader {
            round: u64,
            count: u32,
            term: u32
        }),
        layout!(Progress {
            round: u64,
            agents: u32,
            at_goal: u32,
            conflicts: u32,
            replans: u32,
            done: u8,
            leader: u8,
            reserved: [u8; 6]
        }),
        layout!(WheelCommand {
            period: u64,
            agent: u32,
            flags: u32,
            left_rad_s: f64,
            right_rad_s: f64
        }),
        layout!(Odometry {
            sim_time_ns: u64,
            period: u64,
            agent: u32,
            flags: u32,
            ticks_left: i64,
            ticks_right: i64,
            fix: Pose
        }),
        layout!(Pose {
            x_m: f64,
            y_m: f64,
            theta_rad: f64
        }),
        layout!(TruthHeader {
            sim_time_ns: u64,
            period: u64,
            robots: u32,
            collisions: u32
        }),
        layout!(Estimate {
            sim_time_ns: u64,
            agent: u32,
            reserved: u32,
            pose: Pose
        }),
        layout!(Lifecycle {
            time_ns: u64,
            pid: u32,
            index: u32,
            role: u8,
            event: u8,
            reason: u8,
            reserved: u8,
            restarts: u32
        }),
        layout!(Heartbeat {
            t_ns: u64,
            seq: u64,
            pid: u32,
            index: u32,
            role: u8,
            reserved: [u8; 7]
        }),
        layout!(MapHeader {
            round: u64,
            agent: u32,
            width: u32,
            height: u32,
            iterations: u32,
            target: u32,
            activation: u8,
            reserved: [u8; 3]
        }),
        layout!(View {
            sim_time_ns: u64,
            period: u64,
            agent: u32,
            x0: u32,
            y0: u32,
            size: u32,
            seen: [u32; 32],
            blocked: [u32; 32],
            moving: [u32; 32]
        }),
        layout!(Sighting {
            round: u64,
            agent: u32,
            count: u32,
            closed: u32,
            reserved: u32,
            cells: [u32; 32]
        }),
        layout!(WorldHeader {
            round: u64,
            closed: u32,
            opened: u32,
            to: u32,
            reserved: u32
        }),
        layout!(MoversHeader {
            sim_time_ns: u64,
            period: u64
        }),
        layout!(MoverPlace {
            mover: u32,
            reserved: u32,
            pose: Pose
        }),
        layout!(WheelsHeader {
            first: u32,
            count: u32
        }),
        layout!(OdometryHeader {
            first: u32,
            count: u32
        }),
        layout!(ViewsHeader {
            first: u32,
            count: u32
        }),
    ];
    let fixed = |topic, payload| TopicLayout {
        topic,
        payload,
        slice: false,
        user_header: type_name_of::<()>(),
    };
    let sliced = |topic, payload, user_header| TopicLayout {
        topic,
        payload,
        slice: true,
        user_header,
    };
    let topics = vec![
        sliced(
            "wheels/<first>",
            type_name_of::<WheelCommand>(),
            type_name_of::<WheelsHeader>(),
        ),
        sliced(
            "odom/<first>",
            type_name_of::<Odometry>(),
            type_name_of::<OdometryHeader>(),
        ),
        sliced(
            "view/<first>",
            type_name_of::<View>(),
            type_name_of::<ViewsHeader>(),
        ),
        sliced(
            topics::TRUTH,
            type_name_of::<Pose>(),
            type_name_of::<TruthHeader>(),
        ),
        fixed(topics::CANDIDATES, type_name_of::<Candidate>()),
        sliced(
            topics::COMMIT,
            type_name_of::<Decision>(),
            type_name_of::<CommitHeader>(),
        ),
        sliced(
            "map/<i>",
            type_name_of::<f32>(),
            type_name_of::<MapHeader>(),
        ),
        fixed(topics::PROGRESS, type_name_of::<Progress>()),
        fixed(topics::READY, type_name_of::<Lifecycle>()),
        fixed(topics::LIFECYCLE, type_name_of::<Lifecycle>()),
        fixed(topics::HEARTBEAT, type_name_of::<Heartbeat>()),
        fixed(topics::ESTIMATE, type_name_of::<Estimate>()),
        fixed(topics::SIGHTINGS, type_name_of::<Sighting>()),
        sliced(
            topics::WORLD,
            type_name_of::<u32>(),
            type_name_of::<WorldHeader>(),
        ),
        sliced(
            topics::MOVERS,
            type_name_of::<MoverPlace>(),
            type_name_of::<MoversHeader>(),
        ),
    ];
    Layouts {
        max_agents: MAX_AGENTS,
        types,
        topics,
    }
}

impl Layouts {
    /// The table as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// The table as text, one line per type (as in the [`msg`](crate::msg) docs).
    pub fn render(&self) -> String {
        let mut out = String::new();
        for t in &self.types {
            let fields: Vec<String> = t
                .fields
                .iter()
                .map(|f| format!("{} {} {}", f.offset, f.name, f.ty))
                .collect();
            out += &format!(
                "{} ({}) size {} align {}: {}\n",
                t.name,
                t.type_name,
                t.size,
                t.align,
                fields.join(", ")
            );
        }
        for t in &self.topics {
            let payload = if t.slice {
                format!("[{}]", t.payload)
            } else {
                t.payload.to_string()
            };
            out += &format!("topic {}: {payload}, header {}\n", t.topic, t.user_header);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_byte_of_every_type_is_a_listed_field() {
        // The payloads have no implicit padding (see the msg docs), so fields that tile the
        // struct are all of its fields: a field missing from the table leaves a hole.
        for t in layouts().types {
            let mut end = 0;
            for f in &t.fields {
                assert_eq!(
                    f.offset, end,
                    "{}.{} does not follow the field before",
                    t.name, f.name
                );
                end = f.offset + f.size;
            }
            assert_eq!(end, t.size, "{}: fields end at {end} of {}", t.name, t.size);
        }
    }

    #[test]
    fn type_names_are_the_hnav_ones() {
        let l = layouts();
        for t in &l.types {
            assert_eq!(t.type_name, format!("hnav::{}", t.name));
        }
        let map = l.topics.iter().find(|t| t.topic == "map/<i>").unwrap();
        assert_eq!((map.payload, map.user_header), ("f32", "hnav::MapHeader"));
        let json: serde_json::Value = serde_json::from_str(&l.to_json()).unwrap();
        assert_eq!(json["types"].as_array().unwrap().len(), 20);
    }
}
