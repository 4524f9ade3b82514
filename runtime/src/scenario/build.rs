//! From TOML text to a validated [`Scenario`]: parse with `serde`, then check every semantic
//! rule, turning `toml` spans into line numbers for the errors.

use std::collections::HashMap;
use std::path::Path;

use toml::Spanned;

use super::error::{Loc, ScenarioError};
use super::params::{CoordinatorParams, RestartConfig, RestartRule, RobotParams, SimParams};
use super::raw::{
    RawAgent, RawCoordinator, RawFault, RawFaultAction, RawMap, RawRestart, RawRestartRule, RawRobot, RawRole,
    RawScenario, RawSim,
};
use super::{AgentSpec, FaultAction, FaultSignal, FaultSpec, FaultTarget, MapSpec, Scenario};
use crate::grid::{read_map_file, read_map_rows, Cell, CornerCutting, Endpoint, Grid, GridError};

/// Byte offset to 1-based line.
pub(super) struct Lines<'a> {
    source_name: &'a str,
    starts: Vec<usize>,
}

impl<'a> Lines<'a> {
    pub(super) fn new(text: &str, source_name: &'a str) -> Self {
        let starts = std::iter::once(0).chain(text.match_indices('\n').map(|(i, _)| i + 1)).collect();
        Lines { source_name, starts }
    }

    fn line(&self, offset: usize) -> usize {
        self.starts.partition_point(|&s| s <= offset).max(1)
    }

    fn at<T>(&self, s: &Spanned<T>) -> Loc {
        Loc::new(self.source_name, self.line(s.span().start))
    }

    fn at_opt<T>(&self, s: &Option<Spanned<T>>, fallback: &Loc) -> Loc {
        s.as_ref().map_or_else(|| fallback.clone(), |s| self.at(s))
    }
}

/// Converts a `toml` error, recognising serde's unknown/missing field messages so they get
/// their own variants.
pub(super) fn toml_error(e: &toml::de::Error, lines: &Lines<'_>) -> ScenarioError {
    let at = Loc::new(lines.source_name, e.span().map_or(1, |s| lines.line(s.start)));
    let message = e.message().trim().to_string();
    let quoted = |rest: &str| rest.split_once('`').map(|(key, tail)| (key.to_string(), tail.to_string()));
    if let Some((key, tail)) = message.strip_prefix("unknown field `").and_then(quoted) {
        let expected = tail.trim_start_matches(',').trim().to_string();
        return ScenarioError::UnknownKey { at, key, expected };
    }
    if let Some((key, _)) = message.strip_prefix("missing field `").and_then(quoted) {
        return ScenarioError::MissingKey { at, key };
    }
    ScenarioError::Toml { at, message }
}

/// Parses and validates a scenario.
pub(super) fn parse(text: &str, source_name: &str, base_dir: &Path) -> Result<Scenario, ScenarioError> {
    let lines = Lines::new(text, source_name);
    let raw: RawScenario = toml::from_str(text).map_err(|e| toml_error(&e, &lines))?;
    let map = build_map(&raw.map, &lines, base_dir)?;
    let robot = build_robot(raw.robot, &lines)?;
    let sim = build_sim(raw.sim, &lines)?;
    let coordinator = build_coordinator(raw.coordinator, &lines)?;
    let restart = build_restart(raw.restart);
    if raw.agents.is_empty() {
        return Err(ScenarioError::NoAgents { at: Loc::new(source_name, 1) });
    }
    let mut agents = Vec::with_capacity(raw.agents.len());
    let mut seen = Seen::default();
    for (i, a) in raw.agents.iter().enumerate() {
        let (spec, at) = build_agent(i, a, &map.grid, &lines)?;
        check_agent(i, &spec, &at, &map.grid, &robot, &mut seen)?;
        agents.push(spec);
    }
    let mut faults = Vec::with_capacity(raw.faults.len());
    for (i, f) in raw.faults.iter().enumerate() {
        faults.push(build_fault(i, f, agents.len(), &lines)?);
    }
    Ok(Scenario {
        name: raw.name.into_inner(),
        source_name: source_name.into(),
        map,
        robot,
        sim,
        coordinator,
        restart,
        agents,
        faults,
    })
}

