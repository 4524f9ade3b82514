//! `[ros2]`: the run as ROS 2 topics (`hnav run --ros2`, `hnav-ros2`; see
//! `docs/reference/ros2.md`). A scenario with the section publishes as `--ros2` does.
//!
//! ```toml
//! [ros2]
//! domain_id = 0                 # ROS_DOMAIN_ID, in [0, 232]
//! namespace = "fleet"           # the robots' topics under /fleet/robot_<i>/...; default none
//! router = "tcp/localhost:7447" # the Zenoh router to join (tcp/ or udp/); default
//!                               # rmw_zenoh's, which `hnav run` starts if none answers
//! # With [sim] kind = "ros2" (robots outside HNAV) only:
//! odometry = "joint_states"     # or "odom": where each robot's motion comes from
//! wheel_joints = ["left_wheel_joint", "right_wheel_joint"]  # names in joint_states
//! silence_s = 1.0               # a robot not heard for this long is down
//! ```
//!
//! Like `[record]`, the section decides what is published about a run, not what the run
//! does, so the scenario hash leaves it out; with robots outside HNAV (the only runs the last
//! three keys touch) a run is not reproduced from its scenario anyway.

use serde::Deserialize;
use toml::Spanned;

use super::error::ScenarioError;
use super::lines::Lines;

/// `[ros2]` as `serde` sees it.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRos2 {
    pub domain_id: Option<Spanned<i64>>,
    pub namespace: Option<Spanned<String>>,
    pub router: Option<Spanned<String>>,
    pub odometry: Option<OdometrySource>,
    pub wheel_joints: Option<Spanned<Vec<String>>>,
    pub silence_s: Option<Spanned<f64>>,
}

/// Where the motion of a robot outside HNAV comes from (`[ros2] odometry`).
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OdometrySource {
    /// `/robot_<i>/joint_states` (`sensor_msgs/msg/JointState`): the two wheels' positions,
    /// as ros2_control's joint state broadcaster publishes them beside a
    /// `diff_drive_controller`; HNAV's dead reckoning turns them into a pose as it does Hall
    /// ticks.
    #[default]
    JointStates,
    /// `/robot_<i>/odom` (`nav_msgs/msg/Odometry`): the robot's own odometry; HNAV takes the
    /// motion between two messages (the odom frame's origin is the robot's, not the map's).
    Odom,
}

/// The validated `[ros2]` section.
#[derive(Clone, PartialEq, Debug)]
pub struct Ros2Params {
    /// `ROS_DOMAIN_ID`.
    pub domain_id: u32,
    /// The robots' topics' prefix without slashes at either end (`fleet`, `site/a`); empty
    /// for none.
    pub namespace: String,
    /// The Zenoh router's endpoint; `None`: rmw_zenoh's default, `tcp/localhost:7447`.
    pub router: Option<String>,
    /// Where a robot outside HNAV's motion comes from.
    pub odometry: OdometrySource,
    /// The names of the left and right wheel joints in `joint_states`.
    pub wheel_joints: [String; 2],
    /// A robot outside HNAV not heard for this long is down, seconds.
    pub silence_s: f64,
}

impl Default for Ros2Params {
    fn default() -> Self {
        Ros2Params {
            domain_id: 0,
            namespace: String::new(),
            router: None,
            odometry: OdometrySource::JointStates,
            wheel_joints: ["left_wheel_joint".into(), "right_wheel_joint".into()],
            silence_s: 1.0,
        }
    }
}

impl Ros2Params {
    /// The largest domain id ROS 2 documents.
    pub const MAX_DOMAIN_ID: u32 = 232;
}

