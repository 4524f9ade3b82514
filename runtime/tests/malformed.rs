//! Malformed maps, `.scen` files and scenarios: each gets its own error variant, pointing at
//! the right line, and none of them panics.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use hnav_runtime::grid::{
    read_map, read_map_file, read_scen, validate_scen, Dimension, Endpoint, GridError,
};
use hnav_runtime::scenario::{Scenario, ScenarioError};

/// Runs `f`, failing the test (rather than aborting it) if it panics.
fn no_panic<T>(what: &str, f: impl FnOnce() -> T) -> T {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|_| panic!("{what} panicked"))
}

fn map_err(text: &str) -> GridError {
    no_panic(text, || read_map(text, "bad.map")).expect_err(text)
}

const GOOD_MAP: &str = "type octile\nheight 3\nwidth 4\nmap\n....\n.@@.\n....\n";

#[test]
fn map_truncated_header() {
    let e = map_err("type octile\nheight 3\nwidth 4\n");
    assert_eq!(
        e,
        GridError::TruncatedHeader {
            source_name: "bad.map".into(),
            line: 4
        }
    );
}

#[test]
fn map_wrong_row_width() {
    let e = map_err(&GOOD_MAP.replace(".@@.", ".@@"));
    assert_eq!(
        e,
        GridError::RowWidth {
            source_name: "bad.map".into(),
            line: 6,
            found: 3,
            expected: 4
        }
    );
    assert_eq!(e.to_string(), "bad.map:6: row has 3 characters, expected 4");
    let e = map_err(&GOOD_MAP.replace(".@@.", ".@@.."));
    assert!(
        matches!(
            e,
            GridError::RowWidth {
                line: 6,
                found: 5,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn map_unknown_character() {
    let e = map_err(&GOOD_MAP.replace(".@@.", ".@#."));
    assert_eq!(
        e,
        GridError::UnknownChar {
            source_name: "bad.map".into(),
            line: 6,
            column: 3,
            ch: '#'
        }
    );
    assert_eq!(
        e.to_string(),
        "bad.map:6:3: unknown map character '#' (known: . G S W T @ O)"
    );
}

#[test]
fn map_row_count() {
    let e = map_err(GOOD_MAP.trim_end_matches("....\n"));
    assert!(
        matches!(
            e,
            GridError::TooFewRows {
                line: 7,
                found: 2,
                expected: 3,
                ..
            }
        ),
        "{e}"
    );
    let e = map_err(&format!("{GOOD_MAP}....\n"));
    assert!(
        matches!(
            e,
            GridError::TooManyRows {
                line: 8,
                expected: 3,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn map_bad_and_missing_dimensions() {
    let e = map_err(&GOOD_MAP.replace("height 3", "height three"));
    assert!(
        matches!(
            e,
            GridError::BadDimension {
                line: 2,
                which: Dimension::Height,
                ..
            }
        ),
        "{e}"
    );
    let e = map_err(&GOOD_MAP.replace("width 4", "width -4"));
    assert!(
        matches!(
            e,
            GridError::BadDimension {
                line: 3,
                which: Dimension::Width,
                ..
            }
        ),
        "{e}"
    );
    let e = map_err(&GOOD_MAP.replace("width 4\n", ""));
    assert!(
        matches!(
            e,
            GridError::MissingDimension {
                line: 3,
                which: Dimension::Width,
                ..
            }
        ),
        "{e}"
    );
    let e = map_err(&GOOD_MAP.replace("type octile", "type hex"));
    assert!(
        matches!(e, GridError::UnsupportedType { line: 1, .. }),
        "{e}"
    );
    let e = map_err(&GOOD_MAP.replace("map\n", "mop\n"));
    assert!(matches!(e, GridError::BadHeaderLine { line: 4, .. }), "{e}");
}

#[test]
fn map_file_missing_or_binary() {
    let dir = tempfile::tempdir().unwrap();
    let e = no_panic("missing", || read_map_file(dir.path().join("none.map"))).unwrap_err();
    assert!(matches!(e, GridError::Io { .. }), "{e}");
    let path = dir.path().join("bin.map");
    std::fs::write(&path, [0xff, 0xfe, 0x00, 0x80]).unwrap();
    let e = no_panic("binary", || read_map_file(&path)).unwrap_err();
    assert!(matches!(e, GridError::Io { .. }), "{e}");
}

const SCEN: &str = "version 1\n0\tm.map\t4\t3\t0\t0\t3\t2\t3.41421356\n";

fn scen_err(text: &str) -> GridError {
    no_panic(text, || read_scen(text, "bad.scen")).expect_err(text)
}

#[test]
fn scen_parse_errors() {
    let e = scen_err(&SCEN.replace("version 1", "version 3"));
    assert!(matches!(e, GridError::BadVersion { line: 1, .. }), "{e}");
    let e = scen_err(&SCEN.replace("\t3.41421356", ""));
    assert_eq!(
        e,
        GridError::FieldCount {
            source_name: "bad.scen".into(),
            line: 2,
            found: 8
        }
    );
    let e = scen_err(&SCEN.replace("\t0\t0\t3", "\t0\tzero\t3"));
    assert!(
        matches!(
            e,
            GridError::BadField {
                line: 2,
                field: 6,
                name: "start_y",
                ..
            }
        ),
        "{e}"
    );
    let e = scen_err(&format!("{SCEN}0 m.map 4 3 0 0 3 2 3.4\n"));
    assert!(
        matches!(
            e,
            GridError::FieldCount {
                line: 3,
                found: 1,
                ..
            }
        ),
        "spaces are not tabs: {e}"
    );
}

#[test]
fn scen_validation_errors() {
    let grid = read_map(GOOD_MAP, "m.map").unwrap();
    let text = "version 1\n\
                0\tm.map\t4\t3\t0\t0\t3\t2\t3.41421356\n\
                0\tm.map\t4\t3\t4\t0\t3\t2\t1\n\
                0\tm.map\t4\t3\t0\t0\t2\t1\t1\n\
                0\tm.map\t5\t3\t0\t0\t3\t2\t1\n";
    let scen = no_panic("read", || read_scen(text, "v.scen")).unwrap();
    let errors = validate_scen(&grid, &scen);
    assert_eq!(errors.len(), 3, "{errors:?}");
    assert!(matches!(
        errors[0],
        GridError::OutsideMap {
            line: 3,
            endpoint: Endpoint::Start,
            x: 4,
            ..
        }
    ));
    assert!(matches!(
        errors[1],
        GridError::OnObstacle {
            line: 4,
            endpoint: Endpoint::Goal,
            ch: '@',
            ..
        }
    ));
    assert!(matches!(
        errors[2],
        GridError::SizeMismatch {
            line: 5,
            scen_width: 5,
            width: 4,
            ..
        }
    ));
}

const SCENARIO: &str = r#"name = "bad"
[map]
rows = ["....",
        ".@@.",
        "...."]
[[agents]]
start = [0, 0]
goal = [3, 2]
speed = 1.0
[[agents]]
start = [3, 0]
goal = [0, 2]
"#;

fn scenario_err(text: &str) -> ScenarioError {
    no_panic(text, || {
        Scenario::from_str(text, "bad.toml", Path::new("."))
    })
    .expect_err(text)
}

#[test]
fn scenario_baseline_is_valid() {
    assert!(Scenario::from_str(SCENARIO, "bad.toml", Path::new(".")).is_ok());
}

#[test]
fn scenario_negative_speed() {
    let e = scenario_err(&SCENARIO.replace("speed = 1.0", "speed = -0.5"));
    assert!(
        matches!(
            e,
            ScenarioError::NonPositiveSpeed {
                agent: 0,
                speed: -0.5,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(
        e.to_string(),
        "bad.toml:9: agent 0 speed must be a positive number of cells/s, got -0.5"
    );
}

#[test]
fn scenario_goal_on_obstacle() {
    let e = scenario_err(&SCENARIO.replace("goal = [0, 2]", "goal = [2, 1]"));
    assert!(
        matches!(
            e,
            ScenarioError::GoalOnObstacle {
                agent: 1,
                ch: '@',
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(e.line(), Some(12));
}

#[test]
fn scenario_start_on_obstacle() {
    let e = scenario_err(&SCENARIO.replace("start = [0, 0]", "start = [1, 1]"));
    assert!(
        matches!(e, ScenarioError::StartOnObstacle { agent: 0, .. }),
        "{e}"
    );
    assert_eq!(e.line(), Some(7));
}

#[test]
fn scenario_start_outside_map() {
    let e = scenario_err(&SCENARIO.replace("start = [3, 0]", "start = [3, 3]"));
    assert!(
        matches!(
            e,
            ScenarioError::StartOutsideMap {
                agent: 1,
                x: 3,
                y: 3,
                width: 4,
                height: 3,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(e.line(), Some(11));
}

#[test]
fn scenario_unknown_key() {
    let e = scenario_err(&SCENARIO.replace("speed = 1.0", "sped = 1.0"));
    assert!(
        matches!(&e, ScenarioError::UnknownKey { key, .. } if key == "sped"),
        "{e}"
    );
    assert_eq!(e.line(), Some(9));
    let e = scenario_err(&format!("{SCENARIO}[simulation]\nseed = 1\n"));
    assert!(
        matches!(&e, ScenarioError::UnknownKey { key, .. } if key == "simulation"),
        "{e}"
    );
    assert_eq!(e.line(), Some(13));
}

#[test]
fn scenario_duplicates_and_missing_agents() {
    let e = scenario_err(&SCENARIO.replace("start = [3, 0]", "start = [0, 0]"));
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
    let e = scenario_err(&SCENARIO.replace("goal = [0, 2]", "goal = [3, 2]"));
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
    let head: String = SCENARIO.lines().take(5).map(|l| format!("{l}\n")).collect();
    assert!(matches!(
        scenario_err(&head),
        ScenarioError::NoAgents { .. }
    ));
}

#[test]
fn scenario_map_source_problems() {
    let e = scenario_err(&SCENARIO.replace("[map]\n", "[map]\nfile = \"x.map\"\n"));
    assert!(matches!(e, ScenarioError::MapFileAndRows { .. }), "{e}");
    let e = scenario_err("name = \"x\"\n[map]\n[[agents]]\nstart = [0, 0]\ngoal = [1, 1]\n");
    assert!(matches!(e, ScenarioError::NoMapSource { .. }), "{e}");
    assert_eq!(e.line(), Some(2));
    let e = scenario_err(&SCENARIO.replace("\".@@.\"", "\".@@\""));
    assert!(
        matches!(e.grid_error(), Some(GridError::RowWidth { line: 4, .. })),
        "{e}"
    );
    let e = scenario_err(&SCENARIO.replace("rows = [", "file = \"nowhere.map\"\nx = ["));
    assert!(matches!(e, ScenarioError::UnknownKey { .. }), "{e}");
}

#[test]
fn scenario_map_file_errors_are_wrapped() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("m.map"),
        "type octile\nheight 2\nwidth 2\nmap\n..\n.Q\n",
    )
    .unwrap();
    let text = "name = \"f\"\n[map]\nfile = \"m.map\"\n[[agents]]\nstart = [0, 0]\ngoal = [1, 0]\n";
    let e = no_panic("file", || Scenario::from_str(text, "f.toml", dir.path())).unwrap_err();
    assert!(
        matches!(
            e.grid_error(),
            Some(GridError::UnknownChar {
                line: 6,
                column: 2,
                ..
            })
        ),
        "{e}"
    );
    assert!(
        e.to_string().ends_with("(map referenced from f.toml:3)"),
        "{e}"
    );
}

#[test]
fn scenario_fault_out_of_range() {
    let e = scenario_err(&format!(
        "{SCENARIO}[[faults]]\nat_round = 3\naction = \"kill\"\nrole = \"agent\"\nindex = 2\n"
    ));
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
    assert_eq!(e.line(), Some(17));
}

#[test]
fn scenario_toml_syntax_and_types() {
    let e = scenario_err(&SCENARIO.replace("goal = [3, 2]", "goal = [3, 2"));
    assert!(matches!(e, ScenarioError::Toml { .. }), "{e}");
    let e = scenario_err(&SCENARIO.replace("speed = 1.0", "speed = \"1.0\""));
    assert!(matches!(e, ScenarioError::Toml { .. }), "{e}");
    assert_eq!(e.line(), Some(9));
    let e = scenario_err(&SCENARIO.replace("name = \"bad\"\n", ""));
    assert!(
        matches!(&e, ScenarioError::MissingKey { key, .. } if key == "name"),
        "{e}"
    );
}

#[test]
fn scenario_load_missing_file() {
    let e = no_panic("load", || Scenario::load("/nonexistent/hnav/x.toml")).unwrap_err();
    assert!(matches!(e, ScenarioError::Io { .. }), "{e}");
}
