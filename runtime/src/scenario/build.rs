//! From TOML text to a validated [`Scenario`]: parse with `serde`, then check every semantic
//! rule, turning `toml` spans into line numbers for the errors (`lines`). The parameter
//! sections are checked in `build_params`, agents and faults in `validate`.

use std::path::Path;

use toml::Spanned;

use super::build_params::{build_coordinator, build_restart, build_robot, build_run, build_sim};
use super::error::{Loc, ScenarioError};
use super::lines::{toml_error, Lines};
use super::params::SimKind;
use super::raw::{RawMap, RawScenario};
use super::validate::{build_agent, build_fault, check_agent, check_reachable, Seen};
use super::{MapSpec, Scenario};
use crate::grid::{read_map_file, read_map_rows, CornerCutting, GridError};
use crate::msg::MAX_AGENTS;

/// Parses and validates a scenario.
pub(super) fn parse(
    text: &str,
    source_name: &str,
    base_dir: &Path,
) -> Result<Scenario, ScenarioError> {
    let lines = Lines::new(text, source_name);
    let raw: RawScenario = toml::from_str(text).map_err(|e| toml_error(&e, &lines))?;
    let map = build_map(&raw.map, &lines, base_dir)?;
    let robot = build_robot(raw.robot, &lines)?;
    let outside = (raw.sim.as_ref())
        .and_then(|s| s.kind.as_ref())
        .filter(|k| *k.get_ref() == SimKind::Ros2)
        .map(|k| lines.at(k));
    let sim = build_sim(raw.sim, &lines)?;
    let coordinator = build_coordinator(raw.coordinator, &lines)?;
    let restart = build_restart(raw.restart);
    let run = build_run(raw.run, &lines)?;
    let health = super::health::build_health(raw.health, &lines)?;
    let record = super::record::build_record(raw.record, &lines)?;
    let sensing = super::sensing::build_sensing(raw.sensing, &lines)?;
    let ros2 = super::ros2::build_ros2(raw.ros2, &lines)?;
    let localisation =
        super::localisation::build_localisation(raw.localisation, sim.odometry_hz, &lines)?;
    if raw.agents.is_empty() {
        return Err(ScenarioError::NoAgents {
            at: Loc::new(source_name, 1),
        });
    }
    if let Some(extra) = raw.agents.get(MAX_AGENTS) {
        return Err(ScenarioError::TooManyAgents {
            at: lines.at(extra),
            agents: raw.agents.len(),
            max: MAX_AGENTS,
        });
    }
    let allow_unreachable = raw.allow_unreachable.unwrap_or(false);
    let mut agents = Vec::with_capacity(raw.agents.len());
    let mut goal_locs = Vec::with_capacity(raw.agents.len());
    let mut seen = Seen::default();
    for (i, a) in raw.agents.iter().enumerate() {
        let (spec, at) = build_agent(i, a, &map.grid, &lines)?;
        check_agent(i, &spec, &at, &map.grid, &robot, &mut seen)?;
        agents.push(spec);
        goal_locs.push(at.goal);
    }
    if !allow_unreachable {
        check_reachable(&agents, &map, |i| goal_locs[i].clone())?;
    }
    let mut faults = Vec::with_capacity(raw.faults.len());
    for (i, f) in raw.faults.iter().enumerate() {
        faults.push(build_fault(i, f, agents.len(), &lines)?);
    }
    let tasks = super::tasks::build_tasks(
        raw.tasks,
        sim.seed,
        &agents,
        (&map.grid, map.corner_cutting),
        &lines,
    )?;
    if let Some(at) = outside {
        // The world of robots outside HNAV is theirs: HNAV can neither close its doors nor
        // see for its robots.
        let what = [
            (!raw.events.is_empty(), "[[events]]"),
            (sensing.is_some(), "[sensing]"),
        ];
        if let Some((_, what)) = what.iter().find(|w| w.0) {
            return Err(ScenarioError::InvalidParameter {
                at,
                key: "sim.kind".into(),
                problem: format!(
                    "\"ros2\" drives robots outside HNAV, whose world HNAV does not simulate: {what} needs kind = \"hnav\""
                ),
            });
        }
    }
    let events = super::events::build_events(raw.events, &map.grid, &agents, &sim, &lines)?;
    Ok(Scenario {
        name: raw.name.into_inner(),
        source_name: source_name.into(),
        map,
        robot,
        sim,
        coordinator,
        restart,
        run,
        health,
        record,
        localisation,
        agents,
        faults,
        allow_unreachable,
        tasks,
        events,
        sensing,
        ros2,
    })
}

fn build_map(
    raw: &Spanned<RawMap>,
    lines: &Lines<'_>,
    base_dir: &Path,
) -> Result<MapSpec, ScenarioError> {
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
            let grid = read_map_file(&path).map_err(|error| ScenarioError::Map {
                referenced_from: Some(lines.at(file)),
                error: Box::new(error),
            })?;
            Ok(MapSpec {
                grid,
                file: Some(path),
                corner_cutting,
            })
        }
        (None, Some(rows)) => {
            let map_err = |error| ScenarioError::Map {
                referenced_from: None,
                error: Box::new(error),
            };
            if rows.get_ref().is_empty() {
                return Err(map_err(GridError::BadShape {
                    source_name: lines.source_name.into(),
                    line: lines.at(rows).line,
                    width: 0,
                    height: 0,
                    problem: "`rows` is empty".into(),
                }));
            }
            let numbered = rows
                .get_ref()
                .iter()
                .map(|r| (lines.at(r).line, r.get_ref().as_str()));
            let grid = read_map_rows(numbered, lines.source_name).map_err(map_err)?;
            Ok(MapSpec {
                grid,
                file: None,
                corner_cutting,
            })
        }
    }
}
