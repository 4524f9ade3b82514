//! Replicated coordinators (`--replicas 3`): in lockstep the cluster decides the very rounds
//! a single coordinator decides. Each replica's log, resolved to its committed records, must
//! equal the single coordinator's log record for record (the header's format version aside),
//! and must verify.

use std::path::Path;
use std::time::Duration;

use hnav_runtime::consensus_log::{
    read_decided, read_log, AppliedState, EndReason, Record, FORMAT_VERSION,
};
use hnav_runtime::msg::{LifecycleEvent, Role};
use hnav_tests::swarm::{records_digest, repo_root, verify_log, SwarmRun};
use hnav_tests::TestRun;

/// Generous: a debug build of up to 36 processes on a 2-core machine.
const RUN_TIMEOUT: Duration = Duration::from_secs(600);

/// Runs `scenario` in lockstep with `extra` arguments into `dir`; every robot must reach its
/// goal without a collision.
fn run(tag: &str, scenario: &Path, dir: &Path, registry: &Path, extra: &[&str]) {
    run_in("lockstep", tag, scenario, dir, registry, extra);
}

/// [`run`] in clock mode `mode`.
fn run_in(mode: &str, tag: &str, scenario: &Path, dir: &Path, registry: &Path, extra: &[&str]) {
    let mut run = TestRun::new(tag);
    let mut args = vec!["--mode", mode];
    args.extend_from_slice(extra);
    let mut swarm =
        SwarmRun::start(&mut run, scenario, dir, registry, &args).expect("hnav run starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert!(status.success(), "{status}\n{}", swarm.log_tails());
    let s = swarm.summary().unwrap();
    assert_eq!(s["end"], "all-at-goal", "{s}\n{}", swarm.log_tails());
    assert_eq!(s["collisions"], 0, "{s}");
}

/// The records after the header, and the header with the single coordinator's version.
fn decided(dir: &Path) -> Vec<Record> {
    let mut records = read_decided(dir).unwrap().records;
    if let Some(Record::Header(h)) = records.first_mut() {
        h.version = FORMAT_VERSION;
    }
    records
}

fn same_rounds_as_one_coordinator(tag: &str, scenario: &Path, agents: Option<&str>) {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let mut extra: Vec<&str> = Vec::new();
    if let Some(n) = agents {
        extra.extend(["--agents", n]);
    }
    let one = tmp.path().join("one");
    run(&format!("{tag}1"), scenario, &one, &registry, &extra);
    let single = read_log(one.join("log")).unwrap().records;
    assert!(single.len() > 10, "a suspiciously short log");
    let three = tmp.path().join("three");
    let mut args = extra.clone();
    args.extend(["--replicas", "3"]);
    run(&format!("{tag}3"), scenario, &three, &registry, &args);
    for id in 1..=3 {
        let dir = three.join("log").join(id.to_string());
        let got = decided(&dir);
        assert_eq!(
            got.len(),
            single.len(),
            "replica {id} decided {} records, the single coordinator {}",
            got.len(),
            single.len()
        );
        if let Some(i) = (0..got.len()).find(|&i| got[i] != single[i]) {
            panic!(
                "replica {id}: record {i} differs:\n{:?}\n{:?}",
                got[i], single[i]
            );
        }
        let (ok, report) = verify_log(&dir);
        assert!(ok, "replica {id}'s log does not verify:\n{report}");
    }
    println!(
        "{tag}: {} records, digest {} (the single coordinator and every replica)",
        single.len(),
        records_digest(&single)
    );
}

#[test]
fn three_replicas_decide_the_demo_as_one_coordinator_does() {
    same_rounds_as_one_coordinator("rdemo", &repo_root().join("scenarios/demo.toml"), None);
}

#[test]
fn three_replicas_decide_a_32_agent_run_as_one_coordinator_does() {
    let scenario = repo_root().join("scenarios/random-32-32-10.toml");
    same_rounds_as_one_coordinator("r32", &scenario, Some("32"));
}

/// `hnav ps` shows each replica's Raft role and term: one leader among three.
#[test]
fn hnav_ps_shows_each_replicas_role_and_term() {
    use hnav_tests::swarm::wait_for_ps;
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let mut test_run = TestRun::new("rps");
    let scenario = repo_root().join("scenarios/demo.toml");
    let mut swarm = SwarmRun::start(
        &mut test_run,
        &scenario,
        &tmp.path().join("out"),
        &registry,
        &["--mode", "realtime", "--replicas", "3"],
    )
    .expect("hnav run starts");
    let replicas = |run: &serde_json::Value| -> Vec<serde_json::Value> {
        run["processes"]
            .as_array()
            .into_iter()
            .flatten()
            .filter(|p| p["role"] == "coordinator")
            .cloned()
            .collect()
    };
    let listed = wait_for_ps(
        &registry,
        test_run.run.as_str(),
        Duration::from_secs(60),
        |run| {
            let r = replicas(run);
            r.len() == 3
                && r.iter().all(|p| p["raft"]["term"].as_u64() >= Some(1))
                && r.iter().filter(|p| p["raft"]["role"] == "leader").count() == 1
        },
    );
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    let listed = listed.unwrap_or_else(|e| panic!("{e}\n{}", swarm.log_tails()));
    assert!(status.success(), "{status}\n{}", swarm.log_tails());
    let r = replicas(&listed);
    let indices: Vec<u64> = r.iter().filter_map(|p| p["index"].as_u64()).collect();
    assert_eq!(indices, [1, 2, 3], "{listed}");
}

/// A replica stopped by SIGTERM leaves the cluster, not the run: the leader, told to stop by
/// a signal rather than by the supervisor's `Stop`, logged the run's end (`stopped`) into the
/// replicated log, so the replica elected after it found the run over and decided nothing
/// more (the run then waited for ever). Now the others go on and bring every robot home.
#[test]
fn a_leader_stopped_by_sigterm_leaves_the_run_to_the_others() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let dir = tmp.path().join("out");
    let mut test_run = TestRun::new("rterm");
    let scenario = repo_root().join("scenarios/demo.toml");
    let args = [
        "--mode",
        "lockstep",
        "--replicas",
        "3",
        "--term",
        "coordinator@round:300",
    ];
    let mut swarm =
        SwarmRun::start(&mut test_run, &scenario, &dir, &registry, &args).expect("hnav run starts");
    // The demo takes a few seconds in lockstep; a run that stopped deciding never ends.
    let status = swarm.finish(Duration::from_secs(180));
    let status = status.unwrap_or_else(|e| panic!("{e}\n{}", swarm.log_tails()));
    assert!(status.success(), "{status}\n{}", swarm.log_tails());
    let s = swarm.summary().unwrap();
    assert_eq!(s["end"], "all-at-goal", "{s}\n{}", swarm.log_tails());
    let mut ended = 0;
    for id in 1..=3 {
        let log = dir.join("log").join(id.to_string());
        let (ok, report) = verify_log(&log);
        assert!(ok, "replica {id}'s log does not verify:\n{report}");
        let records = read_decided(&log).unwrap().records;
        let ends: Vec<_> = records
            .iter()
            .filter_map(|r| match r {
                Record::End(e) => Some(e.reason),
                _ => None,
            })
            .collect();
        // The stopped one ends its log where it stopped, without an end record of its own.
        assert!(
            ends.iter().all(|&r| r == EndReason::AllAtGoal) && ends.len() <= 1,
            "replica {id} logged the ends {ends:?}"
        );
        ended += ends.len();
    }
    // The one that led at the end logged it (the other may have stopped before it heard the
    // commit).
    assert!(ended >= 1, "no replica logged the run's end");
}

