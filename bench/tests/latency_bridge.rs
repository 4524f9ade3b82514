//! `hnav-bench latency --only hnav-bridge`: the ping-pong through two `hnav-bridge`s over
//! Zenoh writes its one-way and round-trip rows into `latency.csv` with the sample count the
//! method gives each size, and a size that is no whole number of `f32` (10 B) is skipped. A smoke
//! check: nothing here is a timing.

use std::time::Duration;

use hnav_bench::latency::Options;

mod common;
use common::latency_csv;

/// Seconds on a quiet machine; past this it hangs.
const LIMIT: Duration = Duration::from_secs(180);

#[test]
fn the_bridge_rows_join_the_latency_table() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().display().to_string();
    let text = latency_csv(
        &[
            "latency",
            "--quick",
            "--only",
            "hnav-bridge",
            "--sizes",
            "10,64,4096",
            "--out",
            &out,
        ],
        dir.path(),
        LIMIT,
    );
    let opts = Options::new(true, dir.path().to_path_buf());
    let mut rows: Vec<(String, usize)> = Vec::new();
    for line in text.lines().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        let size: usize = cols[4].parse().unwrap();
        assert_eq!(
            cols[9].parse::<usize>().unwrap(),
            opts.iterations_for(size),
            "{line}"
        );
        rows.push((cols[3].to_string(), size));
    }
    rows.sort();
    let expected: Vec<(String, usize)> = [4096, 64]
        .into_iter()
        .flat_map(|s| ["oneway", "roundtrip"].map(|d| (format!("hnav-bridge/event/{d}"), s)))
        .collect();
    let mut expected = expected;
    expected.sort();
    assert_eq!(rows, expected, "{text}");
}
