//! Unit tests of scenario parsing and validation errors.

use super::test_support::{parse, BASE};
use super::*;
use crate::grid::{Endpoint, GridError};

#[test]
fn defaults_apply() {
    let s = parse(BASE).unwrap();
    assert_eq!(s.name, "t");
    assert_eq!((s.map.grid.width(), s.map.grid.height()), (6, 4));
    assert_eq!(s.map.corner_cutting, CornerCutting::Forbidden);
    assert_eq!(s.map.file, None);
    assert_eq!(s.robot, RobotParams::default());
    assert_eq!(s.sim, SimParams::default());
    assert_eq!(s.coordinator, CoordinatorParams::default());
    assert_eq!(s.restart, RestartConfig::default());
    assert_eq!(s.agents[0].speed, 1.0);
    assert_eq!(s.agents[1].effective_priority(), 0.5);
    assert!(s.faults.is_empty());
    assert!(s.validate().is_ok());
}

#[test]
fn full_file_with_map_file() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("maps")).unwrap();
    std::fs::create_dir(dir.path().join("scenarios")).unwrap();
    std::fs::write(
        dir.path().join("maps/m.map"),
        "type octile\nheight 3\nwidth 4\nmap\n....\n.@..\n....\n",
    )
    .unwrap();
    let text = r#"
name = "full"
[map]
file = "../maps/m.map"
corner_cutting = true
[robot]
wheel_radius_m = 0.03
pole_pairs = 15
gear_ratio = 2
[sim]
step_ms = 2
odometry_hz = 50
clock = "realtime"
seed = 42
slip_std = 0.01
watchdog_ms = 200
slip_hold_s = 0.02
lockstep_deadline_ms = 250
[coordinator]
round_deadline_ms = 20
fsync = "batched"
replan_after_rounds = 5
time_limit_s = 30
[restart]
agent = { policy = "always", max_restarts = 7 }
sim = { backoff_ms = 5 }
[[agents]]
start = [0, 0]
goal = [3, 2]
priority = 4
start_heading_deg = -90
[[faults]]
at_round = 10
action = "kill"
role = "agent"
index = 0
[[faults]]
at_round = 12
action = "kill"
role = "coordinator"
signal = "TERM"
"#;
    let path = dir.path().join("scenarios/full.toml");
    std::fs::write(&path, text).unwrap();
    let s = Scenario::load(&path).unwrap();
    assert_eq!(s.map.corner_cutting, CornerCutting::Allowed);
    assert_eq!(
        s.map.file.as_deref(),
        Some(dir.path().join("scenarios/../maps/m.map").as_path())
    );
    assert_eq!(s.robot.wheel_radius_m, 0.03);
    assert_eq!(s.robot.ticks_per_rev, 180.0);
    assert_eq!(s.sim.clock, ClockMode::Realtime);
    assert_eq!((s.sim.seed, s.sim.step_ms, s.sim.odometry_hz), (42, 2, 50));
    assert_eq!((s.sim.slip_hold_s, s.sim.lockstep_deadline_ms), (0.02, 250));
    assert_eq!(s.coordinator.fsync, FsyncPolicy::Batched);
    assert_eq!(s.coordinator.time_limit_s, 30.0);
    assert_eq!(
        s.restart.agent,
        RestartRule {
            policy: RestartPolicy::Always,
            max_restarts: 7,
            backoff_ms: 100
        }
    );
    assert_eq!(
        s.restart.sim,
        RestartRule {
            policy: RestartPolicy::OnFailure,
            max_restarts: 3,
            backoff_ms: 5
        }
    );
    assert_eq!(s.agents[0].priority, Some(4.0));
    assert_eq!(s.agents[0].start_heading_deg, -90.0);
    assert_eq!(
        s.agents[0].start_heading_rad(),
        -std::f64::consts::FRAC_PI_2
    );
    assert_eq!(s.faults[0].target, FaultTarget::Agent(0));
    assert_eq!(s.faults[0].action, FaultAction::Kill(FaultSignal::Kill));
    assert_eq!(s.faults[0].at, FaultTime::Round(10));
    assert_eq!(s.faults[1].target, FaultTarget::Coordinator);
    assert_eq!(s.faults[1].action, FaultAction::Kill(FaultSignal::Term));

    // A broken map file is reported at its own line, referenced from the scenario.
    std::fs::write(
        dir.path().join("maps/m.map"),
        "type octile\nheight 3\nwidth 4\nmap\n....\n.@.\n....\n",
    )
    .unwrap();
    let e = Scenario::load(&path).unwrap_err();
    assert!(
        matches!(e.grid_error(), Some(GridError::RowWidth { line: 6, .. })),
        "{e}"
    );
    assert!(e.to_string().ends_with(":4)"), "{e}");
    std::fs::remove_file(dir.path().join("maps/m.map")).unwrap();
    let e = Scenario::load(&path).unwrap_err();
    assert!(matches!(e.grid_error(), Some(GridError::Io { .. })), "{e}");
    assert!(matches!(
        Scenario::load(dir.path().join("nope.toml")),
        Err(ScenarioError::Io { .. })
    ));
}

