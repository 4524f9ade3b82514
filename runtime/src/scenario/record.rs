//! `[record]`: what the supervisor's recorder keeps of a run (see
//! `docs/reference/logs-and-recordings.md`).
//!
//! ```toml
//! [record]
//! trajectory_hz = 20     # pose samples per simulated second per robot and source, in
//!                        # [0, 1000]; 0 = one per ground-truth message
//! max_mb = 64            # size cap of each recording file, MiB, in [1, 4096]
//! maps = true            # record the agents' neural-map snapshots
//! ```
//!
//! Like `[health]`, the section decides what is written about a run, not what the run does,
//! so the scenario hash leaves it out (and every earlier log keeps its hash).

use serde::Deserialize;
use toml::Spanned;

use super::error::ScenarioError;
use super::lines::Lines;

/// `[record]` as `serde` sees it.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRecord {
    pub trajectory_hz: Option<Spanned<i64>>,
    pub max_mb: Option<Spanned<i64>>,
    pub maps: Option<bool>,
}

/// The validated `[record]` section.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct RecordParams {
    /// Pose samples per simulated second per robot and source (0: one per truth message).
    pub trajectory_hz: u16,
    /// Size cap of each recording file, MiB.
    pub max_mb: u32,
    /// Whether neural-map snapshots are recorded.
    pub maps: bool,
}

impl RecordParams {
    /// Largest `trajectory_hz`: a sample per millisecond, the sim's finest step.
    pub const MAX_HZ: u16 = 1000;
    /// Largest `max_mb`.
    pub const MAX_MB: u32 = 4096;

    /// The size cap of each file in bytes.
    pub fn max_bytes(&self) -> u64 {
        u64::from(self.max_mb) << 20
    }
}

impl Default for RecordParams {
    fn default() -> Self {
        Self {
            trajectory_hz: 20,
            max_mb: 64,
            maps: true,
        }
    }
}

/// Validates `[record]`.
pub(super) fn build_record(
    raw: Option<RawRecord>,
    lines: &Lines<'_>,
) -> Result<RecordParams, ScenarioError> {
    let d = RecordParams::default();
    let Some(r) = raw else { return Ok(d) };
    let hz = lines.in_range(
        &r.trajectory_hz,
        "record.trajectory_hz",
        (0, i64::from(RecordParams::MAX_HZ)),
        " samples per second",
    )?;
    let mb = lines.in_range(
        &r.max_mb,
        "record.max_mb",
        (1, i64::from(RecordParams::MAX_MB)),
        " MiB",
    )?;
    Ok(RecordParams {
        trajectory_hz: hz.map_or(d.trajectory_hz, |x| x as u16),
        max_mb: mb.map_or(d.max_mb, |x| x as u32),
        maps: r.maps.unwrap_or(d.maps),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Scenario;

    fn parse(record: &str) -> Result<Scenario, ScenarioError> {
        let text = format!(
            "name = \"r\"\n[map]\nrows = [\"...\"]\n[[agents]]\nstart = [0, 0]\ngoal = [2, 0]\n\
             [record]\n{record}\n"
        );
        Scenario::from_str(&text, "r.toml", std::path::Path::new("."))
    }

    #[test]
    fn defaults_and_given_values() {
        assert_eq!(parse("").unwrap().record, RecordParams::default());
        let s = parse("trajectory_hz = 0\nmax_mb = 2\nmaps = false").unwrap();
        assert_eq!(
            s.record,
            RecordParams {
                trajectory_hz: 0,
                max_mb: 2,
                maps: false
            }
        );
        assert_eq!(s.record.max_bytes(), 2 << 20);
    }

    #[test]
    fn bad_values_name_their_line_and_range() {
        let e = parse("trajectory_hz = 5000").unwrap_err().to_string();
        assert_eq!(
            e,
            "r.toml:8: record.trajectory_hz must be in [0, 1000] samples per second, got 5000"
        );
        let e = parse("maps = true\nmax_mb = 0").unwrap_err().to_string();
        assert_eq!(e, "r.toml:9: record.max_mb must be in [1, 4096] MiB, got 0");
        assert!(parse("rate = 3").unwrap_err().to_string().contains("rate"));
    }

    #[test]
    fn the_section_is_not_hashed() {
        let a = parse("").unwrap();
        let b = parse("trajectory_hz = 100\nmax_mb = 3\nmaps = false").unwrap();
        assert_eq!(a.scenario_hash(), b.scenario_hash());
    }
}
