//! End to end: `hnav run` with the sim, the coordinator and one agent process per robot.

use std::time::Duration;

use hnav_tests::swarm::{generated_scenario, repo_root, verify_log, SwarmRun};
use hnav_tests::TestRun;

/// Generous: a debug build of 10 processes on a 2-core machine.
const RUN_TIMEOUT: Duration = Duration::from_secs(600);

fn run_once(tag: &str, dir: &std::path::Path, registry: &std::path::Path) -> SwarmRun {
    let mut run = TestRun::new(tag);
    let scenario = repo_root().join("scenarios/random-32-32-10.toml");
    let mut swarm = SwarmRun::start(&mut run, &scenario, dir, registry, &["--mode", "lockstep"])
        .expect("hnav run starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert!(
        status.success(),
        "hnav run failed: {status}\n{}",
        swarm.log_tails()
    );
    drop(run);
    swarm
}

#[test]
fn eight_agents_lockstep_reach_their_goals_and_replay_byte_for_byte() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let first = run_once("e2e1", &tmp.path().join("a"), &registry);
    let s = first.summary().unwrap();
    let agents = s["agents"].as_array().unwrap();
    assert_eq!(agents.len(), 8);
    for a in agents {
        assert_eq!(a["reached_goal"], true, "{a}\n{}", first.log_tails());
        for k in ["id", "steps", "length", "conflicts", "replans"] {
            assert!(a.get(k).is_some(), "summary lacks {k}: {a}");
        }
    }
    assert_eq!(s["collisions"], 0, "{s}");
    assert!(s["rounds"].as_u64().unwrap() > 0);
    assert!(s["wall_time_s"].as_f64().unwrap() > 0.0);
    let (ok, report) = verify_log(&first.dir.join("log"));
    assert!(ok, "log does not verify:\n{report}");

    let second = run_once("e2e2", &tmp.path().join("b"), &registry);
    let seg = "log/seg-00000000.hlog";
    let a = std::fs::read(first.dir.join(seg)).unwrap();
    let b = std::fs::read(second.dir.join(seg)).unwrap();
    assert!(
        a.len() > 1000,
        "a suspiciously short log: {} bytes",
        a.len()
    );
    assert!(
        a == b,
        "the two lockstep logs differ ({} vs {} bytes)",
        a.len(),
        b.len()
    );
    println!("log {} bytes, summary {s}", a.len());
}

/// The sha256 of the lockstep consensus logs as commit f7d1d19 (before the process refactor
/// of issue 10) wrote them. A lockstep run's log is a pure function of the scenario and the
/// code's decisions, so any change here is a change of behaviour: update these only together
/// with a change that means to decide differently, and say so in its commit.
const GOLDEN_LOGS: [(&str, &str); 2] = [
    (
        "scenarios/demo.toml",
        "dba4bdeb12a858c988d0f39f8c67c6c623c37d956c9e0010fc959e072af3732b",
    ),
    (
        "scenarios/random-32-32-10.toml",
        "33b75e9275cefd29465178441d307b75f4f8bdc115d8dcd1c17a1c4b5ce9d7ed",
    ),
];

#[test]
fn lockstep_logs_match_the_golden_sums() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    for (i, (scenario, want)) in GOLDEN_LOGS.iter().enumerate() {
        let dir = tmp.path().join(format!("g{i}"));
        let got = lockstep_log_sum(
            &format!("gold{i}"),
            &repo_root().join(scenario),
            &dir,
            &registry,
        );
        assert_eq!(&got, want, "{scenario}: the lockstep log changed");
    }
}

/// Robots that share agent processes (`[run] agents_per_process`) decide as robots that do
/// not: the same golden logs, with processes of 4 and 2 robots (the demo's six by 4) and of
/// 3, 3 and 2 (the eight of random-32-32-10 by 3).
#[test]
fn robots_sharing_agent_processes_write_the_golden_logs() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    for (i, ((scenario, want), per)) in GOLDEN_LOGS.iter().zip([4, 3]).enumerate() {
        let text = std::fs::read_to_string(repo_root().join(scenario)).unwrap();
        // The copy lives elsewhere: its map path is made absolute.
        let maps = format!("file = \"{}/maps/", repo_root().display());
        let text = text.replace("file = \"../maps/", &maps);
        let text = format!("{text}\n[run]\nagents_per_process = {per}\n");
        let copy = tmp.path().join(format!("shared{i}.toml"));
        std::fs::write(&copy, text).unwrap();
        let dir = tmp.path().join(format!("s{i}"));
        let got = lockstep_log_sum(&format!("shared{i}"), &copy, &dir, &registry);
        assert_eq!(&got, want, "{scenario} with {per} robots a process");
        let logs: Vec<String> = std::fs::read_dir(dir.join("logs"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with("agent-"))
            .collect();
        let agents = if i == 0 { 6 } else { 8 };
        assert_eq!(
            logs.len(),
            agents / per + usize::from(agents % per > 0),
            "{logs:?}"
        );
    }
}

/// Runs `scenario` in lockstep into `dir` and returns the sha256 of its log segment.
fn lockstep_log_sum(
    tag: &str,
    scenario: &std::path::Path,
    dir: &std::path::Path,
    registry: &std::path::Path,
) -> String {
    use sha2::{Digest, Sha256};
    let mut run = TestRun::new(tag);
    let mut swarm = SwarmRun::start(&mut run, scenario, dir, registry, &["--mode", "lockstep"])
        .expect("hnav run starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert!(
        status.success(),
        "{}: {status}\n{}",
        scenario.display(),
        swarm.log_tails()
    );
    let log = std::fs::read(dir.join("log/seg-00000000.hlog")).unwrap();
    Sha256::digest(&log)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The supervisor's `Stop` says why: at the time limit the coordinator logs the run's end as
/// `time-limit`, not as stopped. Four slow robots with long paths are far from their goals
/// after two seconds.
#[test]
fn a_run_at_its_time_limit_ends_as_time_limit() {
    let tmp = tempfile::tempdir().unwrap();
    let map = repo_root().join("maps/random-32-32-10.map");
    let scenario = generated_scenario(tmp.path(), &map, 4, 3, (25.0, 40.0), 0.25);
    let text = std::fs::read_to_string(&scenario).unwrap();
    let limited = text.replace("time_limit_s = 300", "time_limit_s = 2");
    assert_ne!(text, limited, "the generated scenario sets a time limit");
    std::fs::write(&scenario, limited).unwrap();
    let mut run = TestRun::new("limit");
    let mut swarm = SwarmRun::start(
        &mut run,
        &scenario,
        &tmp.path().join("out"),
        &tmp.path().join("runs"),
        &["--mode", "lockstep"],
    )
    .expect("hnav run starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert_eq!(status.code(), Some(1), "{}", swarm.log_tails());
    let s = swarm.summary().unwrap();
    assert_eq!(
        s["end"],
        "time-limit",
        "{s}
{}",
        swarm.log_tails()
    );
    let (ok, report) = verify_log(&swarm.dir.join("log"));
    assert!(
        ok,
        "log does not verify:
{report}"
    );
}
