//! Unit tests of the scenario hash, agent generation, re-validation and the report.

use super::test_support::{parse, BASE};
use super::*;
use crate::grid::octile_shortest_path_len;

#[test]
fn hash_is_canonical() {
    let a = parse(BASE).unwrap();
    let reformatted = BASE
        .replace("name = \"t\"", "# a comment\nname = \"other name\"")
        .replace("speed = 2.0", "speed = 2");
    let b = parse(&reformatted).unwrap();
    assert_eq!(
        a.scenario_hash(),
        b.scenario_hash(),
        "comments, name and number formatting do not count"
    );
    let mut c = a.clone();
    c.agents[1].speed = 1.5;
    assert_ne!(a.scenario_hash(), c.scenario_hash());
    let mut d = a.clone();
    d.sim.seed = 1;
    assert_ne!(a.scenario_hash(), d.scenario_hash());
    let mut e = a.clone();
    e.map.grid.set_blocked(Cell::new(5, 0), true);
    assert_ne!(a.scenario_hash(), e.scenario_hash());
    let mut f = a.clone();
    f.map.corner_cutting = CornerCutting::Allowed;
    assert_ne!(a.scenario_hash(), f.scenario_hash());
    // Pinned so an accidental change of the encoding is noticed (the log depends on it): the
    // hash of this scenario under the dissertation's rules, written before `rules` existed and
    // kept by naming `rules = "dissertation"`.
    let mut old = a.clone();
    old.coordinator.rules = Rules::Dissertation;
    assert_eq!(format!("{:016x}", old.scenario_hash()), "f19f0d3456037630");
}