/// Validates `[ros2]`; `None` without the section.
pub(super) fn build_ros2(
    raw: Option<RawRos2>,
    lines: &Lines<'_>,
) -> Result<Option<Ros2Params>, ScenarioError> {
    let Some(r) = raw else { return Ok(None) };
    let bad = |s: &Spanned<String>, key: &str, problem: String| ScenarioError::InvalidParameter {
        at: lines.at(s),
        key: key.into(),
        problem,
    };
    let domain = lines.in_range(
        &r.domain_id,
        "ros2.domain_id",
        (0, i64::from(Ros2Params::MAX_DOMAIN_ID)),
        "",
    )?;
    let namespace = match &r.namespace {
        None => String::new(),
        Some(ns) => {
            let trimmed = ns.get_ref().trim_matches('/');
            if !trimmed.is_empty() && !trimmed.split('/').all(is_ros_name_token) {
                return Err(bad(
                    ns,
                    "ros2.namespace",
                    format!(
                        "must be ROS name tokens (letters, digits, '_', not starting with a digit) joined by '/', got {:?}",
                        ns.get_ref()
                    ),
                ));
            }
            trimmed.to_string()
        }
    };
    let router = match &r.router {
        None => None,
        Some(e) => {
            let v = e.get_ref();
            let ok = ["tcp/", "udp/"]
                .iter()
                .any(|p| v.strip_prefix(p).is_some_and(|a| a.contains(':')));
            if !ok {
                return Err(bad(
                    e,
                    "ros2.router",
                    format!("must be a Zenoh endpoint tcp/HOST:PORT or udp/HOST:PORT, got {v:?}"),
                ));
            }
            Some(v.clone())
        }
    };
    let d = Ros2Params::default();
    let wheel_joints = match &r.wheel_joints {
        None => d.wheel_joints,
        Some(w) => match w.get_ref().as_slice() {
            [l, r] if !l.is_empty() && !r.is_empty() && l != r => [l.clone(), r.clone()],
            other => {
                return Err(ScenarioError::InvalidParameter {
                    at: lines.at(w),
                    key: "ros2.wheel_joints".into(),
                    problem: format!(
                        "must be two different joint names, [left, right], got {other:?}"
                    ),
                })
            }
        },
    };
    let silence_s = match &r.silence_s {
        None => d.silence_s,
        Some(v) if v.get_ref().is_finite() && *v.get_ref() > 0.0 => *v.get_ref(),
        Some(v) => {
            return Err(ScenarioError::InvalidParameter {
                at: lines.at(v),
                key: "ros2.silence_s".into(),
                problem: format!("must be a positive number of seconds, got {}", v.get_ref()),
            })
        }
    };
    Ok(Some(Ros2Params {
        domain_id: domain.map_or(0, |d| d as u32),
        namespace,
        router,
        odometry: r.odometry.unwrap_or_default(),
        wheel_joints,
        silence_s,
    }))
}

/// A ROS name token: letters, digits and `_`, not empty, not starting with a digit.
fn is_ros_name_token(t: &str) -> bool {
    t.chars().next().is_some_and(|c| !c.is_ascii_digit())
        && t.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Scenario;

    fn parse(ros2: &str) -> Result<Scenario, ScenarioError> {
        let text = format!(
            "name = \"r\"\n[map]\nrows = [\"...\"]\n[[agents]]\nstart = [0, 0]\ngoal = [2, 0]\n\
             [ros2]\n{ros2}\n"
        );
        Scenario::from_str(&text, "r.toml", std::path::Path::new("."))
    }

    #[test]
    fn defaults_and_given_values() {
        assert_eq!(parse("").unwrap().ros2, Some(Ros2Params::default()));
        let s = parse("domain_id = 7\nnamespace = \"/fleet/a/\"\nrouter = \"tcp/10.0.0.1:7447\"")
            .unwrap();
        assert_eq!(
            s.ros2,
            Some(Ros2Params {
                domain_id: 7,
                namespace: "fleet/a".into(),
                router: Some("tcp/10.0.0.1:7447".into()),
                ..Ros2Params::default()
            })
        );
        let none = Scenario::from_str(
            "name = \"r\"\n[map]\nrows = [\"...\"]\n[[agents]]\nstart = [0, 0]\ngoal = [2, 0]\n",
            "r.toml",
            std::path::Path::new("."),
        )
        .unwrap();
        assert_eq!(none.ros2, None);
    }

    #[test]
    fn bad_values_name_their_line() {
        let e = parse("domain_id = 300").unwrap_err().to_string();
        assert_eq!(e, "r.toml:8: ros2.domain_id must be in [0, 232], got 300");
        let e = parse("\nnamespace = \"9lives\"").unwrap_err().to_string();
        assert!(
            e.starts_with("r.toml:9: ros2.namespace must be ROS name tokens"),
            "{e}"
        );
        let e = parse("router = \"localhost:7447\"")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("r.toml:8: ros2.router must be a Zenoh endpoint"),
            "{e}"
        );
        assert!(parse("domain = 3")
            .unwrap_err()
            .to_string()
            .contains("domain"));
    }

    #[test]
    fn the_outside_robots_keys() {
        let s = parse("odometry = \"odom\"\nwheel_joints = [\"l\", \"r\"]\nsilence_s = 0.5")
            .unwrap()
            .ros2
            .unwrap();
        assert_eq!(s.odometry, OdometrySource::Odom);
        assert_eq!(s.wheel_joints, ["l".to_string(), "r".to_string()]);
        assert_eq!(s.silence_s, 0.5);
        let e = parse("wheel_joints = [\"l\", \"l\"]")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("r.toml:8: ros2.wheel_joints must be two different joint names"),
            "{e}"
        );
        let e = parse("\nsilence_s = 0").unwrap_err().to_string();
        assert!(
            e.starts_with("r.toml:9: ros2.silence_s must be a positive"),
            "{e}"
        );
        assert!(parse("odometry = \"gps\"").is_err());
    }

    #[test]
    fn the_section_is_not_hashed() {
        let a = parse("").unwrap();
        let b = parse("domain_id = 3\nnamespace = \"x\"").unwrap();
        assert_eq!(a.scenario_hash(), b.scenario_hash());
    }
}