fn build_map(raw: &Spanned<RawMap>, lines: &Lines<'_>, base_dir: &Path) -> Result<MapSpec, ScenarioError> {
    let at = lines.at(raw);
    let m = raw.get_ref();
    let corner_cutting = if m.corner_cutting.unwrap_or(false) {
        CornerCutting::Allowed
    } else {
        CornerCutting::Forbidden
    };
    match (&m.file, &m.rows) {
        (Some(_), Some(_)) => Err(ScenarioError::MapFileAndRows { at }),
        (None, None) => Err(ScenarioError::NoMapSource { at }),
        (Some(file), None) => {
            let path = base_dir.join(file.get_ref());
            let grid = read_map_file(&path)
                .map_err(|error| ScenarioError::Map { referenced_from: Some(lines.at(file)), error })?;
            Ok(MapSpec { grid, file: Some(path), corner_cutting })
        }
        (None, Some(rows)) => {
            let map_err = |error| ScenarioError::Map { referenced_from: None, error };
            if rows.get_ref().is_empty() {
                return Err(map_err(GridError::BadShape {
                    source_name: lines.source_name.into(),
                    line: lines.at(rows).line,
                    width: 0,
                    height: 0,
                    problem: "`rows` is empty".into(),
                }));
            }
            let numbered = rows.get_ref().iter().map(|r| (lines.at(r).line, r.get_ref().as_str()));
            let grid = read_map_rows(numbered, lines.source_name).map_err(map_err)?;
            Ok(MapSpec { grid, file: None, corner_cutting })
        }
    }
}

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
    let problem = if positive { "must be a positive number" } else { "must be a number >= 0" };
    Err(ScenarioError::InvalidParameter { at, key: key.into(), problem: format!("{problem}, got {x}") })
}

/// Reads an optional integer with a default and checks it is at least 1.
fn count(v: &Option<Spanned<u32>>, default: u32, key: &str, lines: &Lines<'_>) -> Result<u32, ScenarioError> {
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

fn build_robot(raw: Option<RawRobot>, lines: &Lines<'_>) -> Result<RobotParams, ScenarioError> {
    let d = RobotParams::default();
    let Some(r) = raw else { return Ok(d) };
    let none = Loc::new(lines.source_name, 0);
    let pos = |v: &Option<Spanned<f64>>, def: f64, key: &str| float(v, def, key, true, &none, lines);
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
            let pole_pairs = count(pp, RobotParams::DEFAULT_POLE_PAIRS, "robot.pole_pairs", lines)?;
            let gear = pos(&r.gear_ratio, 1.0, "robot.gear_ratio")?;
            6.0 * f64::from(pole_pairs) * gear
        }
    };
    let p = RobotParams {
        wheel_radius_m: pos(&r.wheel_radius_m, d.wheel_radius_m, "robot.wheel_radius_m")?,
        axle_track_m: pos(&r.axle_track_m, d.axle_track_m, "robot.axle_track_m")?,
        body_radius_m: pos(&r.body_radius_m, d.body_radius_m, "robot.body_radius_m")?,
        max_wheel_speed_rad_s: pos(&r.max_wheel_speed_rad_s, d.max_wheel_speed_rad_s, "robot.max_wheel_speed_rad_s")?,
        max_wheel_accel_rad_s2: pos(
            &r.max_wheel_accel_rad_s2,
            d.max_wheel_accel_rad_s2,
            "robot.max_wheel_accel_rad_s2",
        )?,
        motor_lag_s: float(&r.motor_lag_s, d.motor_lag_s, "robot.motor_lag_s", false, &none, lines)?,
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

fn build_sim(raw: Option<RawSim>, lines: &Lines<'_>) -> Result<SimParams, ScenarioError> {
    let d = SimParams::default();
    let Some(s) = raw else { return Ok(d) };
    let none = Loc::new(lines.source_name, 0);
    let p = SimParams {
        step_ms: count(&s.step_ms, d.step_ms, "sim.step_ms", lines)?,
        odometry_hz: count(&s.odometry_hz, d.odometry_hz, "sim.odometry_hz", lines)?,
        clock: s.clock.unwrap_or(d.clock),
        seed: s.seed.unwrap_or(d.seed),
        slip_std: float(&s.slip_std, d.slip_std, "sim.slip_std", false, &none, lines)?,
        watchdog_ms: count(&s.watchdog_ms, d.watchdog_ms, "sim.watchdog_ms", lines)?,
    };
    // Odometry is sampled on physics steps, so it cannot be faster than one message per step.
    if u64::from(p.odometry_hz) * u64::from(p.step_ms) > 1000 {
        let at = lines.at_opt(&s.odometry_hz, &lines.at_opt(&s.step_ms, &none));
        return Err(ScenarioError::InvalidParameter {
            at,
            key: "sim.odometry_hz".into(),
            problem: format!("{} Hz is faster than one message per {} ms step", p.odometry_hz, p.step_ms),
        });
    }
    Ok(p)
}

fn build_coordinator(raw: Option<RawCoordinator>, lines: &Lines<'_>) -> Result<CoordinatorParams, ScenarioError> {
    let d = CoordinatorParams::default();
    let Some(c) = raw else { return Ok(d) };
    let none = Loc::new(lines.source_name, 0);
    Ok(CoordinatorParams {
        round_deadline_ms: count(&c.round_deadline_ms, d.round_deadline_ms, "coordinator.round_deadline_ms", lines)?,
        fsync: c.fsync.unwrap_or(d.fsync),
        replan_after_rounds: count(
            &c.replan_after_rounds,
            d.replan_after_rounds,
            "coordinator.replan_after_rounds",
            lines,
        )?,
        time_limit_s: float(&c.time_limit_s, d.time_limit_s, "coordinator.time_limit_s", true, &none, lines)?,
    })
}

fn build_restart(raw: Option<RawRestart>) -> RestartConfig {
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
    }
}

