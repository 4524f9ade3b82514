//! `hnav run --ros2` seen from a ROS 2 client that shares no code with HNAV.
//!
//! The client, `clients/python/examples/ros2_check.py`, has PyPI `eclipse-zenoh` 1.10.2 for
//! the network and `rosbags` for ROS 2 Jazzy's message definitions, type hashes and CDR.
//!
//! The client is the Zenoh router of the graph, on a free port of this test's; the lockstep
//! demo run joins it (`--ros2-router`). The client finds the liveliness tokens rmw_zenoh
//! would announce for the node and every publisher, decodes every robot's `odom`,
//! `ground_truth` and `plan`, `/map` (again as a late subscriber, from the publisher's cache)
//! and `/tf`, and once the run has ended checks each robot's last ground-truth pose against
//! its goal in the scenario: within half a cell.
//!
//! The Python is the client tests' ([`hnav_tests::python`]): without it the test skips,
//! unless `HNAV_REQUIRE_PYTHON` is set.

use std::time::{Duration, Instant};

use hnav_tests::python::python;
use hnav_tests::swarm::{repo_root, SwarmRun};
use hnav_tests::{free_port, TestRun};

/// Bound on the client's router coming up.
const ROUTER_TIMEOUT: Duration = Duration::from_secs(30);
/// Bound on the run and the client's checks.
const RUN_TIMEOUT: Duration = Duration::from_secs(180);

#[test]
fn a_ros2_client_without_ros_sees_the_demo_run_and_its_robots_at_their_goals() {
    let Some(python) = python() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let mut run = TestRun::new("ros2");
    let scenario = repo_root().join("scenarios/demo.toml");
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let client = repo_root().join("clients/python/examples/ros2_check.py");
    let args = [
        client.display().to_string(),
        "--listen".into(),
        endpoint.clone(),
        "--scenario".into(),
        scenario.display().to_string(),
        "--timeout".into(),
        (RUN_TIMEOUT.as_secs() - 20).to_string(),
    ];
    let mut checker = run
        .spawn_exact(&python.display().to_string(), &args)
        .expect("the client starts");
    checker
        .wait_for_line("router up", ROUTER_TIMEOUT)
        .expect("the client's router comes up");
    let out = tmp.path().join("out");
    let extra = ["--mode", "lockstep", "--ros2", "--ros2-router", &endpoint];
    let mut swarm = SwarmRun::start(&mut run, &scenario, &out, &tmp.path().join("runs"), &extra)
        .expect("hnav run starts");
    let deadline = Instant::now() + RUN_TIMEOUT;
    let mut lines = Vec::new();
    while let Ok(line) = checker.next_line(deadline.saturating_duration_since(Instant::now())) {
        lines.push(line);
    }
    let status = checker
        .wait_exit(deadline.saturating_duration_since(Instant::now()))
        .expect("the client exits");
    let run_status = swarm.finish(Duration::from_secs(30));
    let text = lines.join("\n");
    eprintln!("{text}");
    let ros2_log = std::fs::read_to_string(out.join("logs/ros2.log")).unwrap_or_default();
    assert!(
        status.success(),
        "the client failed ({status}):\n{text}\n--- ros2.log:\n{ros2_log}"
    );
    assert!(
        run_status.as_ref().is_ok_and(|s| s.success()),
        "{run_status:?}"
    );
    assert_eq!(lines.last().map(String::as_str), Some("OK"), "{text}");
    let at_goal = lines
        .iter()
        .filter(|l| l.contains("final ground truth"))
        .count();
    assert_eq!(at_goal, 6, "{text}");
    assert!(
        lines.iter().any(|l| l.starts_with("late /map 12x12")),
        "{text}"
    );
    // The publisher said what it sent when the run stopped it.
    assert!(ros2_log.contains("sent="), "{ros2_log}");
}

/// The RViz config the tutorial ships subscribes only to what `/hnav` publishes for the
/// demo, in the frame it publishes in.
#[test]
fn the_shipped_rviz_config_shows_the_demos_topics_in_the_map_frame() {
    let text = std::fs::read_to_string(repo_root().join("docs/ros2/hnav.rviz")).unwrap();
    let mut published: Vec<String> = vec!["/map".into(), "/hnav/markers".into()];
    published.extend((0..6).map(|i| format!("/robot_{i}/plan")));
    let topics: Vec<&str> = (text.lines())
        .filter_map(|l| l.trim().strip_prefix("Value: /"))
        .collect();
    for t in &topics {
        // RViz's map display also listens for partial updates; HNAV sends whole maps.
        let t = format!("/{t}");
        assert!(
            published.contains(&t) || t == "/map_updates",
            "{t} is not a topic of /hnav"
        );
    }
    for p in &published {
        assert!(topics.contains(&&p[1..]), "the config does not show {p}");
    }
    assert!(text.contains("Fixed Frame: map"));
    assert!(text.contains("Durability Policy: Transient Local"));
}
