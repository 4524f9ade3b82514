//! The lines of `hnav-bench plan` and the summary of a scenario run. With `--json` a query's
//! line is its [`PlanResult`] as is; without, [`render`] prints it as a table row.

use hnav_runtime::plan::PlanResult;
use serde::Serialize;

/// Lengths within this of the scenario's optimal length count as optimal (the `.scen` files
/// print 8 decimals).
pub const OPTIMAL_TOLERANCE: f64 = 1e-6;

/// A query's answer as one human-readable line.
pub fn render(r: &PlanResult) -> String {
    let optimal = r
        .optimal
        .map(|o| format!("  optimal {o:.4}"))
        .unwrap_or_default();
    format!(
        "{:<10} found {:<5} steps {:>5}  length {:>10.4}{optimal}  iterations {:>7}  {:>10.1} us",
        r.planner, r.found, r.steps, r.length, r.iterations, r.time_us
    )
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
    /// Found paths whose length equals the optimal length within `OPTIMAL_TOLERANCE`.
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
    pub fn add(&mut self, line: &PlanResult) {
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
    use hnav_runtime::grid::Cell;

    fn line(length: f64, optimal: f64, found: bool) -> PlanResult {
        PlanResult {
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

    #[test]
    fn json_line_keeps_its_field_order() {
        let mut l = line(2.5, 2.0, true);
        l.los_checks = Some(7);
        assert_eq!(
            serde_json::to_string(&l).unwrap(),
            r#"{"planner":"hnav","found":true,"steps":3,"length":2.5,"iterations":5,"path":[[0,0],[1,1]],"time_us":2.0,"los_checks":7,"optimal":2.0}"#
        );
    }
}
