//! Statistics and output of `hnav-bench round`: table rows, JSON lines, CSV files.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};
use hnav_runtime::scenario::FsyncPolicy;
use serde_json::json;

use super::layout::fsync_name;
use super::observers::Observers;

/// The distribution of one series of latencies (ns): the same summary `hnav-bench latency`
/// reports.
pub use crate::latency::Summary as Dist;

fn us(ns: u64) -> f64 {
    ns as f64 / 1e3
}

/// `round` with 1 decimal, for JSON.
pub(crate) fn us1(ns: u64) -> f64 {
    (ns as f64 / 100.0).round() / 10.0
}

/// One measured point of the round benchmark.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoundPoint {
    /// Agents in the swarm.
    pub agents: usize,
    /// The coordinator's fsync policy.
    pub fsync: FsyncPolicy,
    /// Coordinator processes: 1, or 3 or 5 Raft replicas.
    pub replicas: u32,
    /// The observers beside the run.
    pub observers: Observers,
    /// Robots per agent process.
    pub per_process: usize,
    /// Round latencies (to the last agent's commit).
    pub dist: Dist,
    /// Latencies to the first agent's commit.
    pub first: Dist,
    /// Measured rounds that stalled (lost wake-up) and are not in the distributions.
    pub stalled: usize,
}

/// The table header of the round benchmark.
pub fn round_header() -> String {
    format!(
        "{:>7} {:>8}  {:<13} {:>8} {:<14} {:>7} {:>10} {:>10} {:>10} | {:>10} {:>10} | {:>7}",
        "agents",
        "per proc",
        "fsync",
        "replicas",
        "observers",
        "rounds",
        "p50 µs",
        "p99 µs",
        "max µs",
        "1st p50",
        "1st p99",
        "stalled"
    )
}

impl RoundPoint {
    /// A table row.
    pub fn row(&self) -> String {
        let d = &self.dist;
        format!(
            "{:>7} {:>8}  {:<13} {:>8} {:<14} {:>7} {:>10.1} {:>10.1} {:>10.1} | {:>10.1} {:>10.1} | {:>7}",
            self.agents,
            self.per_process,
            fsync_name(self.fsync),
            self.replicas,
            self.observers.name(),
            d.n,
            us(d.p50_ns),
            us(d.p99_ns),
            us(d.max_ns),
            us(self.first.p50_ns),
            us(self.first.p99_ns),
            self.stalled
        )
    }

    /// The JSON line.
    pub fn json(&self) -> String {
        let d = &self.dist;
        json!({
            "bench": "round",
            "agents": self.agents,
            "agents_per_process": self.per_process,
            "fsync": fsync_name(self.fsync),
            "replicas": self.replicas,
            "observers": self.observers.name(),
            "p50_us": us1(d.p50_ns),
            "p99_us": us1(d.p99_ns),
            "max_us": us1(d.max_ns),
            "rounds": d.n,
            "first_p50_us": us1(self.first.p50_ns),
            "first_p99_us": us1(self.first.p99_ns),
            "stalled": self.stalled,
        })
        .to_string()
    }
}

/// One fault measurement.
#[derive(Debug, Clone, PartialEq)]
pub struct FaultPoint {
    /// Short key: `kill_to_wake`, `kill_to_down_published`, `kill_to_down_received`,
    /// `restarted_to_decision`.
    pub measure: &'static str,
    /// What the number spans, for the table.
    pub label: String,
    /// Agents and fsync policy of a measurement with a real coordinator.
    pub coordinator: Option<(usize, FsyncPolicy)>,
    /// The latencies.
    pub dist: Dist,
    /// Trials left out because a round stalled (lost wake-up, see `Swarm::play`).
    pub stalled: usize,
}

/// The table header of the fault measurements.
pub fn fault_header() -> String {
    format!(
        "{:<62} {:>6} {:>10} {:>10} {:>10}",
        "measure", "trials", "p50 µs", "p99 µs", "max µs"
    )
}

impl FaultPoint {
    /// A table row.
    pub fn row(&self) -> String {
        let d = &self.dist;
        format!(
            "{:<62} {:>6} {:>10.1} {:>10.1} {:>10.1}",
            self.label,
            d.n,
            us(d.p50_ns),
            us(d.p99_ns),
            us(d.max_ns)
        )
    }

    /// The JSON line.
    pub fn json(&self) -> String {
        let d = &self.dist;
        let mut v = json!({
            "bench": "faults",
            "measure": self.measure,
            "p50_us": us1(d.p50_ns),
            "p99_us": us1(d.p99_ns),
            "max_us": us1(d.max_ns),
            "trials": d.n,
            "stalled": self.stalled,
        });
        if let Some((agents, fsync)) = self.coordinator {
            v["agents"] = json!(agents);
            v["fsync"] = json!(fsync_name(fsync));
        }
        v.to_string()
    }
}

