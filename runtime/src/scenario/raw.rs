//! The scenario file as `serde` sees it, before validation.
//!
//! Everything a semantic check may complain about is wrapped in [`Spanned`] so the error can
//! name its line; every table denies unknown keys so a typo is an error, not a silently
//! ignored setting. Coordinates are `Vec<i64>`: a negative or three-element coordinate then
//! reaches the validator (which names it precisely) instead of failing inside serde, whose
//! fixed-size arrays would also silently accept extra elements.

use serde::Deserialize;
use toml::Spanned;

use super::params::{ClockMode, FsyncPolicy, GiveUpAction, Planner, RestartPolicy, Rules, SimKind};

/// Every key of the format, table by table as the structs below (and `health`'s and
/// `record`'s) take them: `""` is the top level, `restart.ROLE` each role's rule, `agents`,
/// `faults`, `tasks.goals` and `events` one entry of the arrays of tables. The docs that describe the format are
/// checked against it, and a test checks it against what the parser accepts.
pub const KEYS: &[(&str, &[&str])] = &[
    (
        "",
        &[
            "name",
            "allow_unreachable",
            "map",
            "robot",
            "sim",
            "coordinator",
            "restart",
            "run",
            "health",
            "record",
            "localisation",
            "agents",
            "faults",
            "tasks",
            "events",
            "sensing",
            "ros2",
        ],
    ),
    ("map", &["file", "rows", "corner_cutting"]),
    (
        "robot",
        &[
            "wheel_radius_m",
            "axle_track_m",
            "body_radius_m",
            "max_wheel_speed_rad_s",
            "max_wheel_accel_rad_s2",
            "motor_lag_s",
            "ticks_per_rev",
            "pole_pairs",
            "gear_ratio",
            "cell_size_m",
        ],
    ),
    (
        "sim",
        &[
            "step_ms",
            "odometry_hz",
            "clock",
            "seed",
            "slip_std",
            "watchdog_ms",
            "slip_hold_s",
            "lockstep_deadline_ms",
            "kind",
        ],
    ),
    (
        "coordinator",
        &[
            "round_deadline_ms",
            "fsync",
            "replan_after_rounds",
            "time_limit_s",
            "rules",
            "replicas",
            "raft_heartbeat_ms",
            "election_ms",
            "snapshot_entries",
        ],
    ),
    ("run", &["startup_timeout_s", "agents_per_process"]),
    ("restart", &["agent", "coordinator", "sim", "on_give_up"]),
    ("restart.ROLE", &["policy", "max_restarts", "backoff_ms"]),
    (
        "health",
        &[
            "heartbeat_ms",
            "agent_hang_ms",
            "coordinator_hang_ms",
            "sim_hang_ms",
        ],
    ),
    ("record", &["trajectory_hz", "max_mb", "maps"]),
    ("localisation", &["rate_hz", "std_m", "std_deg"]),
    (
        "agents",
        &[
            "start",
            "goal",
            "speed",
            "priority",
            "start_heading_deg",
            "planner",
        ],
    ),
    (
        "faults",
        &[
            "at_round", "at_s", "action", "role", "index", "signal", "for_s",
        ],
    ),
    ("tasks", &["stream", "seed", "goals"]),
    ("tasks.goals", &["agent", "cells"]),
    ("sensing", &["range", "known_map", "repair", "all_knowing"]),
    (
        "ros2",
        &[
            "domain_id",
            "namespace",
            "router",
            "odometry",
            "wheel_joints",
            "silence_s",
        ],
    ),
    (
        "events",
        &[
            "at_round",
            "at_s",
            "close",
            "close_rect",
            "open",
            "open_rect",
            "mover",
            "path",
            "speed",
            "repeat",
            "yields",
        ],
    ),
];

