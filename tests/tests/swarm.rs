//! End to end: `hnav run` with the sim, the coordinator and one agent process per robot.

use std::time::Duration;

use hnav_tests::swarm::{repo_root, verify_log, SwarmRun};
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
