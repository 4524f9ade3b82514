//! `hnav-bench round --replicas`: the decision round against one coordinator and against a
//! Raft cluster of 3 replicas, through the binary. Every point is measured and written (JSON
//! and CSV); a cluster size other than 1, 3 or 5 is refused with a clear error. A smoke check:
//! nothing here is a timing.

use std::collections::BTreeSet;
use std::time::Duration;

mod common;
use common::{bench_within, round_rows};

/// A few seconds on a quiet machine (an election takes up to 1 s); past this it hangs.
const LIMIT: Duration = Duration::from_secs(180);

#[test]
fn one_coordinator_and_three_replicas_are_measured_side_by_side() {
    let args = [
        "--agents",
        "8",
        "--fsync",
        "every-record",
        "--replicas",
        "1,3",
    ];
    let (rows, csv) = round_rows(&args, LIMIT);
    let mut replicas = BTreeSet::new();
    for v in &rows {
        assert_eq!(v["agents"], 8, "{v}");
        assert_eq!(v["fsync"], "every-record", "{v}");
        assert!(v["p50_us"].as_f64().unwrap() > 0.0, "{v}");
        replicas.insert(v["replicas"].as_u64().unwrap());
    }
    assert_eq!(replicas, BTreeSet::from([1, 3]), "{rows:?}");

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
