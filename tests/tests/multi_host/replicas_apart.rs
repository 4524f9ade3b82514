//! Coordinator replicas on hosts of their own: their Raft messages cross the bridges. The hub
//! (`base`) runs the sim and every agent, hosts `rep-1` to `rep-3` one replica each, so that
//! a replica host cut off still leaves the other two talking through the hub.
//!
//! The test cuts a follower's host off (rounds go on: the leader and the third replica are a
//! majority), then the leader's host as well (no majority: no round is committed), then
//! heals both (rounds resume). Every replica's log verifies, the replicas' committed records
//! agree, and no round is missing or logged twice.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use hnav_runtime::consensus_log::{read_decided, Record, ReplicaRole};
use hnav_tests::across::{self, one_at_a_time, Across, DomainPurge, RUN_TIMEOUT};
use hnav_tests::netns::Net;
use hnav_tests::swarm::verify_log;
use hnav_tests::TestRun;

use super::realtime_demo;

/// The hub, then one host per replica (host `i` runs replica `i`).
const HOSTS: [&str; 4] = ["base", "rep-1", "rep-2", "rep-3"];
/// Rounds committed before the first cut.
const CUT_AFTER_ROUNDS: u64 = 300;
/// Rounds that must be committed while only the follower's host is away, and again after
/// the healing.
const ROUNDS_WITH_MAJORITY: u64 = 20;
/// After the leader's host is cut: how long the cluster is given to notice (a leader steps
/// down after an election timeout without a majority, 500 ms to 1 s; a commit index decided
/// before the cut may still reach the log), then how long no round may be committed.
const SETTLE: Duration = Duration::from_millis(1500);
const WITHOUT_MAJORITY: Duration = Duration::from_secs(2);
/// How far apart the hosts' supervisors may end (they start within a second of each other,
/// and end on the first host's `Stop`).
const MAX_END_SPREAD_S: f64 = 10.0;

/// The placement: sim and agents on the hub, replica `i` alone on host `i`.
fn placement(dir: &Path) -> PathBuf {
    let mut text = format!(
        "[[host]]\nname = \"base\"\nlisten = [\"tcp/{}:7447\"]\nsim = true\nagents = \"0-5\"\n",
        Net::addr(0)
    );
    for (id, name) in HOSTS.iter().enumerate().skip(1) {
        text += &format!("\n[[host]]\nname = \"{name}\"\ncoordinator = [{id}]\n");
    }
    let file = dir.join("hosts.toml");
    std::fs::write(&file, text).unwrap();
    file
}

/// Replica `id`'s log directory (on its host, `rep-<id>`).
fn log_dir(across: &Across, id: usize) -> PathBuf {
    across.dirs[id].join("log").join(id.to_string())
}

/// The rounds replica `id` has committed so far (0 while its log cannot be read).
fn rounds(across: &Across, id: usize) -> u64 {
    read_decided(log_dir(across, id)).map_or(0, |d| {
        d.records
            .iter()
            .filter(|r| matches!(r, Record::Round(_)))
            .count() as u64
    })
}

/// The most rounds any replica has committed.
fn most_rounds(across: &Across) -> u64 {
    (1..HOSTS.len())
        .map(|id| rounds(across, id))
        .max()
        .unwrap_or(0)
}

