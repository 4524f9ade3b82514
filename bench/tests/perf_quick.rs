//! `hnav-bench perf --quick` through the binary: the whole performance suite runs (latency,
//! decision round at 1 to 256 agents, commit fan-out, neural map) and writes every point it promises. For the
//! latency part: each transport in each of its modes, both directions, every default size,
//! with the sample count the method gives that size, as CSV (dora-benchmark's columns first),
//! markdown and SVG. A smoke check: nothing here is a timing.

use std::collections::BTreeSet;
use std::time::Duration;

use hnav_bench::latency::{csv, Options, TransportKind, DEFAULT_SIZES};

mod common;
use common::bench_within;

/// The quick suite takes under a minute on a quiet machine; past this it hangs.
const LIMIT: Duration = Duration::from_secs(400);

#[test]
fn the_quick_suite_writes_every_point() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().display().to_string();
    // A peer's rows (as `bench/peers/zenoh/run.sh` writes them) join the latency table.
    let peers = dir.path().join("peers-zenoh.csv");
    let row = |d: &str| {
        format!("2026-12-03T07:00:00Z,Rust,linux-x86_64-2cpu,zenoh/event/{d},64,30.5,29.1,33.0,60.2,5000,90.0,400.0")
    };
    std::fs::write(
        &peers,
        format!("{}\n{}\n{}\n", csv::HEADER, row("oneway"), row("roundtrip")),
    )
    .unwrap();
    let peers = peers.display().to_string();
    let run = bench_within(
        &["perf", "--quick", "--out", &out, "--peers", &peers],
        LIMIT,
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    latency_points(dir.path(), &stdout);
    round_points(dir.path());
    fanout_points(dir.path());
    let md = std::fs::read_to_string(dir.path().join("perf.md")).unwrap();
    for part in [
        "## latency",
        "## round",
        "## fanout",
        "## neural-map",
        "512x512",
    ] {
        assert!(md.contains(part), "no {part:?} in perf.md");
    }
}

/// `fanout.csv`: every mechanism at every default listener count, the quick sample count.
fn fanout_points(dir: &std::path::Path) {
    let text = std::fs::read_to_string(dir.join("fanout.csv")).unwrap();
    let mut seen = BTreeSet::new();
    for line in text.lines().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        assert_eq!(
            cols[2].parse::<usize>().unwrap(),
            hnav_bench::fanout::ROUNDS_QUICK,
            "{line}"
        );
        seen.insert((cols[0].to_string(), cols[1].parse::<usize>().unwrap()));
    }
    let mut expected = BTreeSet::new();
    for m in ["hnav", "hnav-bell", "eventfd", "futex"] {
        for n in [1, 8, 32, 128, 256] {
            expected.insert((m.to_string(), n));
        }
    }
    assert_eq!(seen, expected);
}

/// `round.csv`: both fsync policies at every swarm size up to 256 agents, both measures.
fn round_points(dir: &std::path::Path) {
    let text = std::fs::read_to_string(dir.join("round.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (measure, agents, fsync) = (col("measure"), col("agents"), col("fsync"));
    let mut seen = BTreeSet::new();
    for line in text.lines().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        seen.insert((
            cols[measure].to_string(),
            cols[agents].parse::<usize>().unwrap(),
            cols[fsync].to_string(),
        ));
    }
    let mut expected = BTreeSet::new();
    for m in [
        "last_candidate_to_all_commits",
        "last_candidate_to_first_commit",
    ] {
        for n in [1, 8, 32, 128, 256] {
            for f in ["every-record", "none"] {
                expected.insert((m.to_string(), n, f.to_string()));
            }
        }
    }
    assert_eq!(seen, expected, "{text}");
}

/// `latency.csv`, `latency.md`, `latency.svg` and the ratios in the printed report.
fn latency_points(dir: &std::path::Path, stdout: &str) {
    let text = std::fs::read_to_string(dir.join("latency.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(csv::HEADER));
    let opts = Options::new(true, dir.to_path_buf());
    let mut seen = BTreeSet::new();
    for line in lines {
        let cols: Vec<&str> = line.split(',').collect();
        assert_eq!(cols.len(), csv::HEADER.split(',').count(), "{line}");
        let size: usize = cols[4].parse().unwrap();
        let n: usize = cols[9].parse().unwrap();
        if !cols[3].starts_with("zenoh/") {
            assert_eq!(n, opts.iterations_for(size), "{line}");
        }
        // avg, p50, p90, p99, n, p99.9, max: ordered percentiles, max the largest.
        let us: Vec<f64> = [6, 7, 8, 10, 11]
            .iter()
            .map(|&i| cols[i].parse().unwrap())
            .collect();
        assert!(us.windows(2).all(|w| w[0] <= w[1]), "{line}");
        assert!(seen.insert((cols[3].to_string(), size)), "twice: {line}");
    }
    let mut expected = BTreeSet::new();
    for t in TransportKind::ALL {
        for size in DEFAULT_SIZES.into_iter().filter(|&s| t.measures(s)) {
            for mode in t.modes() {
                for dir in ["oneway", "roundtrip"] {
                    expected.insert((format!("{}/{}/{dir}", t.name(), mode.name()), size));
                }
            }
        }
    }
    for dir in ["oneway", "roundtrip"] {
        expected.insert((format!("zenoh/event/{dir}"), 64));
    }
    assert_eq!(seen, expected);
    assert!(
        stdout
            .lines()
            .any(|l| l.starts_with("zenoh ") && l.contains("64 B")),
        "the peer is not in the other / hnav ratios:\n{stdout}"
    );

    let md = std::fs::read_to_string(dir.join("latency.md")).unwrap();
    assert_eq!(
        md.matches("| hnav/event/oneway |").count(),
        DEFAULT_SIZES.len()
    );
    let svg = std::fs::read_to_string(dir.join("latency.svg")).unwrap();
    assert!(svg.contains("crossbeam/poll") && svg.contains("tcp/event"));
    for ratio in ["hnav / iceoryx2", "hnav one-way, large /", "other / hnav"] {
        assert!(stdout.contains(ratio), "no {ratio:?} in:\n{stdout}");
    }
}
