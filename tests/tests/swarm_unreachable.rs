//! End to end: a scenario that allows an unreachable goal. The walled-in agent reports it
//! once (one unreachable record, which `hnav log show` prints), asks for no moves, and the
//! run ends as soon as the other agent is at its goal instead of at its time limit.

use std::time::Duration;

use hnav_tests::swarm::{verify_log, workspace_bin, SwarmRun};
use hnav_tests::TestRun;

const RUN_TIMEOUT: Duration = Duration::from_secs(300);

/// Agent 0 is walled into the top-left corner; agent 1 drives two cells. The time limit is
/// far beyond what agent 1 needs, so a run that waits for it is easy to tell.
const SCENARIO: &str = r#"name = "walled"
allow_unreachable = true
[map]
rows = [".@...",
        "@@...",
        "....."]
[sim]
clock = "lockstep"
[coordinator]
time_limit_s = 20.0
[[agents]]
start = [0, 0]
goal = [4, 2]
[[agents]]
start = [2, 0]
goal = [4, 0]
"#;

#[test]
fn an_unreachable_goal_is_reported_once_and_ends_the_run_when_the_rest_are_done() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = tmp.path().join("walled.toml");
    std::fs::write(&scenario, SCENARIO).unwrap();
    let mut run = TestRun::new("unreach");
    let mut swarm = SwarmRun::start(
        &mut run,
        &scenario,
        &tmp.path().join("out"),
        &tmp.path().join("runs"),
        &[],
    )
    .expect("hnav run starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert_eq!(
        status.code(),
        Some(1),
        "not every robot reached its goal\n{}",
        swarm.log_tails()
    );
    let s = swarm.summary().unwrap();
    assert_eq!(
        s["end"],
        "all-at-goal-or-unreachable",
        "{s}\n{}",
        swarm.log_tails()
    );
    assert_eq!(s["agents"][0]["unreachable"], true, "{s}");
    assert_eq!(s["agents"][0]["conflicts"], 0, "it asked for no moves: {s}");
    assert_eq!(s["agents"][1]["reached_goal"], true, "{s}");
    // 20 s of sim time is 2000 rounds; agent 1 needs a few hundred.
    let rounds = s["rounds"].as_u64().unwrap();
    assert!(
        rounds < 1000,
        "{rounds} rounds: the run waited for its time limit"
    );

    let (ok, report) = verify_log(&swarm.dir.join("log"));
    assert!(ok, "log does not verify:\n{report}");
    let show = std::process::Command::new(workspace_bin("hnav"))
        .args(["log", "show"])
        .arg(swarm.dir.join("log"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&show.stdout);
    let reports: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("unreachable "))
        .collect();
    assert_eq!(reports.len(), 1, "reported once:\n{text}");
    assert!(reports[0].contains("a0 at [0, 0]"), "{}", reports[0]);
    drop(run);
}