/// Top level.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawScenario {
    pub name: Spanned<String>,
    pub allow_unreachable: Option<bool>,
    pub map: Spanned<RawMap>,
    pub robot: Option<RawRobot>,
    pub sim: Option<RawSim>,
    pub coordinator: Option<RawCoordinator>,
    pub restart: Option<RawRestart>,
    pub run: Option<RawRun>,
    pub health: Option<super::health::RawHealth>,
    pub record: Option<super::record::RawRecord>,
    pub localisation: Option<super::localisation::RawLocalisation>,
    #[serde(default)]
    pub agents: Vec<Spanned<RawAgent>>,
    #[serde(default)]
    pub faults: Vec<Spanned<RawFault>>,
    pub tasks: Option<Spanned<super::tasks::RawTasks>>,
    #[serde(default)]
    pub events: Vec<Spanned<super::events::RawEvent>>,
    pub sensing: Option<super::sensing::RawSensing>,
    pub ros2: Option<super::ros2::RawRos2>,
}

/// `[map]`.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMap {
    pub file: Option<Spanned<String>>,
    pub rows: Option<Spanned<Vec<Spanned<String>>>>,
    pub corner_cutting: Option<bool>,
}

/// `[robot]`.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRobot {
    pub wheel_radius_m: Option<Spanned<f64>>,
    pub axle_track_m: Option<Spanned<f64>>,
    pub body_radius_m: Option<Spanned<f64>>,
    pub max_wheel_speed_rad_s: Option<Spanned<f64>>,
    pub max_wheel_accel_rad_s2: Option<Spanned<f64>>,
    pub motor_lag_s: Option<Spanned<f64>>,
    pub ticks_per_rev: Option<Spanned<f64>>,
    pub pole_pairs: Option<Spanned<u32>>,
    pub gear_ratio: Option<Spanned<f64>>,
    pub cell_size_m: Option<Spanned<f64>>,
}

/// `[sim]`.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSim {
    pub step_ms: Option<Spanned<u32>>,
    pub odometry_hz: Option<Spanned<u32>>,
    pub clock: Option<ClockMode>,
    pub seed: Option<u64>,
    pub slip_std: Option<Spanned<f64>>,
    pub watchdog_ms: Option<Spanned<u32>>,
    pub slip_hold_s: Option<Spanned<f64>>,
    pub lockstep_deadline_ms: Option<u32>,
    pub kind: Option<Spanned<SimKind>>,
}

/// `[coordinator]`.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCoordinator {
    pub round_deadline_ms: Option<Spanned<u32>>,
    pub fsync: Option<FsyncPolicy>,
    pub replan_after_rounds: Option<Spanned<u32>>,
    pub time_limit_s: Option<Spanned<f64>>,
    pub rules: Option<Rules>,
    pub replicas: Option<Spanned<u32>>,
    pub raft_heartbeat_ms: Option<Spanned<u32>>,
    pub election_ms: Option<Spanned<u32>>,
    pub snapshot_entries: Option<Spanned<u64>>,
}

/// `[run]`.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRun {
    pub startup_timeout_s: Option<Spanned<f64>>,
    pub agents_per_process: Option<Spanned<u32>>,
}

/// `[restart]`.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRestart {
    pub agent: Option<RawRestartRule>,
    pub coordinator: Option<RawRestartRule>,
    pub sim: Option<RawRestartRule>,
    pub on_give_up: Option<GiveUpAction>,
}

/// One role's restart rule.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRestartRule {
    pub policy: Option<RestartPolicy>,
    pub max_restarts: Option<u32>,
    pub backoff_ms: Option<u64>,
}

/// One `[[agents]]` entry.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawAgent {
    pub start: Spanned<Vec<i64>>,
    pub goal: Spanned<Vec<i64>>,
    pub speed: Option<Spanned<f64>>,
    pub priority: Option<Spanned<f64>>,
    pub start_heading_deg: Option<Spanned<f64>>,
    pub planner: Option<Planner>,
}

/// What a fault does.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub(super) enum RawFaultAction {
    Kill,
    Freeze,
}

/// Which process a fault hits.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub(super) enum RawRole {
    Agent,
    Coordinator,
    Sim,
}

/// One `[[faults]]` entry. Which keys go together (one time, `signal` only with a kill,
/// `for_s` only with a freeze) is checked in `validate`, where the error can name the line.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFault {
    pub at_round: Option<Spanned<u64>>,
    pub at_s: Option<Spanned<f64>>,
    pub action: RawFaultAction,
    pub role: RawRole,
    pub index: Option<Spanned<i64>>,
    pub signal: Option<Spanned<super::FaultSignal>>,
    pub for_s: Option<Spanned<f64>>,
}
