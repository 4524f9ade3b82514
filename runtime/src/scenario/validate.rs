//! Validation of `[[agents]]` and `[[faults]]`, shared by the TOML path (with lines) and
//! [`Scenario::validate`] (for scenarios changed in code, without lines).

use std::collections::HashMap;

use toml::Spanned;

use super::error::{Loc, ScenarioError};
use super::fault_arg::{check_at_s, check_for_s};
use super::lines::Lines;
use super::params::RobotParams;
use super::raw::{RawAgent, RawFault, RawFaultAction, RawRole};
use super::{
    AgentSpec, FaultAction, FaultSignal, FaultSpec, FaultTarget, FaultTime, MapSpec, Scenario,
};
use crate::grid::{reachable_from, Cell, Endpoint, Grid};
use crate::msg::MAX_AGENTS;

/// Lines of one agent's keys, for errors found after conversion.
#[derive(Clone, Debug)]
pub(super) struct AgentLocs {
    pub start: Loc,
    pub goal: Loc,
    pub speed: Loc,
    pub priority: Loc,
    pub start_heading: Loc,
}

impl AgentLocs {
    /// All keys at one place (used for scenarios built in code).
    pub(super) fn all(at: Loc) -> Self {
        AgentLocs {
            start: at.clone(),
            goal: at.clone(),
            speed: at.clone(),
            priority: at.clone(),
            start_heading: at,
        }
    }
}

pub(super) fn build_agent(
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
        start_heading: lines.at_opt(&a.start_heading_deg, &entry),
    };
    let start = endpoint(i, Endpoint::Start, a.start.get_ref(), grid, &at.start)?;
    let goal = endpoint(i, Endpoint::Goal, a.goal.get_ref(), grid, &at.goal)?;
    let speed = a
        .speed
        .as_ref()
        .map_or(AgentSpec::DEFAULT_SPEED, |s| *s.get_ref());
    let priority = a.priority.as_ref().map(|p| *p.get_ref());
    let start_heading_deg = a.start_heading_deg.as_ref().map_or(0.0, |h| *h.get_ref());
    Ok((
        AgentSpec {
            start,
            goal,
            speed,
            priority,
            start_heading_deg,
            planner: a.planner.unwrap_or_default(),
        },
        at,
    ))
}

/// Turns `[x, y]` into a cell inside the map.
fn endpoint(
    agent: usize,
    which: Endpoint,
    xy: &[i64],
    grid: &Grid,
    at: &Loc,
) -> Result<Cell, ScenarioError> {
    let &[x, y] = xy else {
        return Err(ScenarioError::BadCoordinates {
            at: at.clone(),
            agent,
            endpoint: which,
            len: xy.len(),
        });
    };
    grid.cell_checked(x, y)
        .ok_or_else(|| outside(agent, which, x, y, grid, at))
}

