//! Robots outside HNAV (`[sim] kind = "ros2"`), driven through ROS 2 by a stand-in that
//! shares no code with HNAV, and the ROS 2 side's bad input.
//!
//! The stand-in, `clients/python/examples/ros2_robots.py` (PyPI `eclipse-zenoh` 1.10.2 and
//! `rosbags`), is the graph's Zenoh router and a node of differential-drive robots: it obeys
//! `/robot_<i>/cmd_vel`, publishes `/robot_<i>/joint_states` and `/robot_<i>/ground_truth`,
//! and checks collisions itself. The run joins it (`--ros2-router`), with `hnav-ros2
//! --robots` in the sim's place.
//!
//! The Python is the client tests' ([`hnav_tests::python`]): without it the tests that need
//! it skip, unless `HNAV_REQUIRE_PYTHON` is set.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use hnav_runtime::scenario::RobotParams;
use hnav_tests::python::python;
use hnav_tests::swarm::{hnav_output, repo_root, SwarmRun};
use hnav_tests::{free_port, TestRun};

/// Bound on the stand-in's router coming up.
const ROUTER_TIMEOUT: Duration = Duration::from_secs(30);
/// Bound on a run and the stand-in's checks.
const RUN_TIMEOUT: Duration = Duration::from_secs(150);

/// The demo with its robots outside HNAV: `clock = "lockstep"` becomes `kind = "ros2"`
/// (which runs in realtime).
fn demo_outside(dir: &Path) -> PathBuf {
    let demo = std::fs::read_to_string(repo_root().join("scenarios/demo.toml")).unwrap();
    assert!(
        demo.contains("clock = \"lockstep\""),
        "the demo's [sim] changed"
    );
    let path = dir.join("demo-ros2.toml");
    std::fs::write(
        &path,
        demo.replace("clock = \"lockstep\"", "kind = \"ros2\""),
    )
    .unwrap();
    path
}

/// Two robots on rows of their own, never in each other's way.
const TWO_LANES: &str = r#"name = "two-lanes"
[map]
rows = ["......", "......", "......"]
[sim]
kind = "ros2"
[coordinator]
time_limit_s = 12
[[agents]]
start = [0, 0]
goal = [5, 0]
[[agents]]
start = [0, 2]
goal = [5, 2]
"#;