/// The CSV header of `round.csv` and `faults.csv`.
pub const CSV_HEADER: &str =
    "date,platform,bench,measure,agents,fsync,replicas,n,mean_us,p50_us,p90_us,p99_us,max_us,stalled";

fn csv_row(
    info: &crate::latency::RunInfo,
    bench: &str,
    measure: &str,
    coordinator: Option<(usize, FsyncPolicy, u32)>,
    d: &Dist,
    stalled: usize,
) -> String {
    let (agents, fsync, replicas) = coordinator
        .map_or((String::new(), "", String::new()), |(a, f, r)| {
            (a.to_string(), fsync_name(f), r.to_string())
        });
    format!(
        "{},{},{bench},{measure},{agents},{fsync},{replicas},{},{:.3},{:.3},{:.3},{:.3},{:.3},{stalled}",
        info.date,
        info.platform,
        d.n,
        d.mean_ns / 1e3,
        us(d.p50_ns),
        us(d.p90_ns),
        us(d.p99_ns),
        us(d.max_ns)
    )
}

/// Writes `DIR/round.csv`.
pub fn write_round_csv(dir: &Path, points: &[RoundPoint]) -> Result<std::path::PathBuf> {
    let info = crate::latency::RunInfo::now();
    let rows = points.iter().flat_map(|p| {
        let c = Some((p.agents, p.fsync, p.replicas));
        // The measure names the observers when there are any, so the file's columns stay.
        let mut with = match p.observers.name() {
            "none" => String::new(),
            o => format!("_with_{o}"),
        };
        if p.per_process > 1 {
            with.push_str(&format!("_{}_per_process", p.per_process));
        }
        [
            csv_row(
                &info,
                "round",
                &format!("last_candidate_to_all_commits{with}"),
                c,
                &p.dist,
                p.stalled,
            ),
            csv_row(
                &info,
                "round",
                &format!("last_candidate_to_first_commit{with}"),
                c,
                &p.first,
                p.stalled,
            ),
        ]
    });
    write_csv(&dir.join("round.csv"), rows)
}

/// Writes `DIR/faults.csv`.
pub fn write_fault_csv(dir: &Path, points: &[FaultPoint]) -> Result<std::path::PathBuf> {
    let info = crate::latency::RunInfo::now();
    let rows = points.iter().map(|p| {
        csv_row(
            &info,
            "faults",
            p.measure,
            // The fault measurements run against one coordinator.
            p.coordinator.map(|(a, f)| (a, f, 1)),
            &p.dist,
            p.stalled,
        )
    });
    write_csv(&dir.join("faults.csv"), rows)
}

fn write_csv(path: &Path, rows: impl Iterator<Item = String>) -> Result<std::path::PathBuf> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("create {}", dir.display()))?;
    }
    let mut text = String::from(CSV_HEADER);
    text.push('\n');
    for r in rows {
        text.push_str(&r);
        text.push('\n');
    }
    std::fs::File::create(path)
        .and_then(|mut f| f.write_all(text.as_bytes()))
        .with_context(|| format!("write {}", path.display()))?;
    Ok(path.to_path_buf())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dist_keeps_the_exact_max_and_mean() {
        let mut samples: Vec<u64> = (1..=1000).map(|v| v * 1000).collect();
        samples.push(123_456_789);
        let d = Dist::from_ns(&samples).unwrap();
        assert_eq!(d.n, 1001);
        assert_eq!(d.max_ns, 123_456_789);
        assert!(d.p50_ns.abs_diff(501_000) <= 501, "p50 {}", d.p50_ns);
        assert!(Dist::from_ns(&[]).is_err());
    }

    #[test]
    fn json_lines_have_the_documented_keys() {
        let d = Dist::from_ns(&[10_000, 20_000, 30_000]).unwrap();
        let p = RoundPoint {
            agents: 8,
            fsync: FsyncPolicy::None,
            replicas: 3,
            observers: Observers {
                ros2: true,
                foxglove: true,
            },
            per_process: 16,
            dist: d,
            first: d,
            stalled: 0,
        };
        let v: serde_json::Value = serde_json::from_str(&p.json()).unwrap();
        assert_eq!(v["bench"], "round");
        assert_eq!(v["agents"], 8);
        assert_eq!(v["agents_per_process"], 16);
        assert_eq!(v["fsync"], "none");
        assert_eq!(v["replicas"], 3);
        assert_eq!(v["observers"], "ros2+foxglove");
        assert_eq!(v["rounds"], 3);
        assert_eq!(v["max_us"], 30.0);
        for k in ["p50_us", "p99_us", "first_p50_us", "first_p99_us"] {
            assert!(v[k].is_f64(), "{k}");
        }
    }
}
