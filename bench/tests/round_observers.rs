//! `hnav-bench round --observers`: the decision round with and without the run's observers
//! (`hnav-ros2` beside it, the live Foxglove view in the bench's process), through the
//! binary, both rows in one run. A smoke check: nothing here is a timing.

use std::collections::BTreeSet;
use std::time::Duration;

mod common;
use common::{bench_within, round_rows};

/// A few seconds on a quiet machine; past this it hangs.
const LIMIT: Duration = Duration::from_secs(180);

#[test]
fn the_round_is_measured_with_and_without_ros2_and_foxglove_in_one_run() {
    let args = [
        "--agents",
        "8",
        "--fsync",
        "none",
        "--observers",
        "none,ros2+foxglove",
    ];
    let (rows, csv) = round_rows(&args, LIMIT);
    let seen: BTreeSet<String> = (rows.iter())
        .map(|v| v["observers"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(
        seen,
        BTreeSet::from(["none".to_string(), "ros2+foxglove".to_string()]),
        "{rows:?}"
    );
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
