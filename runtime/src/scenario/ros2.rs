//! `[ros2]`: the run as ROS 2 topics (`hnav run --ros2`, `hnav-ros2`; see
//! `docs/reference/ros2.md`). A scenario with the section publishes as `--ros2` does.
//!
//! ```toml
//! [ros2]
//! domain_id = 0                 # ROS_DOMAIN_ID, in [0, 232]
//! namespace = "fleet"           # the robots' topics under /fleet/robot_<i>/...; default none
//! router = "tcp/localhost:7447" # the Zenoh router to join (tcp/ or udp/); default
//!                               # rmw_zenoh's, which `hnav run` starts if none answers
//! ```
//!
//! Like `[record]`, the section decides what is published about a run, not what the run
//! does, so the scenario hash leaves it out.

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
}

/// The validated `[ros2]` section.
#[derive(Clone, PartialEq, Eq, Debug, Default)]
pub struct Ros2Params {
    /// `ROS_DOMAIN_ID`.
    pub domain_id: u32,
    /// The robots' topics' prefix without slashes at either end (`fleet`, `site/a`); empty
    /// for none.
    pub namespace: String,
    /// The Zenoh router's endpoint; `None`: rmw_zenoh's default, `tcp/localhost:7447`.
    pub router: Option<String>,
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
    Ok(Some(Ros2Params {
        domain_id: domain.map_or(0, |d| d as u32),
        namespace,
        router,
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
    fn the_section_is_not_hashed() {
        let a = parse("").unwrap();
        let b = parse("domain_id = 3\nnamespace = \"x\"").unwrap();
        assert_eq!(a.scenario_hash(), b.scenario_hash());
    }
}
