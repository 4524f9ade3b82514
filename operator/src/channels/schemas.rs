//! The JSON schemas of the channels (schema encoding `jsonschema`), live and exported.
//!
//! Poses, grids, the scene and the log use Foxglove's well-known schemas by name and shape
//! (`foxglove.PoseInFrame`, `foxglove.Grid`, `foxglove.SceneUpdate`, `foxglove.Log`: the
//! fields HNAV fills, named as in Foxglove's JSON schemas), so Foxglove's 3D and Log panels
//! show them without configuration; the rest have schemas of their own (`hnav.*`), which the
//! Raw Messages and Plot panels read.

use serde_json::{json, Value};

/// `foxglove.PoseInFrame`.
pub const POSE_IN_FRAME: &str = "foxglove.PoseInFrame";
/// `foxglove.Grid`.
pub const GRID: &str = "foxglove.Grid";
/// `foxglove.SceneUpdate`: robots, goals, routes and conflicts.
pub const SCENE_UPDATE: &str = "foxglove.SceneUpdate";
/// `foxglove.Log`: decisions and process events as log lines.
pub const LOG: &str = "foxglove.Log";
/// One robot's speed (and energy, when a source has it) for the Plot panel.
pub const ROBOT_STATS: &str = "hnav.RobotStats";
/// One round's committed cells.
pub const COMMITTED_CELLS: &str = "hnav.CommittedCells";
/// One decision of one round.
pub const DECISION: &str = "hnav.Decision";
/// One global replan.
pub const REPLAN: &str = "hnav.Replan";
/// One process event: a process down, restarted or lost.
pub const LIFECYCLE: &str = "hnav.Lifecycle";

fn time() -> Value {
    json!({
        "type": "object",
        "title": "time",
        "properties": {
            "sec": {"type": "integer", "minimum": 0},
            "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}
        },
        "description": "Simulated time since the run's Start"
    })
}

fn pose() -> Value {
    let number = json!({"type": "number"});
    json!({
        "title": "foxglove.Pose",
        "type": "object",
        "properties": {
            "position": {
                "title": "foxglove.Vector3",
                "type": "object",
                "properties": {"x": number, "y": number, "z": number},
                "required": ["x", "y", "z"]
            },
            "orientation": {
                "title": "foxglove.Quaternion",
                "type": "object",
                "properties": {"x": number, "y": number, "z": number, "w": number},
                "required": ["x", "y", "z", "w"]
            }
        },
        "required": ["position", "orientation"]
    })
}

/// A cell as `[x, y]` (column, row), or `null`.
fn cell() -> Value {
    json!({
        "type": ["array", "null"],
        "items": {"type": "integer", "minimum": 0},
        "minItems": 2,
        "maxItems": 2,
        "description": "[x, y]: 0-based column and row, origin top-left"
    })
}

fn color() -> Value {
    let n = json!({"type": "number", "minimum": 0, "maximum": 1});
    json!({
        "title": "foxglove.Color",
        "type": "object",
        "properties": {"r": n, "g": n, "b": n, "a": n},
        "required": ["r", "g", "b", "a"]
    })
}

fn vector3() -> Value {
    let number = json!({"type": "number"});
    json!({
        "title": "foxglove.Vector3",
        "type": "object",
        "properties": {"x": number, "y": number, "z": number},
        "required": ["x", "y", "z"]
    })
}

/// `foxglove.SceneEntity`, with the primitives HNAV draws (cubes, lines, texts).
fn scene_entity() -> Value {
    let array = |title: &str, properties: Value| json!({"type": "array", "items": {"title": title, "type": "object", "properties": properties}});
    json!({
        "title": "foxglove.SceneEntity",
        "type": "object",
        "properties": {
            "timestamp": time(),
            "frame_id": {"type": "string"},
            "id": {"type": "string"},
            "lifetime": {
                "type": "object",
                "title": "duration",
                "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}
            },
            "frame_locked": {"type": "boolean"},
            "metadata": array("foxglove.KeyValuePair", json!({"key": {"type": "string"}, "value": {"type": "string"}})),
            "cubes": array("foxglove.CubePrimitive", json!({"pose": pose(), "size": vector3(), "color": color()})),
            "lines": array("foxglove.LinePrimitive", json!({
                "type": {"title": "foxglove.LineType", "type": "integer", "description": "0 line strip, 1 line loop, 2 line list"},
                "pose": pose(),
                "thickness": {"type": "number"},
                "scale_invariant": {"type": "boolean"},
                "points": {"type": "array", "items": vector3()},
                "color": color()
            })),
            "texts": array("foxglove.TextPrimitive", json!({
                "pose": pose(),
                "billboard": {"type": "boolean"},
                "font_size": {"type": "number"},
                "scale_invariant": {"type": "boolean"},
                "color": color(),
                "text": {"type": "string"}
            }))
        }
    })
}

