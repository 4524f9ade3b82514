//! `[localisation]`: the sim's emulated map-based localisation fix, which bounds the agents'
//! dead-reckoning drift (see `docs/explanation/sim.md`, "Localisation").
//!
//! ```toml
//! [localisation]
//! rate_hz = 1.0          # fixes per simulated second per robot, in [0, odometry_hz];
//!                        # 0 = none (pure dead reckoning)
//! std_m = 0.002          # noise of a fix's x and y, m, >= 0
//! std_deg = 0.5          # noise of a fix's heading, degrees, >= 0
//! ```
//!
//! A fix is the robot's ground-truth pose plus seeded Gaussian noise, published with the
//! odometry reading of every `odometry_hz / rate_hz`-th control period. The agent takes a
//! fix only when it disagrees with its dead reckoning by more than [`GATE_SIGMAS`] standard
//! deviations (in heading, plus the quantum of a tick pair): below that the difference is
//! the fix's own noise, not drift.

use serde::Deserialize;
use toml::Spanned;

use super::error::ScenarioError;
use super::lines::Lines;

/// How many standard deviations of a fix's noise the agent's estimate may differ from the
/// fix before it takes the fix. Five: a fix of an exact estimate differs by more only once
/// in about 270 000 fixes (the noise's 2-D norm), so an estimate that is still good is not
/// disturbed by the fix's noise; a drifted one is corrected once its error passes the gate,
/// to within a fix's noise (with the default noise the two-hour
/// `scenarios/replicas-lifelong.toml` run's largest error was 15.6 mm, of the 22 mm between
/// a default robot at a cell's centre and the cell's edge).
pub const GATE_SIGMAS: f64 = 5.0;

/// `[localisation]` as `serde` sees it.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawLocalisation {
    pub rate_hz: Option<Spanned<f64>>,
    pub std_m: Option<Spanned<f64>>,
    pub std_deg: Option<Spanned<f64>>,
}

/// The validated `[localisation]` section.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct LocalisationParams {
    /// Fixes per simulated second per robot; 0 = none.
    pub rate_hz: f64,
    /// Standard deviation of a fix's x and y, m.
    pub std_m: f64,
    /// Standard deviation of a fix's heading, degrees.
    pub std_deg: f64,
}

impl Default for LocalisationParams {
    fn default() -> Self {
        Self {
            rate_hz: 1.0,
            std_m: 0.002,
            std_deg: 0.5,
        }
    }
}

impl LocalisationParams {
    /// Whether fixes are published at all.
    pub fn enabled(&self) -> bool {
        self.rate_hz > 0.0
    }

    /// Control periods between two fixes of a robot at `odometry_hz` (rounded, at least
    /// one); `None` when there are no fixes.
    pub fn periods_between(&self, odometry_hz: u32) -> Option<u64> {
        self.enabled()
            .then(|| ((f64::from(odometry_hz) / self.rate_hz).round() as u64).max(1))
    }

    /// Whether the odometry reading of control period `period` carries a fix: the last
    /// period of every interval, so the first fix comes `1 / rate_hz` after the start.
    pub fn fix_due(&self, odometry_hz: u32, period: u64) -> bool {
        self.periods_between(odometry_hz)
            .is_some_and(|k| (period + 1).is_multiple_of(k))
    }

    /// The agent's gate: it takes a fix whose position differs from its estimate by more
    /// than the first (m), or whose heading differs by more than the second (rad).
    pub fn gate(&self) -> (f64, f64) {
        (
            GATE_SIGMAS * self.std_m,
            GATE_SIGMAS * self.std_deg.to_radians(),
        )
    }
}

/// Validates `[localisation]` against the odometry rate it samples.
pub(super) fn build_localisation(
    raw: Option<RawLocalisation>,
    odometry_hz: u32,
    lines: &Lines<'_>,
) -> Result<LocalisationParams, ScenarioError> {
    let d = LocalisationParams::default();
    let Some(r) = raw else { return Ok(d) };
    let within = |v: &Option<Spanned<f64>>, key: &str, default: f64, hi: f64| {
        let Some(v) = v else { return Ok(default) };
        let x = *v.get_ref();
        if x.is_finite() && (0.0..=hi).contains(&x) {
            return Ok(x);
        }
        Err(ScenarioError::InvalidParameter {
            at: lines.at(v),
            key: key.into(),
            problem: format!("must be in [0, {hi}], got {}", super::error::number(x)),
        })
    };
    let hz = f64::from(odometry_hz);
    Ok(LocalisationParams {
        rate_hz: within(&r.rate_hz, "localisation.rate_hz", d.rate_hz, hz)?,
        std_m: within(&r.std_m, "localisation.std_m", d.std_m, 1.0)?,
        std_deg: within(&r.std_deg, "localisation.std_deg", d.std_deg, 180.0)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Scenario;

    fn parse(section: &str) -> Result<Scenario, ScenarioError> {
        let text = format!(
            "name = \"l\"\n[map]\nrows = [\"...\"]\n[[agents]]\nstart = [0, 0]\ngoal = [2, 0]\n\
             [localisation]\n{section}\n"
        );
        Scenario::from_str(&text, "l.toml", std::path::Path::new("."))
    }

    #[test]
    fn defaults_given_values_and_the_schedule() {
        let d = parse("").unwrap().localisation;
        assert_eq!(d, LocalisationParams::default());
        assert_eq!(d.periods_between(100), Some(100));
        assert!(!d.fix_due(100, 0) && d.fix_due(100, 99) && d.fix_due(100, 199));
        let s = parse("rate_hz = 0\nstd_m = 0.01\nstd_deg = 2").unwrap();
        let l = s.localisation;
        assert_eq!((l.rate_hz, l.std_m, l.std_deg), (0.0, 0.01, 2.0));
        assert!(!l.enabled() && !l.fix_due(100, 99));
        let fast = parse("rate_hz = 100").unwrap().localisation;
        assert!(fast.fix_due(100, 0) && fast.fix_due(100, 1));
        assert_eq!(d.gate().0, 0.01);
    }

    #[test]
    fn bad_values_name_their_line_and_range() {
        let e = parse("rate_hz = 200").unwrap_err().to_string();
        assert_eq!(
            e,
            "l.toml:8: localisation.rate_hz must be in [0, 100], got 200"
        );
        let e = parse("std_m = -1").unwrap_err().to_string();
        assert_eq!(e, "l.toml:8: localisation.std_m must be in [0, 1], got -1");
        assert!(parse("std_deg = nan").is_err());
        assert!(parse("hz = 3").unwrap_err().to_string().contains("hz"));
    }

    #[test]
    fn only_a_changed_section_is_hashed() {
        let none = parse("").unwrap();
        let same = parse("rate_hz = 1.0\nstd_m = 0.002\nstd_deg = 0.5").unwrap();
        let other = parse("rate_hz = 0").unwrap();
        assert_eq!(none.scenario_hash(), same.scenario_hash());
        assert_ne!(none.scenario_hash(), other.scenario_hash());
    }
}
