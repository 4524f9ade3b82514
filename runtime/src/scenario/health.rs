//! `[health]`: how often every process beats and how long each role may stay silent before
//! the supervisor declares it hung (see `docs/explanation/hangs.md`).
//!
//! ```toml
//! [health]
//! heartbeat_ms = 50           # every process beats this often from its main loop
//! agent_hang_ms = 1000        # default 1000 plus the agents' neural-map rebuilds (below)
//! coordinator_hang_ms = 2000
//! sim_hang_ms = 1000
//! ```
//!
//! Like `[run]`, the section decides whether a process is declared hung, not what a healthy
//! run does, so the scenario hash leaves it out (and every earlier log keeps its hash).

use std::time::Duration;

use serde::Deserialize;
use toml::Spanned;

use super::error::ScenarioError;
use super::lines::Lines;
use crate::msg::Role;

/// `[health]` as `serde` sees it.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawHealth {
    pub heartbeat_ms: Option<Spanned<u32>>,
    pub agent_hang_ms: Option<Spanned<u32>>,
    pub coordinator_hang_ms: Option<Spanned<u32>>,
    pub sim_hang_ms: Option<Spanned<u32>>,
}

/// The validated `[health]` section.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct HealthParams {
    /// How often a process beats, in milliseconds.
    pub heartbeat_ms: u32,
    /// An agent's hang deadline in milliseconds; `None` for the default that grows with the
    /// map ([`default_agent_hang_ms`]).
    pub agent_hang_ms: Option<u32>,
    /// The coordinator's hang deadline in milliseconds.
    pub coordinator_hang_ms: u32,
    /// The sim's hang deadline in milliseconds.
    pub sim_hang_ms: u32,
}

impl HealthParams {
    /// Largest `heartbeat_ms` accepted: one minute.
    pub const MAX_HEARTBEAT_MS: u32 = 60_000;
    /// Largest hang deadline accepted: one hour.
    pub const MAX_HANG_MS: u32 = 3_600_000;
    /// The default beat: five control periods, far more often than any deadline.
    pub const DEFAULT_HEARTBEAT_MS: u32 = 50;
    /// The agents' and the sim's default deadline before the map term: 20 beats. A false
    /// hang kills a healthy process (and writes its death into a lockstep log), so the
    /// defaults sit well above what a busy 2-core machine stalls a loop for.
    pub const DEFAULT_HANG_MS: u32 = 1_000;
    /// The coordinator's default: it also waits for every record's fsync, which a loaded
    /// disk stretches.
    pub const DEFAULT_COORDINATOR_HANG_MS: u32 = 2_000;

    /// How often a process beats.
    pub fn heartbeat(&self) -> Duration {
        Duration::from_millis(self.heartbeat_ms.into())
    }
}

impl Default for HealthParams {
    fn default() -> Self {
        Self {
            heartbeat_ms: Self::DEFAULT_HEARTBEAT_MS,
            agent_hang_ms: None,
            coordinator_hang_ms: Self::DEFAULT_COORDINATOR_HANG_MS,
            sim_hang_ms: Self::DEFAULT_HANG_MS,
        }
    }
}

/// Neuron updates per second per core assumed for a rebuild during the run: the start-up
/// timeout's assumption ([`super::default_startup_timeout_s`]).
const ASSUMED_UPDATES_PER_S: f64 = 1e7;

/// An agent's default hang deadline on a `width` x `height` map with `agents` agents on
/// `cores` cores, in milliseconds: [`HealthParams::DEFAULT_HANG_MS`] plus twice the time
/// one neural-map rebuild takes (an agent replanned toward a waypoint rebuilds its map in its
/// loop, `width * height * max(width, height) / 3` updates at 1e7 per second, the agents
/// sharing the cores), capped at [`HealthParams::MAX_HANG_MS`]. A 32 x 32 map adds nothing
/// to speak of; 64 agents on `maze-128-128-10` on 2 cores get 5.5 s.
pub fn default_agent_hang_ms(width: u32, height: u32, agents: usize, cores: usize) -> u32 {
    let (w, h) = (f64::from(width), f64::from(height));
    let updates = w * h * w.max(h) / 3.0;
    let per_core = agents.max(1).div_ceil(cores.max(1)) as f64;
    let rebuild_ms = 1000.0 * updates * per_core / ASSUMED_UPDATES_PER_S;
    let ms = f64::from(HealthParams::DEFAULT_HANG_MS) + 2.0 * rebuild_ms;
    ms.min(f64::from(HealthParams::MAX_HANG_MS)) as u32
}

/// The hang deadline of `role` under `params` on a `width` x `height` map with `agents`
/// agents on this machine's cores.
pub(super) fn hang_deadline(
    params: &HealthParams,
    role: Role,
    (width, height): (u32, u32),
    agents: usize,
) -> Duration {
    let ms = match role {
        Role::Sim => params.sim_hang_ms,
        Role::Coordinator => params.coordinator_hang_ms,
        Role::Agent => params.agent_hang_ms.unwrap_or_else(|| {
            let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
            default_agent_hang_ms(width, height, agents, cores).max(2 * params.heartbeat_ms)
        }),
        // A bridge beats no heartbeat (its loop blocks on Zenoh as much as on iceoryx2): its
        // exit is watched, not its pace.
        Role::Bridge => HealthParams::MAX_HANG_MS,
    };
    Duration::from_millis(ms.into())
}

