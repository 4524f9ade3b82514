//! Validation of the parameter sections `[robot]`, `[sim]`, `[coordinator]`, `[restart]` and
//! `[run]`:
//! defaults for missing keys, range checks with the key's line for present ones.

use toml::Spanned;

use super::error::{Loc, ScenarioError};
use super::lines::Lines;
use super::params::{
    ClockMode, CoordinatorParams, RestartConfig, RestartRule, RobotParams, RunParams, SimKind,
    SimParams,
};
use super::raw::{RawCoordinator, RawRestart, RawRestartRule, RawRobot, RawRun, RawSim};

/// Reads an optional float with a default and checks it.
fn float(
    v: &Option<Spanned<f64>>,
    default: f64,
    key: &str,
    positive: bool,
    fallback: &Loc,
    lines: &Lines<'_>,
) -> Result<f64, ScenarioError> {
    let Some(s) = v else { return Ok(default) };
    let x = *s.get_ref();
    let ok = x.is_finite() && if positive { x > 0.0 } else { x >= 0.0 };
    if ok {
        return Ok(x);
    }
    let at = lines.at_opt(v, fallback);
    let problem = if positive {
        "must be a positive number"
    } else {
        "must be a number >= 0"
    };
    Err(ScenarioError::InvalidParameter {
        at,
        key: key.into(),
        problem: format!("{problem}, got {}", super::error::number(x)),
    })
}

/// Reads an optional integer with a default and checks it is at least 1.
fn count(
    v: &Option<Spanned<u32>>,
    default: u32,
    key: &str,
    lines: &Lines<'_>,
) -> Result<u32, ScenarioError> {
    match v {
        None => Ok(default),
        Some(s) if *s.get_ref() >= 1 => Ok(*s.get_ref()),
        Some(s) => Err(ScenarioError::InvalidParameter {
            at: lines.at(s),
            key: key.into(),
            problem: "must be at least 1".into(),
        }),
    }
}

pub(super) fn build_robot(
    raw: Option<RawRobot>,
    lines: &Lines<'_>,
) -> Result<RobotParams, ScenarioError> {
    let d = RobotParams::default();
    let Some(r) = raw else { return Ok(d) };
    let none = Loc::new(lines.source_name, 0);
    let pos =
        |v: &Option<Spanned<f64>>, def: f64, key: &str| float(v, def, key, true, &none, lines);
    let ticks_per_rev = match (&r.ticks_per_rev, &r.pole_pairs, &r.gear_ratio) {
        (Some(t), Some(_), _) | (Some(t), _, Some(_)) => {
            return Err(ScenarioError::InvalidParameter {
                at: lines.at(t),
                key: "robot.ticks_per_rev".into(),
                problem: "conflicts with pole_pairs/gear_ratio; give one or the other".into(),
            })
        }
        (Some(_), None, None) => pos(&r.ticks_per_rev, 0.0, "robot.ticks_per_rev")?,
        (None, pp, _) => {
            let pole_pairs = count(
                pp,
                RobotParams::DEFAULT_POLE_PAIRS,
                "robot.pole_pairs",
                lines,
            )?;
            let gear = pos(&r.gear_ratio, 1.0, "robot.gear_ratio")?;
            6.0 * f64::from(pole_pairs) * gear
        }
    };
    let p = RobotParams {
        wheel_radius_m: pos(&r.wheel_radius_m, d.wheel_radius_m, "robot.wheel_radius_m")?,
        axle_track_m: pos(&r.axle_track_m, d.axle_track_m, "robot.axle_track_m")?,
        body_radius_m: pos(&r.body_radius_m, d.body_radius_m, "robot.body_radius_m")?,
        max_wheel_speed_rad_s: pos(
            &r.max_wheel_speed_rad_s,
            d.max_wheel_speed_rad_s,
            "robot.max_wheel_speed_rad_s",
        )?,
        max_wheel_accel_rad_s2: pos(
            &r.max_wheel_accel_rad_s2,
            d.max_wheel_accel_rad_s2,
            "robot.max_wheel_accel_rad_s2",
        )?,
        motor_lag_s: float(
            &r.motor_lag_s,
            d.motor_lag_s,
            "robot.motor_lag_s",
            false,
            &none,
            lines,
        )?,
        ticks_per_rev,
        cell_size_m: pos(&r.cell_size_m, d.cell_size_m, "robot.cell_size_m")?,
    };
    // Cells are reserved one robot at a time, which is only collision-free if a robot fits.
    if 2.0 * p.body_radius_m > p.cell_size_m {
        let at = lines.at_opt(&r.body_radius_m, &lines.at_opt(&r.cell_size_m, &none));
        return Err(ScenarioError::InvalidParameter {
            at,
            key: "robot.body_radius_m".into(),
            problem: format!(
                "{} m: the body (diameter {} m) must fit in a cell of {} m",
                p.body_radius_m,
                2.0 * p.body_radius_m,
                p.cell_size_m
            ),
        });
    }
    Ok(p)
}

