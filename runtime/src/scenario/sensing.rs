//! `[sensing]`: what the robots learn of the world after `Start`, and how.
//!
//! ```toml
//! [sensing]
//! range = 5            # cells a robot's range sensor sees (line of sight), in [1, 15]
//! known_map = true     # the map at Start is known (its changes are not); false: only the
//!                      # walls seen so far are known (seed 003's unmapped setting)
//! repair = "auto"      # how an agent repairs its neural map: "auto", "partial", "rebuild"
//! all_knowing = false  # true: every agent is also told each close and open of [[events]]
//!                      # when it happens, wherever it is (the baseline experiments compare
//!                      # sensing with)
//! ```
//!
//! Without the section the robots sense nothing and plan on the scenario's map: every run
//! before the section existed. With it, the sim publishes each robot's view at every
//! control period and the agent learns the changes from it alone. The section changes what
//! a run does, so it is hashed when present.

use serde::Deserialize;
use toml::Spanned;

use super::error::ScenarioError;
use super::lines::Lines;

/// `[sensing]` as `serde` sees it.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSensing {
    pub range: Option<Spanned<i64>>,
    pub known_map: Option<bool>,
    pub repair: Option<Spanned<RepairRule>>,
    pub all_knowing: Option<bool>,
}

/// How an agent repairs its neural map when its view differs from it (§2.10).
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[serde(rename_all = "kebab-case")]
pub enum RepairRule {
    /// Partial correction for a few new obstacles away from the robot, rebuild otherwise
    /// (the rule is in `agent/src/navigator/sense.rs`).
    Auto,
    /// Always partial correction (opened cells still need a rebuild).
    Partial,
    /// Always a new map with partial activation.
    Rebuild,
}

/// The validated `[sensing]` section.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct SensingParams {
    /// Cells a robot sees around its own, in line of sight.
    pub range: u32,
    /// Whether the map at `Start` is known.
    pub known_map: bool,
    /// How a neural map is repaired.
    pub repair: RepairRule,
    /// Whether every agent is told each close and open of `[[events]]` when it happens (the
    /// all-knowing baseline), besides what it sees.
    pub all_knowing: bool,
}

impl SensingParams {
    /// The largest range: a window of 31 x 31 cells ([`crate::msg::VIEW_EDGE`]).
    pub const MAX_RANGE: u32 = 15;
}

impl Default for SensingParams {
    fn default() -> Self {
        Self {
            range: 5,
            known_map: true,
            repair: RepairRule::Auto,
            all_knowing: false,
        }
    }
}

/// Validates `[sensing]`.
pub(super) fn build_sensing(
    raw: Option<RawSensing>,
    lines: &Lines<'_>,
) -> Result<Option<SensingParams>, ScenarioError> {
    let Some(r) = raw else { return Ok(None) };
    let d = SensingParams::default();
    let max = i64::from(SensingParams::MAX_RANGE);
    let range = lines.in_range(&r.range, "sensing.range", (1, max), " cells")?;
    let range = range.map_or(d.range, |x| x as u32);
    Ok(Some(SensingParams {
        range,
        known_map: r.known_map.unwrap_or(d.known_map),
        repair: r.repair.map_or(d.repair, |s| *s.get_ref()),
        all_knowing: r.all_knowing.unwrap_or(d.all_knowing),
    }))
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{parse, BASE};
    use super::*;

    #[test]
    fn defaults_given_values_and_a_range_out_of_bounds_at_its_line() {
        assert_eq!(parse(BASE).unwrap().sensing, None);
        let s = parse(&format!("{BASE}[sensing]\n")).unwrap();
        assert_eq!(s.sensing, Some(SensingParams::default()));
        let s = parse(&format!(
            "{BASE}[sensing]\nrange = 15\nknown_map = false\nrepair = \"partial\"\nall_knowing = true\n"
        ))
        .unwrap();
        let want = SensingParams {
            range: 15,
            known_map: false,
            repair: RepairRule::Partial,
            all_knowing: true,
        };
        assert_eq!(s.sensing, Some(want));
        let e = parse(&format!("{BASE}[sensing]\nrange = 0\n")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.toml:17: sensing.range must be in [1, 15] cells, got 0"
        );
    }
}