/// Lines of one agent's keys, for errors found after conversion.
#[derive(Clone, Debug)]
pub(super) struct AgentLocs {
    pub start: Loc,
    pub goal: Loc,
    pub speed: Loc,
    pub priority: Loc,
}

impl AgentLocs {
    /// All keys at one place (used for scenarios built in code).
    pub(super) fn all(at: Loc) -> Self {
        AgentLocs { start: at.clone(), goal: at.clone(), speed: at.clone(), priority: at }
    }
}

fn build_agent(
    i: usize,
    raw: &Spanned<RawAgent>,
    grid: &Grid,
    lines: &Lines<'_>,
) -> Result<(AgentSpec, AgentLocs), ScenarioError> {
    let entry = lines.at(raw);
    let a = raw.get_ref();
    let at = AgentLocs {
        start: lines.at(&a.start),
        goal: lines.at(&a.goal),
        speed: lines.at_opt(&a.speed, &entry),
        priority: lines.at_opt(&a.priority, &entry),
    };
    let start = endpoint(i, Endpoint::Start, a.start.get_ref(), grid, &at.start)?;
    let goal = endpoint(i, Endpoint::Goal, a.goal.get_ref(), grid, &at.goal)?;
    let speed = a.speed.as_ref().map_or(AgentSpec::DEFAULT_SPEED, |s| *s.get_ref());
    let priority = a.priority.as_ref().map(|p| *p.get_ref());
    Ok((AgentSpec { start, goal, speed, priority }, at))
}

/// Turns `[x, y]` into a cell inside the map.
fn endpoint(agent: usize, which: Endpoint, xy: &[i64], grid: &Grid, at: &Loc) -> Result<Cell, ScenarioError> {
    let &[x, y] = xy else {
        return Err(ScenarioError::BadCoordinates { at: at.clone(), agent, endpoint: which, len: xy.len() });
    };
    grid.cell_checked(x, y).ok_or_else(|| outside(agent, which, x, y, grid, at))
}

fn outside(agent: usize, which: Endpoint, x: i64, y: i64, grid: &Grid, at: &Loc) -> ScenarioError {
    let (at, width, height) = (at.clone(), grid.width(), grid.height());
    match which {
        Endpoint::Start => ScenarioError::StartOutsideMap { at, agent, x, y, width, height },
        Endpoint::Goal => ScenarioError::GoalOutsideMap { at, agent, x, y, width, height },
    }
}

/// Starts and goals of the agents checked so far.
#[derive(Default)]
pub(super) struct Seen {
    starts: HashMap<Cell, usize>,
    goals: HashMap<Cell, usize>,
}

