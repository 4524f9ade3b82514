//! Unit tests of `[run]` and of how scenario errors print numbers.

use std::time::Duration;

use super::test_support::{parse, BASE};
use super::*;

#[test]
fn startup_timeout_is_read_or_scales_with_the_map() {
    let s = parse(&format!("{BASE}[run]\nstartup_timeout_s = 2.5\n")).unwrap();
    assert_eq!(s.run.startup_timeout_s, Some(2.5));
    assert_eq!(s.startup_timeout(), Duration::from_millis(2500));
    let s = parse(BASE).unwrap();
    assert_eq!(s.run, RunParams::default());
    // 6 x 4 cells: nothing beyond the base.
    let d = s.startup_timeout().as_secs_f64();
    assert!((d - 60.0).abs() < 0.01, "{d}");
    // The timeout decides whether a run starts, not what it does.
    let other = parse(&format!("{BASE}[run]\nstartup_timeout_s = 9\n")).unwrap();
    assert_eq!(s.scenario_hash(), other.scenario_hash());
}

#[test]
fn bad_startup_timeouts_name_line_and_range() {
    for (value, got) in [
        ("0", "0"),
        ("-3", "-3"),
        ("nan", "NaN"),
        ("86401", "86401"),
        ("1e300", "1e300"),
    ] {
        let e = parse(&format!("{BASE}[run]\nstartup_timeout_s = {value}\n")).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "t.toml:17: run.startup_timeout_s must be a number of seconds in (0, 86400], \
                 got {got}"
            )
        );
    }
    let e = parse(&format!("{BASE}[run]\nstartup = 3\n")).unwrap_err();
    assert!(e.to_string().starts_with("t.toml:17: unknown key"), "{e}");
}

/// `{}` of an `f64` prints 1e300 as 301 digits; an error message must stay readable.
#[test]
fn huge_and_tiny_numbers_print_in_scientific_notation() {
    let e = parse(&BASE.replace("speed = 2.0", "speed = -1e300")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.toml:15: agent 1 speed must be a positive number of cells/s, got -1e300"
    );
    let e = parse(&format!("{BASE}[robot]\ncell_size_m = -1e-300\n")).unwrap_err();
    assert!(e.to_string().ends_with("got -1e-300"), "{e}");
    let e = parse(&BASE.replace("speed = 2.0", "speed = 1e300")).unwrap_err();
    assert!(
        e.to_string().starts_with(
            "t.toml:15: agent 1 speed 1e300 cells/s exceeds the robot's 2.625 cells/s"
        ),
        "{e}"
    );
    for (x, shown) in [
        (0.25, "0.25"),
        (120.0, "120"),
        (1e15, "1e15"),
        (3e-7, "3e-7"),
    ] {
        assert_eq!(error::number(x).to_string(), shown);
    }
}

#[test]
fn robots_outside_hnav_run_in_realtime_in_a_world_hnav_does_not_simulate() {
    let s = parse(&format!("{BASE}[sim]\nkind = \"ros2\"\n")).unwrap();
    assert_eq!(s.sim.kind, SimKind::Ros2);
    assert_eq!(
        s.sim.clock,
        ClockMode::Realtime,
        "ros2 defaults to realtime"
    );
    let realtime = parse(&format!("{BASE}[sim]\nclock = \"realtime\"\n")).unwrap();
    assert_ne!(s.scenario_hash(), realtime.scenario_hash());
    // The default keeps every older scenario's hash.
    let hnav = parse(&format!(
        "{BASE}[sim]\nclock = \"realtime\"\nkind = \"hnav\"\n"
    ))
    .unwrap();
    assert_eq!(hnav.scenario_hash(), realtime.scenario_hash());

    let e = parse(&format!(
        "{BASE}[sim]\nclock = \"lockstep\"\nkind = \"ros2\"\n"
    ))
    .unwrap_err();
    assert!(
        e.to_string()
            .starts_with("t.toml:18: sim.kind \"ros2\" runs in realtime only"),
        "{e}"
    );
    let e = parse(&format!(
        "{BASE}[sim]\nkind = \"ros2\"\n[sensing]\nrange = 3\n"
    ))
    .unwrap_err();
    assert!(
        e.to_string().contains("[sensing] needs kind = \"hnav\""),
        "{e}"
    );
    assert!(e.to_string().starts_with("t.toml:17:"), "{e}");
    let e = parse(&format!(
        "{BASE}[sim]\nkind = \"ros2\"\n[[events]]\nat_s = 1.0\nclose = [[2, 2]]\n"
    ))
    .unwrap_err();
    assert!(
        e.to_string().contains("[[events]] needs kind = \"hnav\""),
        "{e}"
    );
    assert!(parse(&format!("{BASE}[sim]\nkind = \"gazebo\"\n")).is_err());
}

#[test]
fn agents_per_process_groups_robots_in_order_without_changing_the_hash() {
    let s = parse(BASE).unwrap();
    assert_eq!(s.run.agents_per_process, 1);
    let one: Vec<_> = s.run.agent_processes(3).collect();
    assert_eq!(one, [(0, 1), (1, 1), (2, 1)]);
    let g = parse(&format!("{BASE}[run]\nagents_per_process = 4\n")).unwrap();
    assert_eq!(g.run.agents_per_process, 4);
    let groups: Vec<_> = g.run.agent_processes(10).collect();
    assert_eq!(groups, [(0, 4), (4, 4), (8, 2)]);
    assert_eq!(
        (
            g.run.process_of(0),
            g.run.process_of(7),
            g.run.process_of(9)
        ),
        (0, 4, 8)
    );
    assert_eq!(g.run.agent_processes(0).count(), 0);
    // How robots are laid out in processes does not change what the run decides.
    assert_eq!(s.scenario_hash(), g.scenario_hash());
}

#[test]
fn bad_agents_per_process_name_line_and_range() {
    let e = parse(&format!("{BASE}[run]\nagents_per_process = 0\n")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.toml:17: run.agents_per_process must be at least 1"
    );
    let e = parse(&format!("{BASE}[run]\nagents_per_process = 257\n")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.toml:17: run.agents_per_process must be at most 256, got 257"
    );
    let e = parse(&format!("{BASE}[run]\nagents_per_process = -2\n")).unwrap_err();
    assert!(e.to_string().starts_with("t.toml:17"), "{e}");
}