/// Replaces `from` with `to` in BASE and parses; `from` must occur.
fn variant(from: &str, to: &str) -> ScenarioError {
    assert!(BASE.contains(from), "{from}");
    parse(&BASE.replacen(from, to, 1)).unwrap_err()
}

#[test]
fn agent_errors_have_lines() {
    let e = variant("speed = 2.0", "speed = 0");
    assert!(
        matches!(e, ScenarioError::NonPositiveSpeed { agent: 1, .. }),
        "{e}"
    );
    assert_eq!(e.line(), Some(15));
    let e = variant("speed = 2.0", "speed = nan");
    assert!(matches!(e, ScenarioError::NonPositiveSpeed { .. }), "{e}");
    let e = variant("speed = 2.0", "speed = 9.0");
    assert!(
        matches!(e, ScenarioError::SpeedTooHigh { agent: 1, .. }),
        "{e}"
    );
    let e = variant("speed = 2.0", "priority = -3");
    assert!(
        matches!(e, ScenarioError::BadPriority { agent: 1, .. }),
        "{e}"
    );
    assert_eq!(e.line(), Some(15));
    let e = variant("goal = [5, 3]", "goal = [1, 1]");
    assert!(
        matches!(
            e,
            ScenarioError::GoalOnObstacle {
                agent: 0,
                ch: '@',
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(e.line(), Some(11));
    let e = variant("start = [5, 0]", "start = [2, 1]");
    assert!(
        matches!(e, ScenarioError::StartOnObstacle { agent: 1, .. }),
        "{e}"
    );
    assert_eq!(e.line(), Some(13));
    let e = variant("start = [5, 0]", "start = [6, 0]");
    assert!(
        matches!(
            e,
            ScenarioError::StartOutsideMap {
                agent: 1,
                x: 6,
                y: 0,
                width: 6,
                height: 4,
                ..
            }
        ),
        "{e}"
    );
    let e = variant("goal = [5, 3]", "goal = [-1, 3]");
    assert!(
        matches!(e, ScenarioError::GoalOutsideMap { x: -1, .. }),
        "{e}"
    );
    let e = variant("goal = [5, 3]", "goal = [5, 3, 1]");
    assert!(
        matches!(
            e,
            ScenarioError::BadCoordinates {
                endpoint: Endpoint::Goal,
                len: 3,
                ..
            }
        ),
        "{e}"
    );
    let e = variant("start = [5, 0]", "start = [0, 0]");
    assert!(
        matches!(
            e,
            ScenarioError::DuplicateStart {
                agent: 1,
                other: 0,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(e.line(), Some(13));
    let e = variant("goal = [0, 3]", "goal = [5, 3]");
    assert!(
        matches!(
            e,
            ScenarioError::DuplicateGoal {
                agent: 1,
                other: 0,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(e.line(), Some(14));
}

#[test]
fn structural_errors() {
    let no_agents: String = BASE.lines().take(8).map(|l| format!("{l}\n")).collect();
    assert!(matches!(
        parse(&no_agents),
        Err(ScenarioError::NoAgents { .. })
    ));
    let e = variant("[map]\n", "[map]\nfile = \"x.map\"\n");
    assert!(matches!(e, ScenarioError::MapFileAndRows { .. }), "{e}");
    assert_eq!(e.line(), Some(2));
    let e = parse("name = \"t\"\n[map]\ncorner_cutting = true\n").unwrap_err();
    assert!(matches!(e, ScenarioError::NoMapSource { .. }), "{e}");
    let e = variant("[map]\n", "[map]\ncolour = 3\n");
    assert_eq!(
        e,
        ScenarioError::UnknownKey {
            at: Loc::new("t.toml", 3),
            key: "colour".into(),
            expected: "expected one of `file`, `rows`, `corner_cutting`".into()
        }
    );
    let e = variant("name = \"t\"\n", "");
    assert!(
        matches!(&e, ScenarioError::MissingKey { key, .. } if key == "name"),
        "{e}"
    );
    let e = variant("speed = 2.0", "speed = \"fast\"");
    assert!(matches!(e, ScenarioError::Toml { .. }), "{e}");
    assert_eq!(e.line(), Some(15));
    let e = variant("\"...@..\",", "\"...@.\",");
    assert!(
        matches!(
            e.grid_error(),
            Some(GridError::RowWidth {
                line: 7,
                found: 5,
                expected: 6,
                ..
            })
        ),
        "{e}"
    );
    let e = variant("\"...@..\",", "\"...@.x\",");
    assert!(
        matches!(
            e.grid_error(),
            Some(GridError::UnknownChar {
                line: 7,
                column: 6,
                ..
            })
        ),
        "{e}"
    );
    let e = parse("name = \"t\"\n[map]\nrows = []\n").unwrap_err();
    assert!(
        matches!(e.grid_error(), Some(GridError::BadShape { line: 3, .. })),
        "{e}"
    );
    let e = parse("name = = 3").unwrap_err();
    assert!(matches!(e, ScenarioError::Toml { .. }), "{e}");
}

#[test]
fn replicas_are_one_three_or_five_and_elections_span_heartbeats() {
    let s = parse(&format!(
        "{BASE}[coordinator]\nreplicas = 5\nraft_heartbeat_ms = 20\nelection_ms = 300\n"
    ))
    .unwrap();
    let c = &s.coordinator;
    assert_eq!((c.replicas, c.election_ticks()), (5, 15));
    // Replicas decide what one coordinator decides: the hash leaves them out.
    assert_eq!(s.scenario_hash(), parse(BASE).unwrap().scenario_hash());
    let e = parse(&format!("{BASE}[coordinator]\nreplicas = 2\n")).unwrap_err();
    assert!(
        matches!(&e, ScenarioError::InvalidParameter { key, .. } if key == "coordinator.replicas"),
        "{e}"
    );
    assert_eq!(e.line(), Some(17));
    assert!(e.to_string().contains("2 replicas; a cluster has 1"), "{e}");
    let e = parse(&format!(
        "{BASE}[coordinator]\nraft_heartbeat_ms = 100\nelection_ms = 250\n"
    ))
    .unwrap_err();
    assert!(
        e.to_string()
            .contains("250 ms is less than 3 heartbeats of 100 ms"),
        "{e}"
    );
    assert_eq!(e.line(), Some(18));
}

#[test]
fn parameter_errors() {
    let e = parse(&format!("{BASE}[robot]\nwheel_radius_m = -0.1\n")).unwrap_err();
    assert!(
        matches!(&e, ScenarioError::InvalidParameter { key, .. } if key == "robot.wheel_radius_m"),
        "{e}"
    );
    assert_eq!(e.line(), Some(17));
    let e = parse(&format!(
        "{BASE}[robot]\nticks_per_rev = 42\npole_pairs = 7\n"
    ))
    .unwrap_err();
    assert!(
        matches!(&e, ScenarioError::InvalidParameter { key, .. } if key == "robot.ticks_per_rev"),
        "{e}"
    );
    let e = parse(&format!("{BASE}[robot]\nbody_radius_m = 0.09\n")).unwrap_err();
    assert!(
        matches!(&e, ScenarioError::InvalidParameter { key, .. } if key == "robot.body_radius_m"),
        "{e}"
    );
    let e = parse(&format!("{BASE}[sim]\nstep_ms = 0\n")).unwrap_err();
    assert!(
        matches!(&e, ScenarioError::InvalidParameter { key, .. } if key == "sim.step_ms"),
        "{e}"
    );
    let e = parse(&format!("{BASE}[sim]\nstep_ms = 20\nodometry_hz = 100\n")).unwrap_err();
    assert!(
        matches!(&e, ScenarioError::InvalidParameter { key, .. } if key == "sim.odometry_hz"),
        "{e}"
    );
    let e = parse(&format!("{BASE}[sim]\nclock = \"fast\"\n")).unwrap_err();
    assert!(matches!(e, ScenarioError::Toml { .. }), "{e}");
    assert_eq!(e.line(), Some(17));
    let e = parse(&format!("{BASE}[coordinator]\ntime_limit_s = 0\n")).unwrap_err();
    assert!(
        matches!(&e, ScenarioError::InvalidParameter { key, .. } if key == "coordinator.time_limit_s"),
        "{e}"
    );
    let e = parse(&format!(
        "{BASE}[restart]\nagent = {{ policy = \"sometimes\" }}\n"
    ))
    .unwrap_err();
    assert!(matches!(e, ScenarioError::Toml { .. }), "{e}");
}

#[test]
fn fault_errors() {
    let fault = |body: &str| {
        parse(&format!(
            "{BASE}[[faults]]\nat_round = 1\naction = \"kill\"\n{body}"
        ))
    };
    assert!(fault("role = \"sim\"\n").is_ok());
    let e = fault("role = \"agent\"\nindex = 2\n").unwrap_err();
    assert!(
        matches!(
            e,
            ScenarioError::FaultAgentOutOfRange {
                fault: 0,
                index: 2,
                agents: 2,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(e.line(), Some(20));
    let e = fault("role = \"agent\"\nindex = -1\n").unwrap_err();
    assert!(
        matches!(e, ScenarioError::FaultAgentOutOfRange { index: -1, .. }),
        "{e}"
    );
    let e = fault("role = \"agent\"\n").unwrap_err();
    assert!(matches!(e, ScenarioError::BadFault { fault: 0, .. }), "{e}");
    let e = fault("role = \"sim\"\nindex = 0\n").unwrap_err();
    assert!(matches!(e, ScenarioError::BadFault { .. }), "{e}");
    let e = fault("role = \"agent\"\nindex = 0\nsignal = \"HUP\"\n").unwrap_err();
    assert!(matches!(e, ScenarioError::Toml { .. }), "{e}");
}

#[test]
fn sim_timing_keys_and_start_headings() {
    // Defaults: slip held 10 ms, no lockstep deadline (liveness from peer events), every
    // robot facing +x.
    let s = parse(BASE).unwrap();
    assert_eq!(s.sim.slip_hold_s, 0.010);
    assert_eq!(s.sim.lockstep_deadline_ms, 0);
    assert!(s.agents.iter().all(|a| a.start_heading_deg == 0.0));
    let s = parse(&format!(
        "{BASE}[sim]\nlockstep_deadline_ms = 0\nslip_hold_s = 1e-3\n"
    ))
    .unwrap();
    assert_eq!((s.sim.lockstep_deadline_ms, s.sim.slip_hold_s), (0, 1e-3));
    let turned = parse(&BASE.replacen("speed = 2.0", "speed = 2.0\nstart_heading_deg = 180", 1));
    assert_eq!(turned.unwrap().agents[1].start_heading_deg, 180.0);

    // Errors carry the key's line.
    for bad in [
        "slip_hold_s = 0",
        "slip_hold_s = -0.01",
        "slip_hold_s = nan",
    ] {
        let e = parse(&format!("{BASE}[sim]\n{bad}\n")).unwrap_err();
        assert!(
            matches!(&e, ScenarioError::InvalidParameter { key, .. } if key == "sim.slip_hold_s"),
            "{e}"
        );
        assert_eq!(e.line(), Some(17), "{e}");
    }
    for bad in ["lockstep_deadline_ms = -1", "lockstep_deadline_ms = 0.5"] {
        let e = parse(&format!("{BASE}[sim]\n{bad}\n")).unwrap_err();
        assert!(matches!(e, ScenarioError::Toml { .. }), "{e}");
        assert_eq!(e.line(), Some(17), "{e}");
    }
    for bad in ["start_heading_deg = 361", "start_heading_deg = inf"] {
        let e = variant("speed = 2.0", &format!("speed = 2.0\n{bad}"));
        assert!(
            matches!(&e, ScenarioError::InvalidParameter { key, .. } if key == "agents[1].start_heading_deg"),
            "{e}"
        );
        assert_eq!(e.line(), Some(16), "{e}");
    }
    let e = variant("speed = 2.0", "speed = 2.0\nstart_heading_deg = \"north\"");
    assert!(matches!(e, ScenarioError::Toml { .. }), "{e}");
    assert_eq!(e.line(), Some(16));

    // Scenarios changed in code are re-checked too, and the hash covers the new fields.
    let mut c = parse(BASE).unwrap();
    let h = c.scenario_hash();
    c.agents[0].start_heading_deg = 45.0;
    assert!(c.validate().is_ok());
    assert_ne!(c.scenario_hash(), h);
    c.agents[0].start_heading_deg = f64::NAN;
    assert!(matches!(
        c.validate(),
        Err(ScenarioError::InvalidParameter { .. })
    ));
    for change in [
        |s: &mut Scenario| s.sim.lockstep_deadline_ms = 500,
        |s: &mut Scenario| s.sim.slip_hold_s = 0.02,
    ] {
        let mut d = parse(BASE).unwrap();
        change(&mut d);
        assert_ne!(d.scenario_hash(), h);
    }
}
