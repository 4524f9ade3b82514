//! `hnav-peer-zenoh`: zenoh pub/sub latency measured with the method of HNAV's own latency
//! suite (`hnav-bench latency`, `bench/src/latency/` in the main workspace), written as rows
//! of HNAV's `latency.csv` so `hnav-bench latency --peers FILE` can show zenoh beside iceoryx2.

mod pingpong;
// HNAV's own summary statistics, compiled in from the workspace so that a peer row and an
// HNAV row are summarised by the same code (this project stays outside the workspace, so it
// cannot depend on hnav-bench without building iceoryx2 and the rest).
#[allow(dead_code)]
#[path = "../../../src/latency/stats.rs"]
mod stats;
mod zenoh_pair;

use std::io::Write;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Parser;

use stats::Summary;
use zenoh_pair::Variant;

/// HNAV's CSV header (`bench/src/latency/csv.rs`): dora-benchmark's columns, then the tail.
const HEADER: &str =
    "date,language,platform,name,size_bytes,avg_us,p50_us,p90_us,p99_us,n,p999_us,max_us";
/// Measured iterations per small point, as HNAV: full run and `--quick`.
const ITERATIONS_FULL: usize = 100_000;
const ITERATIONS_QUICK: usize = 5_000;
/// Warm-up iterations per small point, discarded.
const WARMUP: usize = 1_000;
const MIB: usize = 1024 * 1024;
/// HNAV's default sizes: 8 B to a 40 MiB point cloud.
const DEFAULT_SIZES: [usize; 7] = [8, 64, 4096, 65_536, MIB, 4 * MIB, 40 * MIB];

/// Zenoh pub/sub latency (one-way and round trip) between two sessions of one process over
/// loopback TCP, plain and with zenoh's shared memory, in HNAV's latency CSV format.
#[derive(Debug, Parser)]
#[command(name = "hnav-peer-zenoh", version)]
struct Cli {
    /// CSV file to write (replaced).
    #[arg(long, required_unless_present = "cleanup_shm")]
    out: Option<PathBuf>,
    /// Only remove the zenoh SHM segments in /dev/shm that no process holds any more, and
    /// exit. Zenoh cannot remove the segments its own globals still hold when a process
    /// exits (about 1.3 MiB of `*.zenoh` per run); run.sh calls this after measuring.
    #[arg(long)]
    cleanup_shm: bool,
    /// 5,000 iterations per small point instead of 100,000 (HNAV's --quick).
    #[arg(long)]
    quick: bool,
    /// Payload sizes in bytes, comma separated (without the 16-byte header).
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_SIZES)]
    sizes: Vec<usize>,
    /// Variants to measure, comma separated: zenoh (TCP), zenoh-shm (shared memory).
    #[arg(long, value_delimiter = ',', default_values = ["zenoh", "zenoh-shm"])]
    variants: Vec<Variant>,
}

/// One measured row.
struct Row {
    name: String,
    size: usize,
    summary: Summary,
}

/// Iterations at `size`, HNAV's `Options::iterations_for`: all up to 64 KiB, a tenth from
/// 1 MiB, a hundredth from 16 MiB, never fewer than 10.
fn iterations_for(iterations: usize, size: usize) -> usize {
    let divisor = match size {
        s if s >= 16 * MIB => 100,
        s if s >= MIB => 10,
        _ => 1,
    };
    (iterations / divisor).max(10)
}

/// Warm-up at `size`, HNAV's `Options::warmup_for`: scaled like the measured ones, at least 1.
fn warmup_for(iterations: usize, size: usize) -> usize {
    let warmup = WARMUP.min(iterations);
    let scale = iterations_for(iterations, size) as f64 / iterations.max(1) as f64;
    ((warmup as f64 * scale).ceil() as usize).max(1)
}

/// `<os>-<arch>-<n>cpu`, as HNAV.
fn platform() -> String {
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!(
        "{}-{}-{cpus}cpu",
        std::env::consts::OS,
        std::env::consts::ARCH
    )
}

/// The current UTC time as ISO 8601 seconds (`2026-12-03T07:00:00Z`).
fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    utc_iso(secs)
}

