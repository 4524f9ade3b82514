//! `hnav-bench round --agents-per-process`: the decision round with one agent process per
//! robot and with several robots a process (one commit subscriber and one candidate wake-up
//! per process), both rows in one run, through the binary. A smoke check: nothing here is a
//! timing; what is checked is that every robot of a shared process got every commit.

use std::collections::BTreeSet;
use std::time::Duration;

mod common;
use common::{bench_within, round_rows};

/// A few seconds on a quiet machine; past this it hangs.
const LIMIT: Duration = Duration::from_secs(180);

#[test]
fn the_round_is_measured_with_one_and_with_five_robots_a_process_in_one_run() {
    // 12 robots by 5: processes of 5, 5 and 2, so a short last process is played too.
    let args = [
        "--agents",
        "12",
        "--fsync",
        "none",
        "--agents-per-process",
        "1,5",
    ];
    let (rows, csv) = round_rows(&args, LIMIT);
    let mut seen = BTreeSet::new();
    for v in &rows {
        assert_eq!(v["agents"], 12, "{v}");
        seen.insert(v["agents_per_process"].as_u64().unwrap());
    }
    assert_eq!(seen, BTreeSet::from([1, 5]), "{rows:?}");
    assert!(
        csv.contains("last_candidate_to_all_commits_5_per_process"),
        "{csv}"
    );
    let bad = bench_within(&["round", "--agents-per-process", "0"], LIMIT);
    assert!(!bad.status.success());
    assert!(
        String::from_utf8_lossy(&bad.stderr).contains("--agents-per-process 0: must be 1 to 256"),
        "{}",
        String::from_utf8_lossy(&bad.stderr)
    );
}