/// The schema named `name`, as bytes for the MCAP schema record and the WebSocket advertise.
pub fn schema(name: &str) -> Vec<u8> {
    let body = match name {
        SCENE_UPDATE => json!({
            "title": SCENE_UPDATE,
            "description": "An update to the entities displayed in a 3D scene",
            "type": "object",
            "properties": {
                "deletions": {
                    "type": "array",
                    "items": {
                        "title": "foxglove.SceneEntityDeletion",
                        "type": "object",
                        "properties": {
                            "timestamp": time(),
                            "type": {"title": "foxglove.SceneEntityDeletionType", "type": "integer", "description": "0 matching id, 1 all"},
                            "id": {"type": "string"}
                        }
                    }
                },
                "entities": {"type": "array", "items": scene_entity()}
            }
        }),
        LOG => json!({
            "title": LOG,
            "description": "A log message",
            "type": "object",
            "properties": {
                "timestamp": time(),
                "level": {"title": "foxglove.LogLevel", "type": "integer", "description": "0 unknown, 1 debug, 2 info, 3 warning, 4 error, 5 fatal"},
                "message": {"type": "string"},
                "name": {"type": "string", "description": "the process or agent the line is about"},
                "file": {"type": "string"},
                "line": {"type": "integer", "minimum": 0}
            }
        }),
        ROBOT_STATS => json!({
            "title": ROBOT_STATS,
            "description": "One robot's ground-truth speed, for the Plot panel",
            "type": "object",
            "properties": {
                "timestamp": time(),
                "robot": {"type": "integer"},
                "speed_m_s": {"type": "number", "description": "ground-truth speed over the last sampling interval, m/s"},
                "energy_j": {"type": ["number", "null"], "description": "motor energy so far, J; null where the source has none (no topic carries it live)"}
            }
        }),
        POSE_IN_FRAME => json!({
            "title": POSE_IN_FRAME,
            "description": "A timestamped pose for an object or reference frame in 3D space",
            "type": "object",
            "properties": {
                "timestamp": time(),
                "frame_id": {"type": "string"},
                "pose": pose()
            }
        }),
        GRID => json!({
            "title": GRID,
            "description": "A 2D grid of data",
            "type": "object",
            "properties": {
                "timestamp": time(),
                "frame_id": {"type": "string"},
                "pose": pose(),
                "column_count": {"type": "integer", "minimum": 0},
                "cell_size": {
                    "title": "foxglove.Vector2",
                    "type": "object",
                    "properties": {"x": {"type": "number"}, "y": {"type": "number"}},
                    "required": ["x", "y"]
                },
                "row_stride": {"type": "integer", "minimum": 0},
                "cell_stride": {"type": "integer", "minimum": 0},
                "fields": {
                    "type": "array",
                    "items": {
                        "title": "foxglove.PackedElementField",
                        "type": "object",
                        "properties": {
                            "name": {"type": "string"},
                            "offset": {"type": "integer", "minimum": 0},
                            "type": {"title": "foxglove.NumericType", "type": "integer"}
                        }
                    }
                },
                "data": {"type": "string", "contentEncoding": "base64"}
            }
        }),
        COMMITTED_CELLS => json!({
            "title": COMMITTED_CELLS,
            "description": "The cells one round's commit gave the agents (accepted moves and replans with a cell)",
            "type": "object",
            "properties": {
                "timestamp": time(),
                "round": {"type": "integer"},
                "cells": {
                    "type": "array",
                    "items": {
                        "type": "object",
                        "properties": {"agent": {"type": "integer"}, "cell": cell()}
                    }
                }
            }
        }),
        DECISION => json!({
            "title": DECISION,
            "description": "One agent's decision in one round, as the consensus log holds it",
            "type": "object",
            "properties": {
                "timestamp": time(),
                "round": {"type": "integer"},
                "agent": {"type": "integer"},
                "verdict": {"enum": ["accept", "block", "hold", "replan"]},
                "kind": {"type": "string", "description": "the conflict kind (none, crossing, head-on, ...)"},
                "refused": {"type": "array", "items": {"enum": ["N", "NE", "E", "SE", "S", "SW", "W", "NW"]}},
                "cell": cell(),
                "waypoint": cell()
            }
        }),
        REPLAN => json!({
            "title": REPLAN,
            "description": "A global replan of one agent's route",
            "type": "object",
            "properties": {
                "timestamp": time(),
                "round": {"type": "integer"},
                "agent": {"type": "integer"},
                "planner": {"type": "string"},
                "found": {"type": "boolean"},
                "waypoints": {"type": "array", "items": cell()}
            }
        }),
        LIFECYCLE => json!({
            "title": LIFECYCLE,
            "description": "A process of the run down, restarted or lost, as the consensus log holds it",
            "type": "object",
            "properties": {
                "timestamp": time(),
                "round": {"type": "integer", "description": "the last round committed when it was logged"},
                "process": {"type": "string", "description": "sim, coordinator, agent-<i> (as hnav ps names it)"},
                "role": {"enum": ["sim", "coordinator", "agent", "bridge"]},
                "index": {"type": "integer", "description": "agent index or replica id, else 0"},
                "event": {"enum": ["down", "restarted", "lost"]},
                "restarts": {"type": "integer", "description": "restarts of the process so far"},
                "cell": cell()
            }
        }),
        other => json!({"title": other, "type": "object"}),
    };
    serde_json::to_vec(&body).unwrap_or_default()
}