/// Seconds since the Unix epoch as ISO 8601 UTC (days to civil date: H. Hinnant's algorithm).
fn utc_iso(secs: u64) -> String {
    let (days, rem) = ((secs / 86_400) as i64, secs % 86_400);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1_460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

/// Threads of this process restricted to fewer CPUs than the process may use: zenoh threads
/// that inherited a benchmark thread's pinning (checked after each point, when the two
/// benchmark threads are gone).
fn pinned_threads() -> Vec<String> {
    let allowed = |path: std::path::PathBuf| -> Option<String> {
        let status = std::fs::read_to_string(path).ok()?;
        status
            .lines()
            .find_map(|l| l.strip_prefix("Cpus_allowed_list:"))
            .map(|s| s.trim().to_string())
    };
    let Some(all) = allowed("/proc/self/status".into()) else {
        return Vec::new();
    };
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return Vec::new();
    };
    tasks
        .flatten()
        .filter_map(|t| {
            let cpus = allowed(t.path().join("status"))?;
            let name = std::fs::read_to_string(t.path().join("comm")).unwrap_or_default();
            (cpus != all).then(|| {
                format!(
                    "{} ({}) on {cpus}",
                    name.trim(),
                    t.file_name().to_string_lossy()
                )
            })
        })
        .collect()
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    if cli.cleanup_shm {
        zenoh::shm::cleanup_orphaned_shm_segments();
        return Ok(());
    }
    let out_path = cli.out.clone().context("--out is required")?;
    if cli.sizes.is_empty() || cli.sizes.contains(&0) {
        bail!("--sizes must be a non-empty list of positive byte counts");
    }
    if cli.variants.is_empty() {
        bail!("--variants must name at least one of zenoh, zenoh-shm");
    }
    let iterations = if cli.quick {
        ITERATIONS_QUICK
    } else {
        ITERATIONS_FULL
    };
    let (date, platform) = (utc_now(), platform());
    let started = std::time::Instant::now();
    let mut rows = Vec::new();
    let mut failed = Vec::new();
    // Size by size, both variants back to back, so the pair compared ran under the same
    // machine conditions (as HNAV orders its points).
    for &size in &cli.sizes {
        for &variant in &cli.variants {
            let (w, n) = (
                warmup_for(iterations, size),
                iterations_for(iterations, size),
            );
            eprintln!(
                "measuring {}/event {size} B: {n} + {w} warm-up round trips",
                variant.name()
            );
            // A failed point (a lost message) is left out and said, not the whole table.
            let samples = match zenoh_pair::measure(variant, size, w, n) {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("error: ping-pong {}/event {size} B: {e:#}", variant.name());
                    failed.push(format!("{}/event {size} B", variant.name()));
                    continue;
                }
            };
            for (direction, ns) in [
                ("oneway", &samples.oneway),
                ("roundtrip", &samples.roundtrip),
            ] {
                rows.push(Row {
                    name: format!("{}/event/{direction}", variant.name()),
                    size,
                    summary: Summary::from_ns(ns)?,
                });
            }
            let pinned = pinned_threads();
            if !pinned.is_empty() {
                eprintln!(
                    "warning: threads left pinned by the benchmark: {}",
                    pinned.join(", ")
                );
            }
        }
    }

    let mut csv = String::from(HEADER);
    csv.push('\n');
    for r in &rows {
        let s = &r.summary;
        csv.push_str(&format!(
            "{date},Rust,{platform},{},{},{:.3},{:.3},{:.3},{:.3},{},{:.3},{:.3}\n",
            r.name,
            r.size,
            s.mean_us(),
            s.p50_us(),
            s.p90_us(),
            s.p99_us(),
            s.n,
            s.p999_us(),
            s.max_us()
        ));
    }
    if let Some(dir) = out_path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("create {}", dir.display()))?;
    }
    std::fs::write(&out_path, csv).with_context(|| format!("write {}", out_path.display()))?;

    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "zenoh 1.10.2 latency, {platform}, {} ({}), threads {}pinned, {:.1} s",
        date,
        if cli.quick { "quick" } else { "full" },
        if pingpong::pinning_possible() {
            ""
        } else {
            "not "
        },
        started.elapsed().as_secs_f64()
    )?;
    writeln!(
        out,
        "{:<26} {:>10} {:>7} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11}",
        "name", "size_B", "n", "avg_us", "p50_us", "p90_us", "p99_us", "p99.9_us", "max_us"
    )?;
    for r in &rows {
        let s = &r.summary;
        writeln!(
            out,
            "{:<26} {:>10} {:>7} {:>11.3} {:>11.3} {:>11.3} {:>11.3} {:>11.3} {:>11.3}",
            r.name,
            r.size,
            s.n,
            s.mean_us(),
            s.p50_us(),
            s.p90_us(),
            s.p99_us(),
            s.p999_us(),
            s.max_us()
        )?;
    }
    writeln!(out, "wrote {}", out_path.display())?;
    if !failed.is_empty() {
        bail!("points left out after a failure: {}", failed.join(", "));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iterations_follow_hnav() {
        let q = ITERATIONS_QUICK;
        assert_eq!(
            [8, 65_536, MIB, 4 * MIB, 40 * MIB].map(|s| iterations_for(q, s)),
            [5000, 5000, 500, 500, 50]
        );
        assert_eq!(
            [8, MIB, 40 * MIB].map(|s| warmup_for(q, s)),
            [1000, 100, 10]
        );
        let f = ITERATIONS_FULL;
        assert_eq!(
            [8, MIB, 40 * MIB].map(|s| iterations_for(f, s)),
            [100_000, 10_000, 1_000]
        );
        assert_eq!(
            [8, MIB, 40 * MIB].map(|s| warmup_for(f, s)),
            [1000, 100, 10]
        );
        assert_eq!(iterations_for(500, 40 * MIB), 10);
    }

    #[test]
    fn dates_are_iso_utc() {
        assert_eq!(utc_iso(0), "1970-01-01T00:00:00Z");
        assert_eq!(utc_iso(1_796_281_200), "2026-12-03T07:00:00Z");
        assert_eq!(utc_iso(951_782_400), "2000-02-29T00:00:00Z");
    }
}
