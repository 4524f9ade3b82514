//! `hnav-bench round --observers`: the decision round with and without the run's observers
//! (`hnav-ros2` beside it, the live Foxglove view in the bench's process), through the
//! binary, both rows in one run. A smoke check: nothing here is a timing.

use std::collections::BTreeSet;
use std::time::Duration;

mod common;
use common::bench_within;

/// A few seconds on a quiet machine; past this it hangs.
const LIMIT: Duration = Duration::from_secs(180);

#[test]
fn the_round_is_measured_with_and_without_ros2_and_foxglove_in_one_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().display().to_string();
    let run = bench_within(
        &[
            "round",
            "--agents",
            "8",
            "--fsync",
            "none",
            "--observers",
            "none,ros2+foxglove",
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
    let mut seen = BTreeSet::new();
    for line in stdout.lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        if v["bench"] != "round" {
            continue;
        }
        let (rounds, stalled) = (
            v["rounds"].as_u64().unwrap(),
            v["stalled"].as_u64().unwrap(),
        );
        assert_eq!(rounds + stalled, 60, "{line}");
        seen.insert(v["observers"].as_str().unwrap().to_string());
    }
    assert_eq!(
        seen,
        BTreeSet::from(["none".to_string(), "ros2+foxglove".to_string()]),
        "{stdout}"
    );
    let csv = std::fs::read_to_string(dir.path().join("round.csv")).unwrap();
    assert!(
        csv.contains("last_candidate_to_all_commits_with_ros2+foxglove"),
        "{csv}"
    );
    let bad = bench_within(&["round", "--observers", "rviz"], LIMIT);
    assert!(!bad.status.success());
    assert!(
        String::from_utf8_lossy(&bad.stderr).contains("unknown observer \"rviz\""),
        "{}",
        String::from_utf8_lossy(&bad.stderr)
    );
}
