//! The `pso` experiment's paired step comparison. The tables' mean steps are means over each
//! setting's own successes, and the original algorithm succeeds mostly on easy tasks, which
//! flatters it. Every setting runs on the same maps, starts and goals, so here the original
//! and the modified algorithm are compared on the tasks both solve: per pair of settings
//! (r_max against n_lm, both corner rules) and pooled (per task, the mean over the settings of
//! each algorithm that solve it, on the tasks at least one setting of each solves). Beside it,
//! the other count: every run on every task, a run that never reaches the goal counted at
//! 1200 iterations.

use std::fmt::Write as _;

use serde::Serialize;

use super::pso_tasks::{Row, TaskRun, MODIFIED, MODIFIED_CORNERS, PAPER_TABLE_1, PAPER_TABLE_2};
use super::stats::{mean, paired, Paired};

const RESAMPLES: usize = 2000;

/// One comparison: which settings, and the paired figures (`a` original, `b` modified).
#[derive(Clone, Debug, Serialize)]
pub struct PairRow {
    /// The modified algorithm's rows: `"modified"` (the default, a virtual obstacle at every
    /// detected minimum) or `"modified-corners"` (the notes' corner analysis).
    pub modified: &'static str,
    /// r_max of the original, `None` for the pooled row.
    pub r_max: Option<u32>,
    /// n_lm of the modified, `None` for the pooled row.
    pub n_lm: Option<u32>,
    /// Mean steps on the tasks both solve, and the mean difference modified - original.
    pub steps: Paired,
    /// Mean iterations over all runs on every task (never reached = 1200), and the
    /// difference.
    pub all_runs: Paired,
}

/// The bootstrap stream of the pooled comparison of `modified` (a corner rule's rows), so
/// that the ablation's rows for the full modified algorithm repeat this table's pooled rows.
pub fn pooled_stream(seed: u64, modified: &str) -> u64 {
    seed ^ (0x5f_0000 | u64::from(modified == MODIFIED))
}

/// Per task, the mean of `value` over the runs of `rows` (the settings of one algorithm) on
/// that task where it is `Some`; `None` where it is `None` for every setting.
pub fn per_task_mean(rows: &[&Row], value: impl Fn(&TaskRun) -> Option<f64>) -> Vec<Option<f64>> {
    let n = rows.first().map_or(0, |r| r.detail.len());
    (0..n)
        .map(|i| {
            let values: Vec<f64> = rows.iter().filter_map(|r| value(&r.detail[i])).collect();
            mean(&values)
        })
        .collect()
}

/// Per task, the mean iterations over the settings of `rows` that solve it.
pub fn pooled_per_task(rows: &[&Row]) -> Vec<Option<f64>> {
    per_task_mean(rows, |d| d.success.then_some(f64::from(d.iterations)))
}

/// The paired comparisons of `rows` (the experiment's rows, every setting on the same tasks):
/// for each corner rule the nine setting pairs, then the pooled one.
pub fn compare(rows: &[Row], seed: u64) -> Vec<PairRow> {
    let original: Vec<&Row> = rows.iter().filter(|r| r.algorithm == "original").collect();
    let mut out = Vec::new();
    for (k, rule) in [MODIFIED_CORNERS, MODIFIED].into_iter().enumerate() {
        let modified: Vec<&Row> = rows.iter().filter(|r| r.algorithm == rule).collect();
        for (i, o) in original.iter().enumerate() {
            for (j, m) in modified.iter().enumerate() {
                let stream = seed ^ (0x5e_0000 | (k * 100 + i * 10 + j) as u64);
                out.push(PairRow {
                    modified: rule,
                    r_max: Some(o.parameter),
                    n_lm: Some(m.parameter),
                    steps: paired(&o.per_task, &m.per_task, RESAMPLES, stream),
                    all_runs: paired(&all_runs(&[o]), &all_runs(&[m]), RESAMPLES, stream ^ 0xad),
                });
            }
        }
        out.push(PairRow {
            modified: rule,
            r_max: None,
            n_lm: None,
            steps: paired(
                &pooled_per_task(&original),
                &pooled_per_task(&modified),
                RESAMPLES,
                pooled_stream(seed, rule),
            ),
            all_runs: paired(
                &all_runs(&original),
                &all_runs(&modified),
                RESAMPLES,
                pooled_stream(seed, rule) ^ 0xad,
            ),
        });
    }
    // The default first; the streams above follow the computing order.
    out.sort_by_key(|p| p.modified != MODIFIED);
    out
}

/// Per task, the mean iterations over every run of `rows`, a run that never reaches counted at
/// k_max.
pub fn all_runs(rows: &[&Row]) -> Vec<Option<f64>> {
    per_task_mean(rows, |d| Some(f64::from(d.iterations)))
}

fn num(x: Option<f64>) -> String {
    x.map_or("—".into(), |x| format!("{x:.1}"))
}

fn paper_steps(r_max: Option<u32>, n_lm: Option<u32>) -> String {
    let o = PAPER_TABLE_1.iter().find(|r| Some(r.0 as u32) == r_max);
    let m = PAPER_TABLE_2.iter().find(|r| Some(r.0) == n_lm);
    match (o, m) {
        (Some(o), Some(m)) => format!("{:.0} -> {:.0} ({:+.0})", o.1, m.1, m.1 - o.1),
        _ => "182.67 -> 117.33 (-65.3)".to_string(),
    }
}

/// The paired table, in markdown.
pub fn render(pairs: &[PairRow]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "\nPaired steps: original against modified on the tasks both solve (same map, start and goal); the paper's figures are its unpaired table means.\n");
    let _ = writeln!(s, "| modified | r_max | n_lm | tasks both solve | original steps | modified steps | modified - original [95 %] | all runs, not reached = 1200: original -> modified, difference [95 %] | paper (unpaired) |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
    for p in pairs {
        let d = &p.steps;
        let diff = |d: &Paired| match (d.mean_diff, d.diff_ci) {
            (Some(m), Some(ci)) => format!("{m:+.1} [{:+.1}, {:+.1}]", ci.lo, ci.hi),
            _ => "—".into(),
        };
        let a = &p.all_runs;
        let setting = |x: Option<u32>| x.map_or("pooled".to_string(), |v| v.to_string());
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} -> {}, {} | {} |",
            p.modified,
            setting(p.r_max),
            setting(p.n_lm),
            d.n,
            num(d.mean_a),
            num(d.mean_b),
            diff(d),
            num(a.mean_a),
            num(a.mean_b),
            diff(a),
            paper_steps(p.r_max, p.n_lm)
        );
    }
    s
}
