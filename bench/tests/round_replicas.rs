//! `hnav-bench round --replicas`: the decision round against one coordinator and against a
//! Raft cluster of 3 replicas, through the binary. Every point is measured and written (JSON
//! and CSV); a cluster size other than 1, 3 or 5 is refused with a clear error. A smoke check:
//! nothing here is a timing.

use std::collections::BTreeSet;
use std::time::Duration;

mod common;
use common::bench_within;

/// A few seconds on a quiet machine (an election takes up to 1 s); past this it hangs.
const LIMIT: Duration = Duration::from_secs(180);

#[test]
fn one_coordinator_and_three_replicas_are_measured_side_by_side() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().display().to_string();
    let run = bench_within(
        &[
            "round",
            "--agents",
            "8",
            "--fsync",
            "every-record",
            "--replicas",
            "1,3",
            "--rounds",
            "60",
            "--warmup",
            "20",
            "--json",
            "--out",
            &out,
        ],
        LIMIT,
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let mut replicas = BTreeSet::new();
    for line in stdout.lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        if v["bench"] != "round" {
            continue;
        }
        assert_eq!(v["agents"], 8, "{line}");
        assert_eq!(v["fsync"], "every-record", "{line}");
        // Stalled rounds are left out of the distribution; every other round is in it.
        let (rounds, stalled) = (
            v["rounds"].as_u64().unwrap(),
            v["stalled"].as_u64().unwrap(),
        );
        assert_eq!(rounds + stalled, 60, "{line}");
        assert!(v["p50_us"].as_f64().unwrap() > 0.0, "{line}");
        replicas.insert(v["replicas"].as_u64().unwrap());
    }
    assert_eq!(replicas, BTreeSet::from([1, 3]), "{stdout}");

    let csv = std::fs::read_to_string(dir.path().join("round.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "replicas").unwrap();
    let seen: BTreeSet<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(col).unwrap())
        .collect();
    assert_eq!(seen, BTreeSet::from(["1", "3"]), "{csv}");
}

#[test]
fn a_cluster_of_two_is_refused() {
    let run = bench_within(&["round", "--replicas", "1,2"], LIMIT);
    assert!(!run.status.success());
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        stderr.contains("a coordinator cluster has 1, 3 or 5 members"),
        "{stderr}"
    );
}