/// Starts the stand-in on a free port for `scenario`, with `extra` arguments; returns it
/// and the router's endpoint once it is up.
fn stand_in(
    run: &mut TestRun,
    python: &Path,
    scenario: &Path,
    extra: &[&str],
) -> (hnav_tests::Peer, String) {
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let r = RobotParams::default();
    let script = repo_root().join("clients/python/examples/ros2_robots.py");
    let mut args: Vec<String> = vec![
        script.display().to_string(),
        "--listen".into(),
        endpoint.clone(),
        "--scenario".into(),
        scenario.display().to_string(),
        "--wheel-radius".into(),
        r.wheel_radius_m.to_string(),
        "--axle".into(),
        r.axle_track_m.to_string(),
        "--radius".into(),
        r.body_radius_m.to_string(),
        "--cell".into(),
        r.cell_size_m.to_string(),
        "--timeout".into(),
        (RUN_TIMEOUT.as_secs() - 10).to_string(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    let mut peer = run
        .spawn_exact(&python.display().to_string(), &args)
        .expect("the stand-in starts");
    peer.wait_for_line("router up", ROUTER_TIMEOUT)
        .expect("the stand-in's router comes up");
    (peer, endpoint)
}

/// Every line the stand-in prints until it exits, and how it exited.
fn until_exit(peer: &mut hnav_tests::Peer) -> (Vec<String>, Option<std::process::ExitStatus>) {
    let deadline = Instant::now() + RUN_TIMEOUT;
    let mut lines = Vec::new();
    while let Ok(line) = peer.next_line(deadline.saturating_duration_since(Instant::now())) {
        lines.push(line);
    }
    let status = peer
        .wait_exit(deadline.saturating_duration_since(Instant::now()))
        .ok();
    (lines, status)
}

/// What a run with the stand-in left.
struct Driven {
    /// The stand-in's lines, and how it exited.
    lines: Vec<String>,
    status: Option<std::process::ExitStatus>,
    /// How `hnav run` exited.
    run_status: Result<std::process::ExitStatus, String>,
    /// `DIR/logs/sim.log`: `hnav-ros2 --robots`'s log.
    sim_log: String,
    swarm: SwarmRun,
    _run: TestRun,
}

impl Driven {
    /// The stand-in's own checks passed: it exits 0 only after it printed `OK`.
    fn stand_in_passed(&self) {
        assert!(
            self.status.is_some_and(|s| s.success()),
            "the stand-in's checks ({:?}):\n{}\n--- sim.log:\n{}\n{}",
            self.status,
            self.lines.join("\n"),
            self.sim_log,
            self.swarm.log_tails()
        );
    }
}

/// Runs `scenario` (in `tmp`) with the stand-in given `extra` and `hnav run` given
/// `run_extra`, until both have ended.
fn drive(
    tag: &str,
    python: &Path,
    tmp: &Path,
    scenario: &Path,
    (extra, run_extra): (&[&str], &[&str]),
) -> Driven {
    let mut run = TestRun::new(tag);
    let (mut robots, endpoint) = stand_in(&mut run, python, scenario, extra);
    let out = tmp.join("out");
    let mut args = vec!["--ros2-router", &endpoint];
    args.extend_from_slice(run_extra);
    let mut swarm = SwarmRun::start(&mut run, scenario, &out, &tmp.join("runs"), &args)
        .expect("hnav run starts");
    let (lines, status) = until_exit(&mut robots);
    let run_status = swarm.finish(Duration::from_secs(30));
    eprintln!("{}", lines.join("\n"));
    Driven {
        lines,
        status,
        run_status,
        sim_log: std::fs::read_to_string(out.join("logs/sim.log")).unwrap_or_default(),
        swarm,
        _run: run,
    }
}

#[test]
fn a_ros2_stand_in_drives_the_demos_six_robots_to_their_goals_through_malformed_samples() {
    let Some(python) = python() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let scenario = demo_outside(tmp.path());
    let d = drive(
        "ros2-robots",
        &python,
        tmp.path(),
        &scenario,
        (&["--malformed", "0"], &[]),
    );
    let Driven {
        lines,
        run_status,
        sim_log,
        swarm,
        ..
    } = &d;
    let text = lines.join("\n");
    d.stand_in_passed();
    assert_eq!(lines.last().map(String::as_str), Some("OK"), "{text}");
    assert!(lines.iter().any(|l| l == "collisions 0"), "{text}");
    assert!(
        run_status.as_ref().is_ok_and(|s| s.success()),
        "{run_status:?}\n{}",
        swarm.log_tails()
    );
    let summary = swarm.summary().unwrap();
    assert_eq!(summary["robots_outside"], true, "{summary:#}");
    let agents = summary["agents"].as_array().unwrap();
    assert_eq!(agents.len(), 6);
    assert!(
        agents.iter().all(|a| a["reached_goal"] == true),
        "{summary:#}"
    );
    // The malformed samples were said once, counted, dropped; the run went on.
    assert!(
        sim_log.contains("/robot_0/joint_states: a malformed sample dropped"),
        "{sim_log}"
    );
    let counts = sim_log
        .lines()
        .find(|l| l.contains("periods=") && l.contains("malformed="))
        .unwrap_or_else(|| panic!("no final counts in sim.log:\n{sim_log}"));
    eprintln!("{counts}");
    let field = |k: &str| -> f64 {
        counts
            .split(&format!("{k}="))
            .nth(1)
            .and_then(|v| v.split_whitespace().next())
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("no {k} in {counts}"))
    };
    let malformed = field("malformed");
    assert!(malformed >= 1.0, "{counts}");
    assert!(counts.contains(" down=0"), "{counts}");
    // It sleeps between periods: a loop that leaves a listener's event pending wakes at once
    // forever and spends the whole run on a core (it did, before drain_pending).
    let (cpu_s, wall_s) = (field("cpu_ms") / 1e3, field("periods") / 100.0);
    assert!(
        cpu_s < 0.5 * wall_s,
        "hnav-ros2 --robots spent {cpu_s:.1} s of CPU in a {wall_s:.1} s run: {counts}"
    );
}

#[test]
fn a_robot_that_never_publishes_joint_states_is_down_and_the_run_ends_by_its_time_limit() {
    let Some(python) = python() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let scenario = tmp.path().join("two-lanes.toml");
    std::fs::write(&scenario, TWO_LANES).unwrap();
    let d = drive(
        "ros2-silent",
        &python,
        tmp.path(),
        &scenario,
        (&["--silent", "1"], &[]),
    );
    let Driven {
        run_status,
        sim_log,
        swarm,
        ..
    } = &d;
    // Robot 0 went home; the stand-in leaves the silent robot out of its goal check.
    d.stand_in_passed();
    assert!(
        sim_log.contains("robot 1 down: nothing on /robot_1/joint_states for 1.0 s"),
        "{sim_log}"
    );
    assert!(!sim_log.contains("robot 0 down"), "{sim_log}");
    let summary = swarm.summary().unwrap();
    assert_eq!(summary["end"], "time-limit", "{summary:#}");
    assert_eq!(summary["agents"][0]["reached_goal"], true, "{summary:#}");
    assert_eq!(summary["agents"][1]["reached_goal"], false, "{summary:#}");
    // Not every robot home: the run says so in its exit code, it does not hang.
    assert!(
        run_status.as_ref().is_ok_and(|s| !s.success()),
        "{run_status:?}"
    );
}

#[test]
fn robots_that_publish_their_own_odom_are_driven_home_from_its_differences() {
    let Some(python) = python() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let scenario = tmp.path().join("two-lanes-odom.toml");
    // The robots' odom frames start where each robot does, not at the map's origin.
    std::fs::write(
        &scenario,
        format!("{TWO_LANES}[ros2]\nodometry = \"odom\"\n"),
    )
    .unwrap();
    let d = drive(
        "ros2-odom",
        &python,
        tmp.path(),
        &scenario,
        (&["--odom"], &[]),
    );
    d.stand_in_passed();
    assert_eq!(
        d.lines.last().map(String::as_str),
        Some("OK"),
        "{}",
        d.lines.join("\n")
    );
    assert!(
        d.run_status.as_ref().is_ok_and(|s| s.success()),
        "{:?}\n{}",
        d.run_status,
        d.swarm.log_tails()
    );
    assert!(d.sim_log.contains("down=0"), "{}", d.sim_log);
}

#[test]
fn a_killed_robots_process_is_restarted_and_drives_on_from_where_the_run_was() {
    let Some(python) = python() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let scenario = tmp.path().join("two-lanes.toml");
    // Far enough that the robots are on their way at the kill.
    std::fs::write(
        &scenario,
        TWO_LANES
            .replace("\"......\"", "\"............\"")
            .replace("goal = [5,", "goal = [11,")
            .replace("time_limit_s = 12", "time_limit_s = 40"),
    )
    .unwrap();
    let d = drive(
        "ros2-restart",
        &python,
        tmp.path(),
        &scenario,
        (&[], &["--kill", "sim@2s"]),
    );
    let Driven {
        run_status,
        sim_log,
        swarm,
        ..
    } = &d;
    let events = std::fs::read_to_string(swarm.dir.join("events.jsonl")).unwrap_or_default();
    assert!(
        events.contains("\"event\":\"spawned\"") && events.contains("\"node\":\"sim\""),
        "the sim's slot was not respawned:\n{events}"
    );
    d.stand_in_passed();
    assert!(
        run_status.as_ref().is_ok_and(|s| s.success()),
        "{run_status:?}\n{}\n{events}",
        swarm.log_tails()
    );
    // The successor counted on from the run's start (2 s of 10 ms periods before the kill),
    // not from 1, which every agent would have ignored.
    let resumed: u64 = (sim_log.lines())
        .find_map(|l| {
            l.split("resumed at period ")
                .nth(1)?
                .split_whitespace()
                .next()?
                .parse()
                .ok()
        })
        .unwrap_or_else(|| panic!("no resume in sim.log:\n{sim_log}"));
    assert!(resumed >= 150, "resumed at period {resumed}\n{sim_log}");
}

#[test]
fn an_unreachable_router_is_said_and_the_run_goes_on() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = tmp.path().join("two-lanes.toml");
    std::fs::write(
        &scenario,
        TWO_LANES.replace("kind = \"ros2\"", "clock = \"lockstep\""),
    )
    .unwrap();
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let run = TestRun::new("ros2-nowhere");
    let out = tmp.path().join("out");
    let args: Vec<String> = [
        "run",
        &scenario.display().to_string(),
        "--run",
        run.run.as_str(),
        "--out",
        &out.display().to_string(),
        "--ros2-router",
        &endpoint,
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let o = hnav_output(&args, &tmp.path().join("runs"), RUN_TIMEOUT).unwrap();
    assert!(o.status.success(), "{}\n{}", o.stderr, o.stdout);
    assert!(
        o.stderr.contains(&format!(
            "ros2: no Zenoh router answers at {endpoint} yet: hnav-ros2 keeps trying to join it"
        )),
        "{}",
        o.stderr
    );
    // The publisher was started beside the run (and stopped with it, whether or not it had
    // joined by then), and the run went on to its end.
    assert!(out.join("logs/ros2.log").exists());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(
        (summary["agents"].as_array().unwrap())
            .iter()
            .all(|a| a["reached_goal"] == true),
        "{summary:#}"
    );
}

#[test]
fn robots_outside_hnav_refuse_a_lockstep_clock_on_the_command_line() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = tmp.path().join("two-lanes.toml");
    std::fs::write(&scenario, TWO_LANES).unwrap();
    let run = TestRun::new("ros2-lockstep");
    let args: Vec<String> = [
        "run",
        &scenario.display().to_string(),
        "--run",
        run.run.as_str(),
        "--out",
        &tmp.path().join("out").display().to_string(),
        "--mode",
        "lockstep",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let o = hnav_output(&args, &tmp.path().join("runs"), Duration::from_secs(30)).unwrap();
    assert!(!o.status.success(), "{}", o.stderr);
    assert!(
        o.stderr.contains(
            "--mode lockstep: the scenario's [sim] kind = \"ros2\" runs in realtime only"
        ),
        "{}",
        o.stderr
    );
}