pub(super) fn build_sim(
    raw: Option<RawSim>,
    lines: &Lines<'_>,
) -> Result<SimParams, ScenarioError> {
    let d = SimParams::default();
    let Some(s) = raw else { return Ok(d) };
    let none = Loc::new(lines.source_name, 0);
    let mut p = SimParams {
        step_ms: count(&s.step_ms, d.step_ms, "sim.step_ms", lines)?,
        odometry_hz: count(&s.odometry_hz, d.odometry_hz, "sim.odometry_hz", lines)?,
        clock: s.clock.unwrap_or(d.clock),
        seed: s.seed.unwrap_or(d.seed),
        slip_std: float(&s.slip_std, d.slip_std, "sim.slip_std", false, &none, lines)?,
        watchdog_ms: count(&s.watchdog_ms, d.watchdog_ms, "sim.watchdog_ms", lines)?,
        slip_hold_s: float(
            &s.slip_hold_s,
            d.slip_hold_s,
            "sim.slip_hold_s",
            true,
            &none,
            lines,
        )?,
        // Any u32 (0 = no deadline); a negative or fractional value fails in serde, with its
        // line.
        lockstep_deadline_ms: s.lockstep_deadline_ms.unwrap_or(d.lockstep_deadline_ms),
        kind: s.kind.as_ref().map_or(d.kind, |k| *k.get_ref()),
    };
    // Robots outside HNAV keep their own time: such a run follows the wall clock, which is
    // also what it defaults to.
    if let Some(k) = s.kind.as_ref().filter(|k| *k.get_ref() == SimKind::Ros2) {
        match s.clock {
            Some(ClockMode::Lockstep) => {
                return Err(ScenarioError::InvalidParameter {
                    at: lines.at(k),
                    key: "sim.kind".into(),
                    problem: "\"ros2\" runs in realtime only (robots outside HNAV do not wait for a lockstep round); drop clock = \"lockstep\"".into(),
                })
            }
            Some(ClockMode::Realtime) => {}
            None => p.clock = ClockMode::Realtime,
        }
    }
    // Odometry is sampled on physics steps, so it cannot be faster than one message per step.
    if u64::from(p.odometry_hz) * u64::from(p.step_ms) > 1000 {
        let at = lines.at_opt(&s.odometry_hz, &lines.at_opt(&s.step_ms, &none));
        return Err(ScenarioError::InvalidParameter {
            at,
            key: "sim.odometry_hz".into(),
            problem: format!(
                "{} Hz is faster than one message per {} ms step",
                p.odometry_hz, p.step_ms
            ),
        });
    }
    Ok(p)
}

pub(super) fn build_coordinator(
    raw: Option<RawCoordinator>,
    lines: &Lines<'_>,
) -> Result<CoordinatorParams, ScenarioError> {
    let d = CoordinatorParams::default();
    let Some(c) = raw else { return Ok(d) };
    let none = Loc::new(lines.source_name, 0);
    Ok(CoordinatorParams {
        round_deadline_ms: count(
            &c.round_deadline_ms,
            d.round_deadline_ms,
            "coordinator.round_deadline_ms",
            lines,
        )?,
        fsync: c.fsync.unwrap_or(d.fsync),
        replan_after_rounds: count(
            &c.replan_after_rounds,
            d.replan_after_rounds,
            "coordinator.replan_after_rounds",
            lines,
        )?,
        time_limit_s: float(
            &c.time_limit_s,
            d.time_limit_s,
            "coordinator.time_limit_s",
            true,
            &none,
            lines,
        )?,
        rules: c.rules.unwrap_or(d.rules),
        replicas: replicas(&c.replicas, d.replicas, lines)?,
        raft_heartbeat_ms: count(
            &c.raft_heartbeat_ms,
            d.raft_heartbeat_ms,
            "coordinator.raft_heartbeat_ms",
            lines,
        )?,
        election_ms: count(
            &c.election_ms,
            d.election_ms,
            "coordinator.election_ms",
            lines,
        )?,
        snapshot_entries: c
            .snapshot_entries
            .as_ref()
            .map_or(d.snapshot_entries, |s| *s.get_ref()),
    })
    .and_then(|p| election_after_heartbeats(p, &c, lines))
}