#[test]
fn agent_count_truncates_and_grows() {
    let s = parse(BASE).unwrap();
    let one = s.with_agent_count(1, 0).unwrap();
    assert_eq!(one.agents, s.agents[..1].to_vec());
    // The scenario has agents: it is the count that is wrong, and the message says so.
    let e = s.with_agent_count(0, 0).unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.toml: --agents must be at least 1 (a run needs a robot), got 0"
    );

    let many = s.with_agent_count(12, 99).unwrap();
    assert_eq!(many.agents.len(), 12);
    assert_eq!(&many.agents[..2], &s.agents[..]);
    assert!(many.validate().is_ok(), "distinct, free, in bounds");
    for a in &many.agents[2..] {
        assert_ne!(a.start, a.goal);
        assert!(
            octile_shortest_path_len(&many.map.grid, a.start, a.goal, many.map.corner_cutting)
                .is_some()
        );
    }
    assert_eq!(many, s.with_agent_count(12, 99).unwrap(), "deterministic");
    assert_ne!(many, s.with_agent_count(12, 100).unwrap(), "seed matters");

    // 21 free cells: at most 21 distinct starts.
    let e = s.with_agent_count(22, 1).unwrap_err();
    assert!(
        matches!(
            e,
            ScenarioError::NotEnoughFreeCells {
                requested: 22,
                placed: 21,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn agent_count_respects_faults_and_components() {
    let with_fault =
        format!("{BASE}[[faults]]\nat_round = 1\naction = \"kill\"\nrole = \"agent\"\nindex = 1\n");
    let s = parse(&with_fault).unwrap();
    assert!(matches!(
        s.with_agent_count(1, 0),
        Err(ScenarioError::FaultAgentOutOfRange { .. })
    ));

    // Two rooms split by a wall: every generated goal is in its start's room.
    let text = "name = \"rooms\"\n[map]\nrows = [\"..@..\", \"..@..\"]\n[[agents]]\nstart = [0, 0]\ngoal = [1, 1]\n";
    let s = parse(text).unwrap();
    let grown = s.with_agent_count(4, 5).unwrap();
    for a in &grown.agents {
        assert_eq!(a.start.x < 2, a.goal.x < 2, "{a:?}");
    }
}

#[test]
fn validate_catches_changes_in_code() {
    let mut s = parse(BASE).unwrap();
    s.agents[1].goal = Cell::new(2, 1);
    assert!(matches!(
        s.validate(),
        Err(ScenarioError::GoalOnObstacle { .. })
    ));
    s.agents[1].goal = Cell::new(9, 9);
    assert!(matches!(
        s.validate(),
        Err(ScenarioError::GoalOutsideMap { .. })
    ));
    s.agents.clear();
    assert!(matches!(s.validate(), Err(ScenarioError::NoAgents { .. })));
}

#[test]
fn report_lists_agents() {
    let s = parse(BASE).unwrap();
    let r = ScenarioReport::new(&s);
    assert_eq!(r.agents.len(), 2);
    assert_eq!(r.agents[0].start_id, 1);
    assert_eq!(r.agents[0].goal_id, 24);
    assert!(r.agents[0].shortest_path_len.is_some());
    assert!(r.warnings.is_empty());
    let text = r.render();
    assert!(text.contains("6 x 4, 3 blocked"), "{text}");
    let dir = tempfile::tempdir().unwrap();
    let path = r.write_json(&dir.path().join("out")).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    assert_eq!(json["agents"][1]["goal"], serde_json::json!([0, 3]));
    assert_eq!(json["scenario_hash"].as_str().map(str::len), Some(16));
}

#[test]
fn allow_unreachable_counts_in_the_hash_only_when_set() {
    let a = parse(BASE).unwrap();
    assert!(!a.allow_unreachable);
    let b = parse(&format!("allow_unreachable = false\n{BASE}")).unwrap();
    assert_eq!(a.scenario_hash(), b.scenario_hash(), "false is the default");
    let c = parse(&format!("allow_unreachable = true\n{BASE}")).unwrap();
    assert!(c.allow_unreachable);
    assert_ne!(a.scenario_hash(), c.scenario_hash());
}

#[test]
fn validate_refuses_unreachable_goals_and_too_many_agents() {
    let mut s = parse(BASE).unwrap();
    // Wall agent 0's goal (5, 3) in: (4, 3) and (5, 2) are its only free neighbours.
    s.map.grid.set_blocked(Cell::new(4, 3), true);
    s.map.grid.set_blocked(Cell::new(5, 2), true);
    s.map.grid.set_blocked(Cell::new(4, 2), true);
    let e = s.validate().unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.toml: agent 0: goal [5, 3] is unreachable from start [0, 0] (write \
         allow_unreachable = true at the top of the scenario to run it anyway)"
    );
    s.allow_unreachable = true;
    assert!(s.validate().is_ok());

    let s = parse(BASE).unwrap();
    let e = s
        .with_agent_count(crate::msg::MAX_AGENTS + 1, 0)
        .unwrap_err();
    assert!(
        matches!(
            e,
            ScenarioError::TooManyAgents {
                agents: 4097,
                max: 4096,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn lacam_is_the_default_dissertation_keeps_the_unkeyed_hash_and_a_bad_name_is_a_located_error() {
    let a = parse(BASE).unwrap();
    assert_eq!(a.coordinator.rules, Rules::Lacam, "the default");
    let with = |rules: &str| format!("{BASE}\n[coordinator]\nrules = \"{rules}\"\n");
    let l = parse(&with("lacam")).unwrap();
    assert_eq!(l.coordinator.rules, Rules::Lacam);
    assert_eq!(
        l.scenario_hash(),
        a.scenario_hash(),
        "the default, named or not"
    );
    let b = parse(&with("dissertation")).unwrap();
    assert_eq!(b.coordinator.rules, Rules::Dissertation);
    // That the named dissertation's rules keep the hash of the days before the option is
    // checked by the golden logs (`tests/tests/swarm.rs`), whose headers carry it.
    assert_ne!(
        b.scenario_hash(),
        a.scenario_hash(),
        "an old unkeyed log is not lacam's"
    );
    let c = parse(&with("pibt")).unwrap();
    assert_eq!(c.coordinator.rules, Rules::Pibt);
    assert_ne!(a.scenario_hash(), c.scenario_hash());
    assert_ne!(b.scenario_hash(), c.scenario_hash());
    assert_ne!(l.scenario_hash(), c.scenario_hash());
    let text = with("fifo");
    let e = parse(&text).unwrap_err();
    let line = text.lines().position(|l| l.starts_with("rules")).unwrap() + 1;
    assert_eq!(e.line(), Some(line), "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains("fifo")
            && msg.contains("`dissertation`")
            && msg.contains("`pibt`")
            && msg.contains("`lacam`"),
        "{msg}"
    );
}

#[test]
fn planner_counts_in_the_hash_only_off_the_default_and_a_bad_name_is_a_located_error() {
    let a = parse(BASE).unwrap();
    assert!(a.agents.iter().all(|s| s.planner == Planner::Hnav));
    // The second agent's table is the last one in BASE, so an appended key lands in it.
    let with = |planner: &str| format!("{BASE}planner = \"{planner}\"\n");
    let b = parse(&with("hnav")).unwrap();
    assert_eq!(a.scenario_hash(), b.scenario_hash(), "the default");
    let c = parse(&with("pso")).unwrap();
    assert_eq!(c.agents[1].planner, Planner::Pso);
    assert_eq!(c.agents[0].planner, Planner::Hnav);
    let d = parse(&with("ga-fuzzy")).unwrap();
    assert_eq!(d.agents[1].planner, Planner::GaFuzzy);
    assert_ne!(a.scenario_hash(), c.scenario_hash());
    assert_ne!(c.scenario_hash(), d.scenario_hash());
    let text = with("astar");
    let e = parse(&text).unwrap_err();
    let line = text.lines().position(|l| l.starts_with("planner")).unwrap() + 1;
    assert_eq!(e.line(), Some(line), "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains("astar") && msg.contains("`pso`") && msg.contains("`ga-fuzzy`"),
        "{msg}"
    );
    let report = ScenarioReport::new(&d).render();
    assert!(report.contains("ga-fuzzy"), "{report}");
}