/// Waits (bounded) until some replica has committed `target` rounds; fails at once if a
/// supervisor ends first.
fn wait_rounds(across: &mut Across, target: u64, what: &str) -> Duration {
    let t0 = Instant::now();
    let deadline = t0 + RUN_TIMEOUT;
    loop {
        let got = most_rounds(across);
        if got >= target {
            return t0.elapsed();
        }
        for (i, p) in across.supervisors.iter_mut().enumerate() {
            if let Ok(status) = p.wait_exit(Duration::ZERO) {
                panic!(
                    "host {} ended ({status}) at {got} rounds, waiting for {target} ({what})\n{}",
                    HOSTS[i],
                    across.tails()
                );
            }
        }
        assert!(
            Instant::now() < deadline,
            "{got} rounds, never {target} ({what})"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The replica whose role file says leader in the highest term, waited for (bounded).
fn leader(across: &Across) -> usize {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let roles =
            (1..HOSTS.len()).filter_map(|id| Some((id, ReplicaRole::read(&log_dir(across, id))?)));
        let lead = roles
            .filter(|(_, r)| r.role == "leader")
            .max_by_key(|(_, r)| r.term);
        if let Some((id, _)) = lead {
            return id;
        }
        assert!(Instant::now() < deadline, "no replica says it leads");
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn replicas_on_three_hosts_decide_with_a_majority_stop_without_and_resume_when_healed() {
    let _one = one_at_a_time();
    let Some(net) = across::net_or_skip("rep", HOSTS.len()) else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let scenario = realtime_demo(tmp.path());
    let hosts = placement(tmp.path());
    let mut run = TestRun::new("rep");
    let _purge = DomainPurge {
        run: run.run.clone(),
        hosts: HOSTS.iter().map(|h| h.to_string()).collect(),
    };
    // A fault for a process of another host than the hub's: every host reads the plan,
    // host `rep-2` carries it out (replica 2 is killed and restarted, and catches up).
    let extra = [
        "--mode",
        "realtime",
        "--replicas",
        "3",
        "--kill",
        "coordinator:2@round:150",
    ];
    let mut across = Across::start(
        &mut run,
        &net,
        &HOSTS,
        &hosts,
        &scenario,
        tmp.path(),
        &extra,
        &[],
    );
    wait_rounds(&mut across, CUT_AFTER_ROUNDS, "before the cuts");
    let lead = leader(&across);
    let follower = if lead == 1 { 2 } else { 1 };
    // A majority left: the leader and the third replica, through the hub.
    net.cut(follower, false).unwrap();
    let before = most_rounds(&across);
    let took = wait_rounds(&mut across, before + ROUNDS_WITH_MAJORITY, "one host cut");
    println!(
        "follower {follower}'s host cut: {ROUNDS_WITH_MAJORITY} rounds in {:.2} s by leader {lead}",
        took.as_secs_f64()
    );
    // No majority: the leader's host away too.
    net.cut(lead, false).unwrap();
    let cut_at = most_rounds(&across);
    std::thread::sleep(SETTLE); // the fault's length, not a synchronisation
    let settled = most_rounds(&across);
    std::thread::sleep(WITHOUT_MAJORITY);
    let still = most_rounds(&across);
    println!(
        "leader {lead}'s host cut too: {} rounds in the first {} ms, then {} in {} s",
        settled - cut_at,
        SETTLE.as_millis(),
        still - settled,
        WITHOUT_MAJORITY.as_secs()
    );
    assert_eq!(
        still, settled,
        "rounds were committed without a majority of the replicas"
    );
    net.cut(follower, true).unwrap();
    net.cut(lead, true).unwrap();
    let took = wait_rounds(&mut across, still + ROUNDS_WITH_MAJORITY, "healed");
    println!(
        "healed: {ROUNDS_WITH_MAJORITY} more rounds {:.2} s after",
        took.as_secs_f64()
    );
    across.finish();
    the_hosts_ended_together(&across);
    every_replica_holds_the_same_rounds_once(&across);
    only_its_host_carried_out_the_fault(&across);
}

/// `rep-2`'s journal has the kill of replica 2; no other host signalled anything.
fn only_its_host_carried_out_the_fault(across: &Across) {
    for (i, dir) in across.dirs.iter().enumerate() {
        let journal = std::fs::read_to_string(dir.join("events.jsonl")).unwrap_or_default();
        let kills: Vec<&str> = (journal.lines())
            .filter(|l| l.contains(r#""event":"signalled""#))
            .collect();
        match i {
            2 => {
                assert!(
                    kills.len() == 1 && kills[0].contains("coordinator-2"),
                    "rep-2's journal:\n{journal}"
                );
                println!("rep-2: {}", kills[0]);
            }
            _ => assert!(kills.is_empty(), "{} signalled: {kills:?}", HOSTS[i]),
        }
    }
}

/// Every host's supervisor ended with the run, none at its own time limit: a host that
/// missed the coordinator's last progress (a realtime bridge may drop it) ends on another
/// host's `Stop` (before, one host of three runs went on to the 120 s limit).
fn the_hosts_ended_together(across: &Across) {
    let walls: Vec<f64> = (across.dirs.iter())
        .map(|d| across::summary(d)["wall_time_s"].as_f64().unwrap())
        .collect();
    let (first, last) = walls
        .iter()
        .fold((f64::MAX, 0.0f64), |(lo, hi), &w| (lo.min(w), hi.max(w)));
    println!("the hosts ended {first:.1} to {last:.1} s after their start");
    assert!(
        last - first < MAX_END_SPREAD_S,
        "the hosts' wall times {walls:?}"
    );
}

/// Every replica's log verifies; the shorter committed records are a prefix of the longer;
/// the rounds of the longest go 0, 1, 2, ... without a gap or a repeat.
fn every_replica_holds_the_same_rounds_once(across: &Across) {
    let mut logs = Vec::new();
    for id in 1..HOSTS.len() {
        let (ok, report) = verify_log(&log_dir(across, id));
        assert!(ok, "replica {id}'s log does not verify:\n{report}");
        logs.push((id, read_decided(log_dir(across, id)).unwrap().records));
    }
    logs.sort_by_key(|(_, r)| r.len());
    let (_, longest) = logs.last().unwrap();
    for (id, records) in &logs {
        if let Some(i) = (0..records.len()).find(|&i| records[i] != longest[i]) {
            panic!("replica {id}: record {i} differs from the longest log's");
        }
    }
    let rounds: Vec<u64> = longest
        .iter()
        .filter_map(|r| match r {
            Record::Round(r) => Some(r.round),
            _ => None,
        })
        .collect();
    let first = rounds[0];
    if let Some(i) = (1..rounds.len()).find(|&i| rounds[i] != rounds[i - 1] + 1) {
        panic!(
            "round {} follows round {}: a round lost or logged twice",
            rounds[i],
            rounds[i - 1]
        );
    }
    let lens: Vec<String> = logs
        .iter()
        .map(|(id, r)| format!("replica {id}: {} records", r.len()))
        .collect();
    println!(
        "rounds {first} to {}, each once; {}",
        rounds.last().unwrap(),
        lens.join(", ")
    );
}
