//! `plan_query`: the JSON the bench prints, and bad input.

mod common;

use hnav_agent::plan::{plan_query, PlanOptions, PlanStop};
use hnav_agent::{Activation, Error, Role};
use hnav_runtime::grid::{Cell, CornerCutting, Grid};
use hnav_runtime::plan::PlanResult;

#[test]
fn json_has_exactly_the_bench_fields() {
    let g = common::maze();
    let options = PlanOptions {
        activation: Activation::Tanh,
        stop: PlanStop::Full,
        corner_cutting: CornerCutting::Allowed,
    };
    let r = plan_query(&g, common::id(&g, 1), common::id(&g, 56), &options).unwrap();
    assert!(r.found);
    assert_eq!((r.steps, r.iterations), (13, 19));
    let json = serde_json::to_value(&r).unwrap();
    let obj = json.as_object().unwrap();
    let mut keys: Vec<&str> = obj.keys().map(String::as_str).collect();
    keys.sort_unstable();
    assert_eq!(
        keys,
        [
            "found",
            "iterations",
            "length",
            "path",
            "planner",
            "steps",
            "time_us"
        ]
    );
    assert_eq!(obj["planner"], "hnav");
    assert_eq!(obj["path"][0], serde_json::json!([0, 0]));
    assert_eq!(obj["path"][13], serde_json::json!([5, 5]));
    assert!(obj["time_us"].as_f64().unwrap() > 0.0);
    let back: PlanResult = serde_json::from_value(json).unwrap();
    assert_eq!(back, r);
    println!("{}", serde_json::to_string(&r).unwrap());
}

#[test]
fn corner_cutting_changes_the_maze() {
    // Forbidden: the maze's squeezes between two blocked corners are closed (notes: 25 / 18).
    let g = common::maze();
    let options = PlanOptions {
        stop: PlanStop::Full,
        ..PlanOptions::default()
    };
    let r = plan_query(&g, common::id(&g, 1), common::id(&g, 56), &options).unwrap();
    println!(
        "maze without corner cutting: {} sweeps, {} steps",
        r.iterations, r.steps
    );
    assert!(r.found);
    assert_eq!((r.iterations, r.steps), (25, 18));
}

#[test]
fn bad_cells_are_errors() {
    let g = common::grid_with_ids(5, 5, &[13]);
    let o = PlanOptions::default();
    let e = plan_query(&g, Cell::new(5, 0), Cell::new(0, 0), &o).unwrap_err();
    assert!(
        matches!(
            e,
            Error::OutOfBounds {
                role: Role::Start,
                ..
            }
        ),
        "{e}"
    );
    let e = plan_query(&g, Cell::new(0, 0), Cell::new(0, 9), &o).unwrap_err();
    assert!(
        matches!(
            e,
            Error::OutOfBounds {
                role: Role::Goal,
                ..
            }
        ),
        "{e}"
    );
    let e = plan_query(&g, Cell::new(2, 2), Cell::new(0, 0), &o).unwrap_err();
    assert!(
        matches!(
            e,
            Error::Blocked {
                role: Role::Start,
                ..
            }
        ),
        "{e}"
    );
    let e = plan_query(&g, Cell::new(0, 0), Cell::new(2, 2), &o).unwrap_err();
    assert_eq!(e.to_string(), "goal [2, 2] is on an obstacle");
    let same = plan_query(&g, Cell::new(1, 1), Cell::new(1, 1), &o).unwrap();
    assert!(same.found && same.steps == 0 && same.path == vec![Cell::new(1, 1)]);
    let open = Grid::new(1, 1).unwrap();
    assert!(
        plan_query(&open, Cell::new(0, 0), Cell::new(0, 0), &o)
            .unwrap()
            .found
    );
}
