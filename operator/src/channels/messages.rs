//! One JSON message per thing shown, in the shapes of [`super::schemas`]: poses and grids
//! as Foxglove's well-known schemas, decisions with their verdicts and kinds by name, cells
//! as `[x, y]` (`null` for none).

use base64::Engine as _;
use serde_json::{json, Value};

use crate::recording::{MapSnapshot, PoseSample};
use hnav_runtime::consensus_log::LoggedDecision;
use hnav_runtime::grid::Grid;
use hnav_runtime::msg::{ConflictKind, Verdict, NO_CELL};

/// The frame every pose and grid is in.
pub const FRAME: &str = "map";
/// `log10_activation` of a neuron at exactly 0 (below the smallest `f32`).
pub(crate) const LOG10_OF_ZERO: f32 = -46.0;
pub(crate) const NUMERIC_UINT8: u8 = 1;
pub(crate) const NUMERIC_FLOAT32: u8 = 7;
pub(crate) const DIRECTIONS: [&str; 8] = ["N", "NE", "E", "SE", "S", "SW", "W", "NW"];

pub(crate) fn stamp(t_ns: u64) -> Value {
    json!({"sec": t_ns / 1_000_000_000, "nsec": t_ns % 1_000_000_000})
}

pub(crate) fn cell(index: u32, width: u32) -> Value {
    if index == NO_CELL || width == 0 {
        Value::Null
    } else {
        json!([index % width, index / width])
    }
}

pub(crate) fn decision_message(t: u64, round: u64, d: &LoggedDecision, width: u32) -> Value {
    let name = |n: Option<&str>, code: u8| n.map_or_else(|| code.to_string(), str::to_string);
    json!({
        "timestamp": stamp(t),
        "round": round,
        "agent": d.agent,
        "verdict": name(Verdict::from_u8(d.verdict).map(Verdict::name), d.verdict),
        "kind": name(ConflictKind::from_u8(d.kind).map(ConflictKind::name), d.kind),
        "refused": (0..8).filter(|b| d.refused & (1 << b) != 0).map(|b| DIRECTIONS[b]).collect::<Vec<_>>(),
        "cell": cell(d.cell, width),
        "waypoint": cell(d.waypoint, width),
    })
}

pub(crate) fn pose_message(s: &PoseSample) -> Value {
    let pose = pose(
        f64::from(s.x_m),
        f64::from(s.y_m),
        0.0,
        f64::from(s.theta_rad),
    );
    json!({"timestamp": stamp(s.t_ns), "frame_id": FRAME, "pose": pose})
}

/// A `foxglove.Pose` at `(x, y, z)` turned `theta` about z.
pub(crate) fn pose(x: f64, y: f64, z: f64, theta: f64) -> Value {
    let half = theta / 2.0;
    json!({
        "position": {"x": x, "y": y, "z": z},
        "orientation": {"x": 0.0, "y": 0.0, "z": half.sin(), "w": half.cos()}
    })
}

/// `g` as a `foxglove.Grid` of field `occupied` (1 = blocked) at `t_ns`.
pub(crate) fn occupancy(g: &Grid, t_ns: u64, cell_m: f64) -> Value {
    let occupied: Vec<u8> = g.blocked().iter().map(|&b| u8::from(b)).collect();
    let fields = [("occupied", 0, NUMERIC_UINT8)];
    grid_message(t_ns, (g.width(), cell_m), 1, &fields, &occupied)
}

/// A `foxglove.Grid` at the frame's origin: `columns` cells of `cell_m` a row, each
/// `cell_stride` bytes of `data` holding `fields` (name, offset, numeric type).
pub(crate) fn grid_message(
    t_ns: u64,
    (columns, cell_m): (u32, f64),
    cell_stride: u32,
    fields: &[(&str, u32, u8)],
    data: &[u8],
) -> Value {
    json!({
        "timestamp": stamp(t_ns),
        "frame_id": FRAME,
        "pose": {
            "position": {"x": 0.0, "y": 0.0, "z": 0.0},
            "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}
        },
        "column_count": columns,
        "cell_size": {"x": cell_m, "y": cell_m},
        "row_stride": columns * cell_stride,
        "cell_stride": cell_stride,
        "fields": fields.iter().map(|(name, offset, ty)| json!({"name": name, "offset": offset, "type": ty})).collect::<Vec<_>>(),
        "data": base64::engine::general_purpose::STANDARD.encode(data),
    })
}

/// A neural map as a grid of its activations and their log10, since the wave front decays
/// geometrically and a linear colour scale shows only the cells next to the target.
pub(crate) fn neural_map_message(snap: &MapSnapshot, cell_m: f64) -> Value {
    let mut data = Vec::with_capacity(snap.values.len() * 8);
    for &v in &snap.values {
        let log = if v > 0.0 { v.log10() } else { LOG10_OF_ZERO };
        data.extend_from_slice(&v.to_le_bytes());
        data.extend_from_slice(&log.to_le_bytes());
    }
    let fields = [
        ("activation", 0, NUMERIC_FLOAT32),
        ("log10_activation", 4, NUMERIC_FLOAT32),
    ];
    grid_message(snap.t_ns, (snap.header.width, cell_m), 8, &fields, &data)
}
