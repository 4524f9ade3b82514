//! The JSON lines of `hnav-bench plan` and the summary of a scenario run.

use hnav_agent::plan::PlanResult;
use hnav_coordinator::planner::QueryResult;
use hnav_runtime::grid::Cell;
use serde::Serialize;

/// Lengths within this of the scenario's optimal length count as optimal (the `.scen` files
/// print 8 decimals).
pub const OPTIMAL_TOLERANCE: f64 = 1e-6;

/// One answered query, as printed with `--json`.
#[derive(Debug, Clone, Serialize)]
pub struct QueryLine {
    /// The planner's name.
    pub planner: String,
    /// Whether a path to the goal was found.
    pub found: bool,
    /// Moves in the path.
    pub steps: usize,
    /// Path length (straight 1, diagonal √2; any-angle planners: Euclidean).
    pub length: f64,
    /// The planner's iterations: neural-map sweeps, or node expansions.
    pub iterations: u64,
    /// The path's cells (waypoints for any-angle planners) as `[x, y]`.
    pub path: Vec<Cell>,
    /// Wall time of the query, µs.
    pub time_us: f64,
    /// Line-of-sight checks (any-angle planners only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub los_checks: Option<u64>,
    /// The scenario's optimal length (scenario runs only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub optimal: Option<f64>,
}

impl QueryLine {
    /// From the neural map's answer.
    pub fn from_hnav(r: PlanResult) -> Self {
        Self {
            planner: "hnav".into(),
            found: r.found,
            steps: r.steps,
            length: r.length,
            iterations: u64::from(r.iterations),
            path: r.path,
            time_us: r.time_us,
            los_checks: None,
            optimal: None,
        }
    }

    /// From a global planner's answer.
    pub fn from_global(r: QueryResult) -> Self {
        Self {
            los_checks: (r.los_checks > 0).then_some(r.los_checks),
            planner: r.planner,
            found: r.found,
            steps: r.steps,
            length: r.length,
            iterations: r.iterations,
            path: r.path,
            time_us: r.time_us,
            optimal: None,
        }
    }

    /// A one-line human rendering.
    pub fn render(&self) -> String {
        let optimal = self
            .optimal
            .map(|o| format!("  optimal {o:.4}"))
            .unwrap_or_default();
        format!(
            "{:<10} found {:<5} steps {:>5}  length {:>10.4}{optimal}  iterations {:>7}  {:>10.1} us",
            self.planner, self.found, self.steps, self.length, self.iterations, self.time_us
        )
    }
}

/// Totals over a scenario file.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Always true: tells the summary line from the query lines.
    pub summary: bool,
    /// The planner's name.
    pub planner: &'static str,
    /// Queries answered.
    pub queries: usize,
    /// Queries where a path was found.
    pub found: usize,
    /// Found paths whose length equals the optimal length within [`OPTIMAL_TOLERANCE`].
    pub optimal: usize,
    /// Mean of length / optimal over found paths with a positive optimal length.
    pub mean_ratio: f64,
    /// 95th percentile of that ratio.
    pub p95_ratio: f64,
    /// Largest ratio.
    pub max_ratio: f64,
    /// Sum of the queries' wall times, µs.
    pub total_time_us: f64,
    #[serde(skip)]
    ratios: Vec<f64>,
}

impl Summary {
    /// An empty summary.
    pub fn new(planner: &'static str) -> Self {
        Self {
            summary: true,
            planner,
            queries: 0,
            found: 0,
            optimal: 0,
            mean_ratio: 0.0,
            p95_ratio: 0.0,
            max_ratio: 0.0,
            total_time_us: 0.0,
            ratios: Vec::new(),
        }
    }

    /// Counts one answered query.
    pub fn add(&mut self, line: &QueryLine) {
        self.queries += 1;
        self.total_time_us += line.time_us;
        if !line.found {
            return;
        }
        self.found += 1;
        if let Some(opt) = line.optimal {
            if (line.length - opt).abs() <= OPTIMAL_TOLERANCE {
                self.optimal += 1;
            }
            if opt > 0.0 {
                self.ratios.push(line.length / opt);
                self.ratios.sort_by(f64::total_cmp);
                let n = self.ratios.len();
                self.mean_ratio = self.ratios.iter().sum::<f64>() / n as f64;
                self.p95_ratio = self.ratios[((n as f64 * 0.95).ceil() as usize).clamp(1, n) - 1];
                self.max_ratio = self.ratios[n - 1];
            }
        }
    }

    /// A one-line human rendering.
    pub fn render(&self) -> String {
        format!(
            "{}: {} queries, {} found, {} optimal; length/optimal mean {:.4}, p95 {:.4}, max {:.4}; {:.1} ms in all",
            self.planner,
            self.queries,
            self.found,
            self.optimal,
            self.mean_ratio,
            self.p95_ratio,
            self.max_ratio,
            self.total_time_us / 1e3
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(length: f64, optimal: f64, found: bool) -> QueryLine {
        QueryLine {
            planner: "hnav".into(),
            found,
            los_checks: None,
            steps: 3,
            length,
            iterations: 5,
            path: vec![Cell::new(0, 0), Cell::new(1, 1)],
            time_us: 2.0,
            optimal: Some(optimal),
        }
    }

    #[test]
    fn summary_counts_optimal_and_ratios() {
        let mut s = Summary::new("hnav");
        s.add(&line(2.0, 2.0, true));
        s.add(&line(3.0, 2.0, true));
        s.add(&line(0.0, 2.0, false));
        assert_eq!((s.queries, s.found, s.optimal), (3, 2, 1));
        assert!((s.mean_ratio - 1.25).abs() < 1e-12);
        assert!((s.max_ratio - 1.5).abs() < 1e-12);
        assert!((s.total_time_us - 6.0).abs() < 1e-12);
    }

    #[test]
    fn json_line_has_the_issue_fields() {
        let v = serde_json::to_value(line(2.0, 2.0, true)).unwrap();
        for key in [
            "planner",
            "found",
            "steps",
            "length",
            "iterations",
            "path",
            "time_us",
            "optimal",
        ] {
            assert!(v.get(key).is_some(), "missing {key}");
        }
        assert_eq!(v["path"][1], serde_json::json!([1, 1]));
        let mut single = line(2.0, 2.0, true);
        single.optimal = None;
        assert!(serde_json::to_value(single)
            .unwrap()
            .get("optimal")
            .is_none());
    }
}