/// A replica killed while the others decide far past the snapshot threshold comes back
/// behind their snapshots: it installs its leader's snapshot (the entries it missed are
/// compacted away), and every replica's log, each compacted, verifies and adds up to the
/// same state.
///
/// Realtime, because a lockstep run holds its rounds while a killed process is away (that
/// is what keeps it reproducible), so no replica ever falls behind a snapshot there.
#[test]
fn a_replica_left_far_behind_catches_up_from_a_snapshot() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let dir = tmp.path().join("out");
    let demo = std::fs::read_to_string(repo_root().join("scenarios/demo.toml")).unwrap();
    let scenario = tmp.path().join("demo-snapshots.toml");
    let compacting = demo.replacen(
        "[coordinator]\n",
        "[coordinator]\nsnapshot_entries = 10\n",
        1,
    );
    assert_ne!(compacting, demo, "the demo has a [coordinator] table");
    // Restarted 2 s after its kill: the others (a new leader elected meanwhile if it led)
    // decide about a hundred rounds without it, ten snapshots' worth.
    let compacting = format!("{compacting}\n[restart.coordinator]\nbackoff_ms = 2000\n");
    std::fs::write(&scenario, compacting).unwrap();
    let args = ["--replicas", "3", "--kill", "coordinator:2@round:40"];
    run_in("realtime", "rsnap", &scenario, &dir, &registry, &args);
    let logs = std::fs::read_dir(dir.join("logs")).unwrap();
    let installed = logs.flatten().any(|e| {
        std::fs::read_to_string(e.path())
            .is_ok_and(|t| t.contains("installed the leader's snapshot"))
    });
    assert!(
        installed,
        "no replica installed a snapshot\n{}",
        hnav_tests::swarm::log_tails(&dir)
    );
    let mut states = Vec::new();
    for id in 1..=3 {
        let log = dir.join("log").join(id.to_string());
        let (ok, report) = verify_log(&log);
        assert!(ok, "replica {id}'s log does not verify:\n{report}");
        assert!(
            report.contains("snapshot   index"),
            "replica {id} never compacted:\n{report}"
        );
        let d = read_decided(&log).unwrap();
        let Some(Record::Header(h)) = d.records.first() else {
            panic!("replica {id}'s log has no header");
        };
        let mut state = d.compacted.clone().unwrap_or_else(|| AppliedState::new(h));
        for r in &d.records[1..] {
            state.fold(r);
        }
        assert_eq!(
            state.end.map(|e| e.reason),
            Some(EndReason::AllAtGoal),
            "replica {id}"
        );
        states.push(state);
    }
    assert!(states.iter().all(|s| *s == states[0]), "{states:#?}");
}