fn outside(agent: usize, which: Endpoint, x: i64, y: i64, grid: &Grid, at: &Loc) -> ScenarioError {
    let (at, width, height) = (at.clone(), grid.width(), grid.height());
    match which {
        Endpoint::Start => ScenarioError::StartOutsideMap {
            at,
            agent,
            x,
            y,
            width,
            height,
        },
        Endpoint::Goal => ScenarioError::GoalOutsideMap {
            at,
            agent,
            x,
            y,
            width,
            height,
        },
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
    check_endpoints(i, a, at, grid)?;
    check_motion(i, a, at, robot)?;
    seen.claim(i, a, at)
}

/// Start and goal inside the map, then both passable (an endpoint outside is reported before
/// any on an obstacle).
fn check_endpoints(
    i: usize,
    a: &AgentSpec,
    at: &AgentLocs,
    grid: &Grid,
) -> Result<(), ScenarioError> {
    let endpoints = [
        (Endpoint::Start, a.start, &at.start),
        (Endpoint::Goal, a.goal, &at.goal),
    ];
    for (which, cell, loc) in endpoints {
        if !grid.contains(cell) {
            return Err(outside(i, which, cell.x.into(), cell.y.into(), grid, loc));
        }
    }
    for (which, cell, loc) in endpoints {
        if let Some(tile) = grid.tile(cell).filter(|t| !t.is_passable()) {
            let (at, ch) = (loc.clone(), tile.to_char());
            return Err(match which {
                Endpoint::Start => ScenarioError::StartOnObstacle {
                    at,
                    agent: i,
                    cell,
                    ch,
                },
                Endpoint::Goal => ScenarioError::GoalOnObstacle {
                    at,
                    agent: i,
                    cell,
                    ch,
                },
            });
        }
    }
    Ok(())
}

/// Speed (positive, within the robot's), priority (positive) and start heading (in range).
fn check_motion(
    i: usize,
    a: &AgentSpec,
    at: &AgentLocs,
    robot: &RobotParams,
) -> Result<(), ScenarioError> {
    if !(a.speed.is_finite() && a.speed > 0.0) {
        return Err(ScenarioError::NonPositiveSpeed {
            at: at.speed.clone(),
            agent: i,
            speed: a.speed,
        });
    }
    let max = robot.max_speed_cells_s();
    if a.speed > max {
        return Err(ScenarioError::SpeedTooHigh {
            at: at.speed.clone(),
            agent: i,
            speed: a.speed,
            max,
        });
    }
    if let Some(p) = a.priority.filter(|p| !(p.is_finite() && *p > 0.0)) {
        return Err(ScenarioError::BadPriority {
            at: at.priority.clone(),
            agent: i,
            priority: p,
        });
    }
    let h = a.start_heading_deg;
    if !(h.is_finite() && h.abs() <= AgentSpec::MAX_START_HEADING_DEG) {
        return Err(ScenarioError::InvalidParameter {
            at: at.start_heading.clone(),
            key: format!("agents[{i}].start_heading_deg"),
            problem: format!(
                "must be a number of degrees in [-{m}, {m}], got {}",
                super::error::number(h),
                m = AgentSpec::MAX_START_HEADING_DEG
            ),
        });
    }
    Ok(())
}

impl Seen {
    /// Takes agent `i`'s start and goal, refused if an earlier agent has either.
    fn claim(&mut self, i: usize, a: &AgentSpec, at: &AgentLocs) -> Result<(), ScenarioError> {
        if let Some(&other) = self.starts.get(&a.start) {
            return Err(ScenarioError::DuplicateStart {
                at: at.start.clone(),
                agent: i,
                other,
                cell: a.start,
            });
        }
        if let Some(&other) = self.goals.get(&a.goal) {
            return Err(ScenarioError::DuplicateGoal {
                at: at.goal.clone(),
                agent: i,
                other,
                cell: a.goal,
            });
        }
        self.starts.insert(a.start, i);
        self.goals.insert(a.goal, i);
        Ok(())
    }
}

/// Fault `i` of the TOML's `[[faults]]`, checked against a run of `agents` agents.
pub(super) fn build_fault(
    i: usize,
    raw: &Spanned<RawFault>,
    agents: usize,
    lines: &Lines<'_>,
) -> Result<FaultSpec, ScenarioError> {
    let entry = lines.at(raw);
    let f = raw.get_ref();
    Ok(FaultSpec {
        target: fault_target(i, f, agents, lines, &entry)?,
        at: fault_time(i, f, lines, entry)?,
        action: fault_action(i, f, lines)?,
    })
}

/// A [`ScenarioError::BadFault`] of fault `i`.
fn bad_fault(i: usize, at: Loc, problem: impl Into<String>) -> ScenarioError {
    ScenarioError::BadFault {
        at,
        fault: i,
        problem: problem.into(),
    }
}

/// Whom fault `i` hits: its `role` and `index`; `entry` is where the fault is written.
fn fault_target(
    i: usize,
    f: &RawFault,
    agents: usize,
    lines: &Lines<'_>,
    entry: &Loc,
) -> Result<FaultTarget, ScenarioError> {
    let Some(ix) = &f.index else {
        return match f.role {
            RawRole::Agent => Err(bad_fault(
                i,
                entry.clone(),
                "role = \"agent\" needs an `index`",
            )),
            RawRole::Coordinator => Ok(FaultTarget::Coordinator),
            RawRole::Sim => Ok(FaultTarget::Sim),
        };
    };
    let index = *ix.get_ref();
    match f.role {
        RawRole::Agent => match usize::try_from(index) {
            Ok(a) if a < agents => Ok(FaultTarget::Agent(a)),
            _ => Err(ScenarioError::FaultAgentOutOfRange {
                at: lines.at(ix),
                fault: i,
                index,
                agents,
            }),
        },
        RawRole::Coordinator => match u32::try_from(index) {
            Ok(id) if (1..=crate::msg::MAX_REPLICAS).contains(&id) => Ok(FaultTarget::Replica(id)),
            _ => Err(bad_fault(
                i,
                lines.at(ix),
                format!(
                    "a coordinator's `index` names a replica, 1 to {}",
                    crate::msg::MAX_REPLICAS
                ),
            )),
        },
        RawRole::Sim => Err(bad_fault(
            i,
            lines.at(ix),
            "`index` is only meaningful with role = \"agent\" or \"coordinator\"",
        )),
    }
}

/// When fault `i` fires: exactly one of `at_round` and `at_s`; `entry` is where the fault is
/// written.
fn fault_time(
    i: usize,
    f: &RawFault,
    lines: &Lines<'_>,
    entry: Loc,
) -> Result<FaultTime, ScenarioError> {
    match (&f.at_round, &f.at_s) {
        (Some(r), None) => Ok(FaultTime::Round(*r.get_ref())),
        (None, Some(s)) => {
            let secs = *s.get_ref();
            check_at_s(secs).map_err(|p| bad_fault(i, lines.at(s), format!("`at_s` {p}")))?;
            Ok(FaultTime::Seconds(secs))
        }
        (Some(_), Some(s)) => Err(bad_fault(
            i,
            lines.at(s),
            "give one of `at_round` and `at_s`, not both",
        )),
        (None, None) => Err(bad_fault(i, entry, "needs `at_round` or `at_s`")),
    }
}

/// What fault `i` does: a kill (with its `signal`) or a freeze (for `for_s`), each refusing
/// the other's key.
fn fault_action(i: usize, f: &RawFault, lines: &Lines<'_>) -> Result<FaultAction, ScenarioError> {
    match f.action {
        RawFaultAction::Kill => {
            if let Some(d) = &f.for_s {
                return Err(bad_fault(
                    i,
                    lines.at(d),
                    "`for_s` is only meaningful with action = \"freeze\"",
                ));
            }
            let signal = f
                .signal
                .as_ref()
                .map_or(FaultSignal::Kill, |s| *s.get_ref());
            Ok(FaultAction::Kill(signal))
        }
        RawFaultAction::Freeze => {
            if let Some(s) = &f.signal {
                return Err(bad_fault(
                    i,
                    lines.at(s),
                    "`signal` is only meaningful with action = \"kill\" (a freeze sends \
                     SIGSTOP, then SIGCONT after `for_s`)",
                ));
            }
            let for_s = f.for_s.as_ref().map(|d| {
                let secs = *d.get_ref();
                check_for_s(secs).map_err(|p| bad_fault(i, lines.at(d), format!("`for_s` {p}")))?;
                Ok(secs)
            });
            Ok(FaultAction::Freeze {
                for_s: for_s.transpose()?,
            })
        }
    }
}

/// Refuses the first agent whose goal is not in its start's connected part of the map (walls
/// and the corner-cutting rule considered; other robots are not walls). `goal_at` gives the
/// place to name for agent `i`.
///
/// Floods the map once per connected part that holds a start rather than once per agent,
/// so a swarm in one open area costs one flood.
pub(super) fn check_reachable(
    agents: &[AgentSpec],
    map: &MapSpec,
    goal_at: impl Fn(usize) -> Loc,
) -> Result<(), ScenarioError> {
    let grid = &map.grid;
    let mut part = vec![u32::MAX; grid.len()];
    let mut parts = 0u32;
    for (i, a) in agents.iter().enumerate() {
        let start = grid.index(a.start);
        if part[start] == u32::MAX {
            let reached = reachable_from(grid, a.start, map.corner_cutting);
            for (label, _) in part.iter_mut().zip(reached).filter(|(_, r)| *r) {
                *label = parts;
            }
            parts += 1;
        }
        if part[grid.index(a.goal)] != part[start] {
            return Err(ScenarioError::UnreachableGoal {
                at: goal_at(i),
                agent: i,
                start: a.start,
                goal: a.goal,
            });
        }
    }
    Ok(())
}

/// Re-checks a scenario built or changed in code (no lines available).
pub(super) fn revalidate(s: &Scenario) -> Result<(), ScenarioError> {
    let at = Loc::new(&s.source_name, 0);
    if s.agents.is_empty() {
        return Err(ScenarioError::NoAgents { at });
    }
    if s.agents.len() > MAX_AGENTS {
        return Err(ScenarioError::TooManyAgents {
            at,
            agents: s.agents.len(),
            max: MAX_AGENTS,
        });
    }
    let locs = AgentLocs::all(at.clone());
    let mut seen = Seen::default();
    for (i, a) in s.agents.iter().enumerate() {
        check_agent(i, a, &locs, &s.map.grid, &s.robot, &mut seen)?;
    }
    if !s.allow_unreachable {
        check_reachable(&s.agents, &s.map, |_| at.clone())?;
    }
    for (i, f) in s.faults.iter().enumerate() {
        let bad = |problem: String| ScenarioError::BadFault {
            at: at.clone(),
            fault: i,
            problem,
        };
        if let FaultTime::Seconds(secs) = f.at {
            check_at_s(secs).map_err(|p| bad(format!("`at_s` {p}")))?;
        }
        if let FaultAction::Freeze { for_s: Some(secs) } = f.action {
            check_for_s(secs).map_err(|p| bad(format!("`for_s` {p}")))?;
        }
        if let FaultTarget::Agent(a) = f.target {
            if a >= s.agents.len() {
                let index = i64::try_from(a).unwrap_or(i64::MAX);
                return Err(ScenarioError::FaultAgentOutOfRange {
                    at,
                    fault: i,
                    index,
                    agents: s.agents.len(),
                });
            }
        }
    }
    Ok(())
}
