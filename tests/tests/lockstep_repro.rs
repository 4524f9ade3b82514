//! Lockstep runs that end on their time limit are reproducible: the limit counts rounds of
//! simulated time (`time_limit_s` × `sim.odometry_hz`), not wall-clock seconds, so two runs
//! of the same scenario write the same consensus log byte for byte.

use std::path::{Path, PathBuf};
use std::time::Duration;

use hnav_runtime::consensus_log::{read_log, EndReason, Record};
use hnav_tests::swarm::{repo_root, verify_log, SwarmRun};
use hnav_tests::TestRun;

const RUN_TIMEOUT: Duration = Duration::from_secs(300);

/// The demo scenario (six robots, an inline map) with a 1.5 s time limit: 150 rounds of
/// 10 ms, far fewer than the robots need to reach their goals.
fn limited_scenario(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(repo_root().join("scenarios/demo.toml")).unwrap();
    let limited = text.replace("time_limit_s = 60", "time_limit_s = 1.5");
    assert_ne!(text, limited, "the demo scenario sets a time limit");
    let path = dir.join("limited.toml");
    std::fs::write(&path, limited).unwrap();
    path
}

/// Runs `scenario` in lockstep into `dir`; returns the log segment's bytes.
fn run(tag: &str, scenario: &Path, dir: &Path, registry: &Path) -> Vec<u8> {
    let mut run = TestRun::new(tag);
    let mut swarm = SwarmRun::start(&mut run, scenario, dir, registry, &["--mode", "lockstep"])
        .expect("hnav run starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert_eq!(status.code(), Some(1), "{status}\n{}", swarm.log_tails());
    let s = swarm.summary().unwrap();
    assert_eq!(s["end"], "time-limit", "{s}\n{}", swarm.log_tails());
    let (ok, report) = verify_log(&dir.join("log"));
    assert!(ok, "log does not verify:\n{report}");
    std::fs::read(dir.join("log/seg-00000000.hlog")).unwrap()
}

#[test]
fn two_lockstep_runs_to_the_time_limit_write_the_same_log() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = limited_scenario(tmp.path());
    let registry = tmp.path().join("runs");
    let a = run("limit-a", &scenario, &tmp.path().join("a"), &registry);
    let b = run("limit-b", &scenario, &tmp.path().join("b"), &registry);
    assert!(
        a == b,
        "the two lockstep logs differ ({} vs {} bytes)",
        a.len(),
        b.len()
    );
    let contents = read_log(tmp.path().join("a/log")).unwrap();
    let last_round = contents
        .records
        .iter()
        .filter_map(|r| match r {
            Record::Round(rec) => Some(rec.round),
            _ => None,
        })
        .max();
    assert_eq!(last_round, Some(150), "1.5 s of 10 ms rounds");
    match contents.records.last() {
        Some(Record::End(e)) => {
            assert_eq!(e.reason, EndReason::TimeLimit);
            assert_eq!(e.round, 150);
        }
        other => panic!("the log does not end with its end record: {other:?}"),
    }
}