/// `coordinator.replicas`: one of [`CoordinatorParams::REPLICAS`].
fn replicas(
    v: &Option<Spanned<u32>>,
    default: u32,
    lines: &Lines<'_>,
) -> Result<u32, ScenarioError> {
    match v {
        None => Ok(default),
        Some(s) if CoordinatorParams::REPLICAS.contains(s.get_ref()) => Ok(*s.get_ref()),
        Some(s) => Err(ScenarioError::InvalidParameter {
            at: lines.at(s),
            key: "coordinator.replicas".into(),
            problem: format!(
                "{} replicas; a cluster has 1 (no replication), 3 or 5",
                s.get_ref()
            ),
        }),
    }
}

/// Raft needs several heartbeats per election timeout, or followers stand for election
/// while the leader is well.
fn election_after_heartbeats(
    p: CoordinatorParams,
    c: &RawCoordinator,
    lines: &Lines<'_>,
) -> Result<CoordinatorParams, ScenarioError> {
    if p.election_ticks() >= 3 {
        return Ok(p);
    }
    let none = Loc::new(lines.source_name, 0);
    Err(ScenarioError::InvalidParameter {
        at: lines.at_opt(&c.election_ms, &lines.at_opt(&c.raft_heartbeat_ms, &none)),
        key: "coordinator.election_ms".into(),
        problem: format!(
            "{} ms is less than 3 heartbeats of {} ms",
            p.election_ms, p.raft_heartbeat_ms
        ),
    })
}

pub(super) fn build_restart(raw: Option<RawRestart>) -> RestartConfig {
    let d = RestartConfig::default();
    let Some(r) = raw else { return d };
    let rule = |raw: Option<RawRestartRule>, d: RestartRule| match raw {
        None => d,
        Some(x) => RestartRule {
            policy: x.policy.unwrap_or(d.policy),
            max_restarts: x.max_restarts.unwrap_or(d.max_restarts),
            backoff_ms: x.backoff_ms.unwrap_or(d.backoff_ms),
        },
    };
    RestartConfig {
        agent: rule(r.agent, d.agent),
        coordinator: rule(r.coordinator, d.coordinator),
        sim: rule(r.sim, d.sim),
        on_give_up: r.on_give_up.unwrap_or(d.on_give_up),
    }
}

pub(super) fn build_run(
    raw: Option<RawRun>,
    lines: &Lines<'_>,
) -> Result<RunParams, ScenarioError> {
    let d = RunParams::default();
    let Some(raw) = raw else { return Ok(d) };
    let per = count(
        &raw.agents_per_process,
        d.agents_per_process,
        "run.agents_per_process",
        lines,
    )?;
    if let Some(v) = raw
        .agents_per_process
        .as_ref()
        .filter(|_| per > RunParams::MAX_AGENTS_PER_PROCESS)
    {
        return Err(ScenarioError::InvalidParameter {
            at: lines.at(v),
            key: "run.agents_per_process".into(),
            problem: format!(
                "must be at most {}, got {per}",
                RunParams::MAX_AGENTS_PER_PROCESS
            ),
        });
    }
    let Some(v) = raw.startup_timeout_s else {
        return Ok(RunParams {
            agents_per_process: per,
            ..d
        });
    };
    let x = *v.get_ref();
    let max = RunParams::MAX_STARTUP_TIMEOUT_S;
    if x.is_finite() && x > 0.0 && x <= max {
        return Ok(RunParams {
            startup_timeout_s: Some(x),
            agents_per_process: per,
        });
    }
    Err(ScenarioError::InvalidParameter {
        at: lines.at(&v),
        key: "run.startup_timeout_s".into(),
        problem: format!(
            "must be a number of seconds in (0, {max}], got {}",
            super::error::number(x)
        ),
    })
}