/// Validates `[health]`: `heartbeat_ms` in [1, 60000], each hang deadline in
/// [2 * heartbeat_ms, 3600000] (a beat may be up to one period late, so a deadline of one
/// period would kill healthy processes).
pub(super) fn build_health(
    raw: Option<RawHealth>,
    lines: &Lines<'_>,
) -> Result<HealthParams, ScenarioError> {
    let d = HealthParams::default();
    let Some(r) = raw else { return Ok(d) };
    let heartbeat_ms = match &r.heartbeat_ms {
        None => d.heartbeat_ms,
        Some(v) => within(
            v,
            "health.heartbeat_ms",
            1,
            HealthParams::MAX_HEARTBEAT_MS,
            lines,
        )?,
    };
    let min = 2 * heartbeat_ms;
    let hang = |v: &Option<Spanned<u32>>, key: &str| -> Result<Option<u32>, ScenarioError> {
        v.as_ref()
            .map(|v| within(v, key, min, HealthParams::MAX_HANG_MS, lines))
            .transpose()
    };
    let p = HealthParams {
        heartbeat_ms,
        agent_hang_ms: hang(&r.agent_hang_ms, "health.agent_hang_ms")?,
        coordinator_hang_ms: hang(&r.coordinator_hang_ms, "health.coordinator_hang_ms")?
            .unwrap_or(d.coordinator_hang_ms),
        sim_hang_ms: hang(&r.sim_hang_ms, "health.sim_hang_ms")?.unwrap_or(d.sim_hang_ms),
    };
    // A beat slower than a defaulted deadline would make that deadline unmeetable.
    for (ms, key) in [
        (p.coordinator_hang_ms, "coordinator_hang_ms"),
        (p.sim_hang_ms, "sim_hang_ms"),
    ] {
        if ms < min {
            return Err(ScenarioError::InvalidParameter {
                at: r.heartbeat_ms.as_ref().map_or_else(
                    || super::error::Loc::new(lines.source_name, 0),
                    |v| lines.at(v),
                ),
                key: "health.heartbeat_ms".into(),
                problem: format!(
                    "{heartbeat_ms} ms is more than half the default {key} ({ms} ms); \
                     lower it or set {key}"
                ),
            });
        }
    }
    Ok(p)
}

/// `v` if it is in `[lo, hi]`, else an error at its line.
fn within(
    v: &Spanned<u32>,
    key: &str,
    lo: u32,
    hi: u32,
    lines: &Lines<'_>,
) -> Result<u32, ScenarioError> {
    let x = *v.get_ref();
    if (lo..=hi).contains(&x) {
        return Ok(x);
    }
    let problem = if key == "health.heartbeat_ms" {
        format!("must be in [{lo}, {hi}] ms, got {x}")
    } else {
        format!("must be in [{lo}, {hi}] ms (at least twice health.heartbeat_ms), got {x}")
    };
    Err(ScenarioError::InvalidParameter {
        at: lines.at(v),
        key: key.into(),
        problem,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Scenario;

    fn parse(health: &str) -> Result<Scenario, ScenarioError> {
        let text = format!(
            "name = \"h\"\n[map]\nrows = [\"...\"]\n[[agents]]\nstart = [0, 0]\ngoal = [2, 0]\n\
             [health]\n{health}\n"
        );
        Scenario::from_str(&text, "h.toml", std::path::Path::new("."))
    }

    #[test]
    fn defaults_and_given_values() {
        let s = parse("").unwrap();
        assert_eq!(s.health, HealthParams::default());
        assert_eq!(s.hang_deadline(Role::Coordinator), Duration::from_secs(2));
        assert_eq!(s.hang_deadline(Role::Sim), Duration::from_secs(1));
        let s = parse("heartbeat_ms = 20\nagent_hang_ms = 300\nsim_hang_ms = 40").unwrap();
        assert_eq!(s.heartbeat(), Duration::from_millis(20));
        assert_eq!(s.hang_deadline(Role::Agent), Duration::from_millis(300));
        assert_eq!(s.hang_deadline(Role::Sim), Duration::from_millis(40));
    }

    #[test]
    fn bad_values_name_their_line_and_range() {
        let e = parse("heartbeat_ms = 0").unwrap_err().to_string();
        assert_eq!(
            e,
            "h.toml:8: health.heartbeat_ms must be in [1, 60000] ms, got 0"
        );
        let e = parse("heartbeat_ms = 100\nagent_hang_ms = 150")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "h.toml:9: health.agent_hang_ms must be in [200, 3600000] ms (at least twice \
             health.heartbeat_ms), got 150"
        );
        let e = parse("heartbeat_ms = 1500").unwrap_err().to_string();
        assert!(
            e.starts_with("h.toml:8: health.heartbeat_ms 1500 ms is more than half"),
            "{e}"
        );
        let e = parse("hang_ms = 5").unwrap_err().to_string();
        assert!(e.contains("hang_ms"), "{e}");
    }

    #[test]
    fn the_agents_default_grows_with_the_map_and_the_agents_per_core() {
        assert_eq!(default_agent_hang_ms(32, 32, 8, 2), 1_008);
        assert_eq!(default_agent_hang_ms(128, 128, 64, 2), 5_473);
        assert_eq!(
            default_agent_hang_ms(5000, 5000, 256, 1),
            HealthParams::MAX_HANG_MS
        );
    }
}