/// The leader's own `down` is heard only by the followers: it dies, so it cannot log it,
/// and no one leads while the supervisor publishes it. The replica elected next logged the
/// old leader's `restarted` but never its `down`, so the log said a process came back that
/// never went away. Now what a follower heard of a process other than an agent (a replica,
/// the sim) and no leader logged is logged by the next leader, in the order heard.
#[test]
fn a_killed_leaders_down_is_logged_by_the_next_leader() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let dir = tmp.path().join("out");
    let scenario = repo_root().join("scenarios/demo.toml");
    let args = ["--replicas", "3", "--kill", "coordinator@round:300"];
    run("rdown", &scenario, &dir, &registry, &args);
    let log = dir.join("log").join("1");
    let (ok, report) = verify_log(&log);
    assert!(ok, "replica 1's log does not verify:\n{report}");
    let events: Vec<(LifecycleEvent, u32, u32)> = read_decided(&log)
        .unwrap()
        .records
        .iter()
        .filter_map(|r| match r {
            Record::Lifecycle(l) if Role::from_u8(l.role) == Some(Role::Coordinator) => {
                Some((LifecycleEvent::from_u8(l.event)?, l.index, l.restarts))
            }
            _ => None,
        })
        .collect();
    let restarted: Vec<_> = events
        .iter()
        .filter(|e| e.0 == LifecycleEvent::Restarted)
        .collect();
    assert_eq!(
        restarted.len(),
        1,
        "one leader killed, one restart: {events:?}"
    );
    let (_, killed, restarts) = *restarted[0];
    assert_eq!(
        events,
        [
            (LifecycleEvent::Down, killed, restarts - 1),
            (LifecycleEvent::Restarted, killed, restarts)
        ],
        "the killed leader's events as logged"
    );
}
