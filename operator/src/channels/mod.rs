//! The Foxglove channels a run is shown on: one set of topics, schemas and message shapes for
//! the live view (`hnav run --foxglove`, `hnav view --foxglove`, the `viewer` module) and the
//! MCAP export (`hnav log export --mcap`, the `export` module), so a run looks the same live
//! and recorded.
//!
//! Every message is JSON (message encoding [`MESSAGE_ENCODING`]) with a JSON schema (schema
//! encoding [`SCHEMA_ENCODING`], [`schemas`]). The channels both write ([`shown`]):
//!
//! | topic | schema | one message per |
//! |---|---|---|
//! | `/map` | `foxglove.Grid` | the map (field `occupied`, 1 = wall), again at each close or open of the scenario's `[[events]]` |
//! | `/scene` | `foxglove.SceneUpdate` | ground-truth sample: robots, goals, routes, conflicts ([`scene`]) |
//! | `/robots/<i>/truth` | `foxglove.PoseInFrame` | ground-truth sample of robot `i` |
//! | `/robots/<i>/stats` | `hnav.RobotStats` | ground-truth sample: robot `i`'s speed |
//! | `/log` | `foxglove.Log` | decision other than "held, nothing asked" (a repeated hold or block once), process down, restarted, lost; the run's start and stop |
//!
//! The export writes more channels from what only a finished run has (the estimates, the
//! neural maps, the log's decisions, replans and process events as `hnav.*`; see `export`).
//!
//! Poses and grids are in one frame, [`FRAME`]: metres, x along columns, y along rows (the
//! sim's frame), z up.

pub(crate) mod messages;
pub mod scene;
pub mod schemas;

pub use messages::FRAME;

/// The message encoding of every channel.
pub const MESSAGE_ENCODING: &str = "json";
/// The schema encoding of every channel.
pub const SCHEMA_ENCODING: &str = "jsonschema";

/// The map.
pub const MAP: &str = "/map";
/// The 3D scene.
pub const SCENE: &str = "/scene";
/// Decisions and process events as log lines.
pub const LOG: &str = "/log";

/// Robot `i`'s ground-truth pose.
pub fn truth(i: usize) -> String {
    format!("/robots/{i}/truth")
}

/// Robot `i`'s speed.
pub fn stats(i: usize) -> String {
    format!("/robots/{i}/stats")
}

/// One channel: its topic and its schema's name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Channel {
    /// The topic.
    pub topic: String,
    /// The schema's name (one of [`schemas`]'s constants).
    pub schema: &'static str,
}

/// The channels of a run of `robots` robots that the live view and the export both write,
/// in the order the table above lists them.
pub fn shown(robots: usize) -> Vec<Channel> {
    let ch = |topic: String, schema| Channel { topic, schema };
    let mut out = vec![
        ch(MAP.into(), schemas::GRID),
        ch(SCENE.into(), schemas::SCENE_UPDATE),
    ];
    for i in 0..robots {
        out.push(ch(truth(i), schemas::POSE_IN_FRAME));
        out.push(ch(stats(i), schemas::ROBOT_STATS));
    }
    out.push(ch(LOG.into(), schemas::LOG));
    out
}

/// One message for one channel.
#[derive(Debug, Clone, PartialEq)]
pub struct Message {
    /// The channel's topic.
    pub topic: String,
    /// Its schema's name.
    pub schema: &'static str,
    /// Log time: simulated time, ns since the run's start.
    pub t_ns: u64,
    /// The message.
    pub body: serde_json::Value,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shown_channel_has_a_schema_of_its_own_name() {
        for c in shown(2) {
            let s: serde_json::Value = serde_json::from_slice(&schemas::schema(c.schema)).unwrap();
            assert_eq!(s["title"], c.schema, "{}", c.topic);
            assert!(
                s["properties"].is_object(),
                "{}: a schema of fields",
                c.topic
            );
        }
        assert_eq!(shown(3).len(), 3 + 2 * 3);
    }
}
