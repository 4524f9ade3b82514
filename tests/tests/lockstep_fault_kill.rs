//! A lockstep run with a fault plan is reproducible: the sim holds before stepping past a
//! fault's round until the supervisor reports the fault done, so each fault fires exactly at
//! its `at_round` and two runs write the same consensus log byte for byte.
//!
//! In its own test binary because the supervisor SIGKILLs processes.

use std::path::{Path, PathBuf};
use std::time::Duration;

use hnav_runtime::msg::{LifecycleEvent, Role};
use hnav_tests::swarm::{lifecycle_records, repo_root, verify_log, SwarmRun};
use hnav_tests::TestRun;

const RUN_TIMEOUT: Duration = Duration::from_secs(300);

/// The demo scenario with agent 1 SIGKILLed at round 40 and the coordinator at round 90,
/// both restarted on failure (the default policy).
fn faulty_scenario(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(repo_root().join("scenarios/demo.toml")).unwrap();
    let faults = "\n[[faults]]\nat_round = 40\naction = \"kill\"\nrole = \"agent\"\nindex = 1\n\
                  \n[[faults]]\nat_round = 90\naction = \"kill\"\nrole = \"coordinator\"\n";
    let path = dir.join("faulty.toml");
    std::fs::write(&path, format!("{text}{faults}")).unwrap();
    path
}

/// Runs `scenario` in lockstep into `dir`; returns the log segment's bytes. Every view of
/// the run shows its two faults: the summary's restarts, the report's process events and
/// agent-down mark, the MCAP export's lifecycle channel.
fn run(tag: &str, scenario: &Path, dir: &Path, registry: &Path) -> Vec<u8> {
    let mut run = TestRun::new(tag);
    let mut swarm = SwarmRun::start(&mut run, scenario, dir, registry, &["--mode", "lockstep"])
        .expect("hnav run starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert!(status.success(), "{status}\n{}", swarm.log_tails());
    let summary = swarm.summary().unwrap();
    assert_eq!(
        summary["restarts"],
        serde_json::json!({"agent-1": 1, "coordinator": 1}),
        "{summary}"
    );
    let svg = std::fs::read_to_string(dir.join("report.svg")).unwrap();
    assert!(
        svg.contains("round 40: agent-1 down, restarted at ["),
        "{svg}"
    );
    assert!(
        svg.contains("round 90: coordinator down, restarted"),
        "{svg}"
    );
    assert!(svg.contains("2 process restarts"), "{svg}");
    let mcap = dir.join("run.mcap");
    hnav_operator::export::export_mcap(dir, &mcap).unwrap();
    let bytes = std::fs::read(&mcap).unwrap();
    let events: Vec<String> = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(Result::unwrap)
        .filter(|m| m.channel.topic == "/lifecycle")
        .map(|m| {
            let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
            format!(
                "{} {} {}",
                v["round"],
                v["process"].as_str().unwrap(),
                v["event"].as_str().unwrap()
            )
        })
        .collect();
    assert_eq!(
        events,
        [
            "40 agent-1 down",
            "40 agent-1 restarted",
            "90 coordinator down",
            "90 coordinator restarted"
        ]
    );
    let (ok, report) = verify_log(&dir.join("log"));
    assert!(ok, "log does not verify:\n{report}");
    std::fs::read(dir.join("log/seg-00000000.hlog")).unwrap()
}

#[test]
fn two_lockstep_runs_with_a_fault_plan_write_the_same_log() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = faulty_scenario(tmp.path());
    let registry = tmp.path().join("runs");
    let a = run("fault-a", &scenario, &tmp.path().join("a"), &registry);
    let b = run("fault-b", &scenario, &tmp.path().join("b"), &registry);
    let events = lifecycle_records(&tmp.path().join("a/log"));
    let (agent, coordinator) = (Some(Role::Agent), Some(Role::Coordinator));
    assert_eq!(
        events,
        vec![
            (40, agent, 1, Some(LifecycleEvent::Down)),
            (40, agent, 1, Some(LifecycleEvent::Restarted)),
            // The restarted coordinator hears its predecessor's `Down` as the topic's history.
            (90, coordinator, 0, Some(LifecycleEvent::Down)),
            (90, coordinator, 0, Some(LifecycleEvent::Restarted)),
        ],
        "each fault is logged at its at_round"
    );
    assert!(
        a == b,
        "the two lockstep logs differ ({} vs {} bytes)",
        a.len(),
        b.len()
    );
}
