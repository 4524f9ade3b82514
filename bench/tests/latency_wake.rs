//! `hnav-bench latency --only hnav,hnav-waitset,uds-dgram --modes event`: the HNAV row (the
//! receiver's `SingleWaiter`), the opt-in row through the general `Waiter` and the datagram
//! floor all join the latency table, the floor at 64 B only. A smoke check: nothing here is a
//! timing.

use std::time::Duration;

mod common;
use common::latency_csv;

/// Seconds on a quiet machine; past this it hangs.
const LIMIT: Duration = Duration::from_secs(180);

#[test]
fn the_wait_rows_and_the_datagram_floor_join_the_latency_table() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().display().to_string();
    let args = [
        "latency",
        "--quick",
        "--only",
        "hnav,hnav-waitset,uds-dgram",
        "--modes",
        "event",
        "--sizes",
        "64,4096",
        "--out",
        &out,
    ];
    let text = latency_csv(&args, dir.path(), LIMIT);
    let mut rows: Vec<(String, usize)> = text
        .lines()
        .skip(1)
        .map(|line| {
            let cols: Vec<&str> = line.split(',').collect();
            (cols[3].to_string(), cols[4].parse().unwrap())
        })
        .collect();
    rows.sort();
    let mut expected: Vec<(String, usize)> = [("hnav", 64), ("hnav", 4096)]
        .into_iter()
        .chain([
            ("hnav-waitset", 64),
            ("hnav-waitset", 4096),
            ("uds-dgram", 64),
        ])
        .flat_map(|(t, s)| ["oneway", "roundtrip"].map(|d| (format!("{t}/event/{d}"), s)))
        .collect();
    expected.sort();
    assert_eq!(rows, expected, "{text}");
}