/// The per-agent rules that do not depend on how the agent was written down.
pub(super) fn check_agent(
    i: usize,
    a: &AgentSpec,
    at: &AgentLocs,
    grid: &Grid,
    robot: &RobotParams,
    seen: &mut Seen,
) -> Result<(), ScenarioError> {
    for (which, cell, loc) in [(Endpoint::Start, a.start, &at.start), (Endpoint::Goal, a.goal, &at.goal)] {
        if !grid.contains(cell) {
            return Err(outside(i, which, cell.x.into(), cell.y.into(), grid, loc));
        }
    }
    for (which, cell, loc) in [(Endpoint::Start, a.start, &at.start), (Endpoint::Goal, a.goal, &at.goal)] {
        if let Some(tile) = grid.tile(cell).filter(|t| !t.is_passable()) {
            let (at, ch) = (loc.clone(), tile.to_char());
            return Err(match which {
                Endpoint::Start => ScenarioError::StartOnObstacle { at, agent: i, cell, ch },
                Endpoint::Goal => ScenarioError::GoalOnObstacle { at, agent: i, cell, ch },
            });
        }
    }
    if !(a.speed.is_finite() && a.speed > 0.0) {
        return Err(ScenarioError::NonPositiveSpeed { at: at.speed.clone(), agent: i, speed: a.speed });
    }
    let max = robot.max_speed_cells_s();
    if a.speed > max {
        return Err(ScenarioError::SpeedTooHigh { at: at.speed.clone(), agent: i, speed: a.speed, max });
    }
    if let Some(p) = a.priority.filter(|p| !(p.is_finite() && *p > 0.0)) {
        return Err(ScenarioError::BadPriority { at: at.priority.clone(), agent: i, priority: p });
    }
    if let Some(&other) = seen.starts.get(&a.start) {
        return Err(ScenarioError::DuplicateStart { at: at.start.clone(), agent: i, other, cell: a.start });
    }
    if let Some(&other) = seen.goals.get(&a.goal) {
        return Err(ScenarioError::DuplicateGoal { at: at.goal.clone(), agent: i, other, cell: a.goal });
    }
    seen.starts.insert(a.start, i);
    seen.goals.insert(a.goal, i);
    Ok(())
}

fn build_fault(i: usize, raw: &Spanned<RawFault>, agents: usize, lines: &Lines<'_>) -> Result<FaultSpec, ScenarioError> {
    let at = lines.at(raw);
    let f = raw.get_ref();
    let target = match (f.role, &f.index) {
        (RawRole::Agent, None) => {
            return Err(ScenarioError::BadFault { at, fault: i, problem: "role = \"agent\" needs an `index`".into() })
        }
        (RawRole::Agent, Some(ix)) => {
            let index = *ix.get_ref();
            match usize::try_from(index) {
                Ok(a) if a < agents => FaultTarget::Agent(a),
                _ => return Err(ScenarioError::FaultAgentOutOfRange { at: lines.at(ix), fault: i, index, agents }),
            }
        }
        (_, Some(ix)) => {
            return Err(ScenarioError::BadFault {
                at: lines.at(ix),
                fault: i,
                problem: "`index` is only meaningful with role = \"agent\"".into(),
            })
        }
        (RawRole::Coordinator, None) => FaultTarget::Coordinator,
        (RawRole::Sim, None) => FaultTarget::Sim,
    };
    let action = match f.action {
        RawFaultAction::Kill => FaultAction::Kill,
    };
    Ok(FaultSpec { at_round: f.at_round, action, target, signal: f.signal.unwrap_or(FaultSignal::Kill) })
}

/// Re-checks a scenario built or changed in code (no lines available).
pub(super) fn revalidate(s: &Scenario) -> Result<(), ScenarioError> {
    let at = Loc::new(&s.source_name, 0);
    if s.agents.is_empty() {
        return Err(ScenarioError::NoAgents { at });
    }
    let locs = AgentLocs::all(at.clone());
    let mut seen = Seen::default();
    for (i, a) in s.agents.iter().enumerate() {
        check_agent(i, a, &locs, &s.map.grid, &s.robot, &mut seen)?;
    }
    for (i, f) in s.faults.iter().enumerate() {
        if let FaultTarget::Agent(a) = f.target {
            if a >= s.agents.len() {
                let index = i64::try_from(a).unwrap_or(i64::MAX);
                return Err(ScenarioError::FaultAgentOutOfRange { at, fault: i, index, agents: s.agents.len() });
            }
        }
    }
    Ok(())
}
