//! The `pso` experiment's ablation: why the modified algorithm takes more steps than the
//! original on the same tasks, against the paper's direction.
//!
//! The modified algorithm differs from the original (r_max = 1) in three ways, and each
//! variant reverts one of them to the original's, at n_lm 5, 7, 10 on the experiment's tasks:
//!
//! | variant | what is switched off | options |
//! |---|---|---|
//! | `no-virtual-obstacles` | (a) the virtual obstacles: the detector runs and counts, nothing is placed | `Escape::DetectOnly` |
//! | `fixed-weights` | (b) the adaptive tanh weights: velocity (2) with k = 0.5 and r2 = 1 - r1 | `WeightLaw::Fixed` |
//! | `original-blocked-move` | (c) the modified blocked move: noise (20) at r_max = 1 and the cell x + v + r instead of an equiprobable r and x + r | `Variant::Original`, `Alternative::Sum` |
//!
//! (c) stands in for "no integer noise on blocked moves": per the notes (§2.3, §4.2) both
//! algorithms add integer noise on blocked moves, so the noise itself is not a modification;
//! its distribution and the cell it is added to are. Each variant is pooled over its three
//! settings and compared with the original pooled over r_max 1, 2, 4, per task, as the paired
//! table's pooled row: success (Wilson), and steps on the tasks both solve (bootstrap).
//!
//! Three step counts are reported, each labelled: iterations on successes (the tables', the
//! notes' reading of the paper), iterations over all runs with a run that never reaches the
//! goal counted at k_max (the paper does not say whether failures are left out), and the
//! length of the route through the trace (what a robot would drive; not the paper's count).

use std::fmt::Write as _;

use serde::Serialize;

use super::pso_paired::{per_task_mean, pooled_per_task, pooled_stream};
use super::pso_tasks::{Row, TaskRun, MODIFIED, MODIFIED_CORNERS, PAPER_TABLE_1, PAPER_TABLE_2};
use super::stats::{mean, paired, wilson, Interval, Paired, Z95};

const RESAMPLES: usize = 2000;
/// k_max of both tables: the count of a run that never reaches the goal under the all-runs
/// reading.
const K_MAX: f64 = 1200.0;

/// The ablation's rows: (rows' algorithm, what is switched off, corner rule), the original
/// first as the reference.
const VARIANTS: [(&str, &str, Option<&str>); 8] = [
    ("original", "(original, r_max 1/2/4)", None),
    (
        MODIFIED_CORNERS,
        "(d) nothing: full modified",
        Some("sides"),
    ),
    (MODIFIED, "(d) nothing: full modified", Some("always")),
    ("no-virtual-obstacles", "(a) virtual obstacles", None),
    (
        "fixed-weights-corners",
        "(b) adaptive weights",
        Some("sides"),
    ),
    ("fixed-weights", "(b) adaptive weights", Some("always")),
    (
        "original-blocked-move-corners",
        "(c) modified blocked move",
        Some("sides"),
    ),
    (
        "original-blocked-move",
        "(c) modified blocked move",
        Some("always"),
    ),
];

/// The paper's share of runs that never reached the goal (local minima), per setting, in the
/// order of Tables 1 and 2: Table 1's failure breakdown (notes §4.2); Table 2 gives none and
/// names only traps, so all its failures are taken as not reached.
const PAPER_NOT_REACHED: [f64; 6] = [0.10, 0.10, 0.04, 0.06, 0.02, 0.04];

/// One ablation row: a variant pooled over its settings, against the original.
#[derive(Clone, Debug, Serialize)]
pub struct AblationRow {
    /// The rows' `algorithm` it pools.
    pub algorithm: &'static str,
    /// The modification switched off.
    pub switched_off: &'static str,
    /// `"sides"` (the notes' corner analysis), `"always"` (an obstacle at every detection),
    /// `None` where no obstacle is placed.
    pub corner_rule: Option<&'static str>,
    /// Runs (all settings).
    pub runs: u64,
    /// Successes.
    pub successes: u64,
    /// Wilson 95 % interval of the success rate.
    pub success_ci: Interval,
    /// Mean local-minimum detections per run.
    pub detections_per_run: f64,
    /// Mean virtual obstacles per run.
    pub obstacles_per_run: f64,
    /// Iterations on the tasks both solve, original (`a`) against this variant (`b`); `None`
    /// for the original itself.
    pub steps: Option<Paired>,
    /// Iterations on the tasks both solve, against the original at r_max = 1 only (the
    /// modified algorithm's own noise amplitude).
    pub vs_r_max_1: Option<Paired>,
    /// Iterations on the tasks every run of every setting of the experiment solves (the same
    /// tasks for every variant, and no run left out of a task's mean).
    pub common: Option<Paired>,
    /// Iterations over all runs, a run that never reaches the goal counted at k_max, on all
    /// tasks.
    pub all_runs: Option<Paired>,
    /// Octile length of the route through the trace, on the tasks both solve.
    pub route: Option<Paired>,
}

/// The tasks split by which algorithm solves them (in at least one of its settings).
#[derive(Clone, Debug, Serialize)]
pub struct Split {
    /// The modified algorithm's rows: `"modified"` or `"modified-corners"`.
    pub modified: &'static str,
    /// `"both solve"`, `"original only"`, `"modified only"`, `"neither"`.
    pub group: &'static str,
    /// Tasks in the group.
    pub tasks: u64,
    /// Mean of the original's per-task iterations on the group's tasks it solves.
    pub original_steps: Option<f64>,
    /// The same for the modified algorithm.
    pub modified_steps: Option<f64>,
    /// Mean shortest-path length (octile, cells) of the group's tasks.
    pub shortest: Option<f64>,
    /// Mean detections per run of the original on the group's tasks (its swarm stalling).
    pub original_detections: Option<f64>,
}

/// The paired steps on the tasks both solve, split by whether the variant's swarm stalled
/// (a local-minimum detection) in any of its successful runs of the task.
#[derive(Clone, Debug, Serialize)]
pub struct StallSplit {
    /// The variant's rows: `"modified-corners"`, `"modified"` or `"no-virtual-obstacles"`.
    pub variant: &'static str,
    /// Whether the variant's swarm stalled on the group's tasks.
    pub stalled: bool,
    /// Iterations, original (`a`) against the variant (`b`).
    pub steps: Paired,
}

/// One setting's steps under both counts, beside what the paper's figure implies.
#[derive(Clone, Debug, Serialize)]
pub struct Counting {
    /// The rows' `algorithm`.
    pub algorithm: &'static str,
    /// r_max or n_lm.
    pub parameter: u32,
    /// The paper's mean steps.
    pub paper_steps: f64,
    /// The paper's share of runs that never reached the goal.
    pub paper_not_reached: f64,
    /// The paper's mean over the runs that reached the goal, if its figure averaged all runs
    /// with a run that never reached counted at k_max: `(steps - m k_max) / (1 - m)`.
    pub paper_implied_reached: f64,
    /// Ours: mean iterations over successes (the tables' count).
    pub successes_mean: Option<f64>,
    /// Ours: mean iterations over the runs that reached the goal (successes and gaps).
    pub reached_mean: Option<f64>,
    /// Ours: mean iterations over all runs, not reached counted at k_max.
    pub all_runs_mean: Option<f64>,
    /// Bootstrap 95 % interval of `all_runs_mean`.
    pub all_runs_ci: Option<Interval>,
}

/// Everything the ablation reports.
#[derive(Clone, Debug, Serialize)]
pub struct Ablation {
    /// The variants against the original.
    pub rows: Vec<AblationRow>,
    /// The tasks by which algorithm solves them, per corner rule.
    pub splits: Vec<Split>,
    /// The paired steps by whether the variant's swarm stalled, for the full modified
    /// algorithm (both corner rules) and the one without virtual obstacles.
    pub stall_splits: Vec<StallSplit>,
    /// Per setting of Tables 1 and 2 (both corner rules): the step counts.
    pub counting: Vec<Counting>,
}

fn of<'a>(rows: &[&'a Row], algorithm: &str) -> Vec<&'a Row> {
    rows.iter()
        .copied()
        .filter(|r| r.algorithm == algorithm)
        .collect()
}

fn iterations(d: &TaskRun) -> Option<f64> {
    Some(f64::from(d.iterations))
}

fn route(d: &TaskRun) -> Option<f64> {
    d.route_len
}

/// Mean of `f` over every run of `rows`.
fn per_run(rows: &[&Row], f: impl Fn(&TaskRun) -> u32) -> f64 {
    let all: Vec<f64> = rows
        .iter()
        .flat_map(|r| r.detail.iter().map(|d| f64::from(f(d))))
        .collect();
    mean(&all).unwrap_or(0.0)
}

/// `values` with the tasks outside `keep` removed.
fn masked(values: &[Option<f64>], keep: impl Fn(usize) -> bool) -> Vec<Option<f64>> {
    values
        .iter()
        .enumerate()
        .map(|(i, v)| v.filter(|_| keep(i)))
        .collect()
}

/// The ablation over `rows` (every setting of the experiment, all on the same tasks), with
/// `shortest` the tasks' shortest-path lengths.
pub fn analyse(rows: &[&Row], shortest: &[Option<f64>], seed: u64) -> Ablation {
    let original = of(rows, "original");
    let o_steps = pooled_per_task(&original);
    let o_all = per_task_mean(&original, iterations);
    let o_route = per_task_mean(&original, route);
    let solved_by_all: Vec<bool> = (0..o_steps.len())
        .map(|i| rows.iter().all(|r| r.detail[i].success))
        .collect();
    let common = |xs: Vec<Option<f64>>| masked(&xs, |i| solved_by_all[i]);
    let mut out = Ablation {
        rows: Vec::new(),
        splits: Vec::new(),
        stall_splits: Vec::new(),
        counting: Vec::new(),
    };
    for (k, (algorithm, switched_off, corner_rule)) in VARIANTS.into_iter().enumerate() {
        let v = of(rows, algorithm);
        let successes: u64 = v.iter().map(|r| r.successes).sum();
        let runs: u64 = v.iter().map(|r| r.runs).sum();
        let stream = |c: u64| seed ^ (0xab_0000 | (c << 8) | k as u64);
        let compare = algorithm != "original";
        out.rows.push(AblationRow {
            algorithm,
            switched_off,
            corner_rule,
            runs,
            successes,
            success_ci: wilson(successes, runs, Z95).unwrap_or(Interval { lo: 0.0, hi: 1.0 }),
            detections_per_run: per_run(&v, |d| d.detections),
            obstacles_per_run: per_run(&v, |d| d.obstacles),
            // The full modified algorithm's rows are the paired table's pooled rows, stream
            // included.
            steps: compare.then(|| {
                let full = [MODIFIED_CORNERS, MODIFIED].contains(&algorithm);
                let stream = if full {
                    pooled_stream(seed, algorithm)
                } else {
                    stream(1)
                };
                paired(&o_steps, &pooled_per_task(&v), RESAMPLES, stream)
            }),
            vs_r_max_1: compare.then(|| {
                paired(
                    &pooled_per_task(&original[..1]),
                    &pooled_per_task(&v),
                    RESAMPLES,
                    stream(5),
                )
            }),
            common: compare.then(|| {
                paired(
                    &common(o_steps.clone()),
                    &common(pooled_per_task(&v)),
                    RESAMPLES,
                    stream(4),
                )
            }),
            all_runs: compare.then(|| {
                let full = [MODIFIED_CORNERS, MODIFIED].contains(&algorithm);
                let stream = if full {
                    pooled_stream(seed, algorithm) ^ 0xad
                } else {
                    stream(2)
                };
                paired(&o_all, &per_task_mean(&v, iterations), RESAMPLES, stream)
            }),
            route: compare
                .then(|| paired(&o_route, &per_task_mean(&v, route), RESAMPLES, stream(3))),
        });
    }
    let o_detections = per_task_mean(&original, |d| Some(f64::from(d.detections)));
    for modified in [MODIFIED_CORNERS, MODIFIED] {
        let m = of(rows, modified);
        let m_steps = pooled_per_task(&m);
        // (group, (the original solves, the modified solves)).
        let groups = [
            ("both solve", (true, true)),
            ("original only", (true, false)),
            ("modified only", (false, true)),
            ("neither", (false, false)),
        ];
        for (group, solves) in groups {
            let keep = |i: usize| (o_steps[i].is_some(), m_steps[i].is_some()) == solves;
            let avg = |xs: &[Option<f64>]| {
                mean(&masked(xs, keep).into_iter().flatten().collect::<Vec<_>>())
            };
            out.splits.push(Split {
                modified,
                group,
                tasks: (0..o_steps.len()).filter(|&i| keep(i)).count() as u64,
                original_steps: avg(&o_steps),
                modified_steps: avg(&m_steps),
                shortest: avg(shortest),
                original_detections: avg(&o_detections),
            });
        }
    }
    for (k, variant) in [MODIFIED_CORNERS, MODIFIED, "no-virtual-obstacles"]
        .into_iter()
        .enumerate()
    {
        let v = of(rows, variant);
        let v_steps = pooled_per_task(&v);
        // Detections in the variant's successful runs of each task.
        let stalls = per_task_mean(&v, |d| d.success.then_some(f64::from(d.detections)));
        for stalled in [false, true] {
            let keep = |i: usize| stalls[i].is_some_and(|p| (p > 0.0) == stalled);
            out.stall_splits.push(StallSplit {
                variant,
                stalled,
                steps: paired(
                    &masked(&o_steps, keep),
                    &masked(&v_steps, keep),
                    RESAMPLES,
                    seed ^ (0xac_0000 | (k * 10 + usize::from(stalled)) as u64),
                ),
            });
        }
    }
    let paper = PAPER_TABLE_1
        .map(|(r, s, _)| (r as u32, s))
        .into_iter()
        .chain(PAPER_TABLE_2.map(|(n, s, _)| (n, s)))
        .zip(PAPER_NOT_REACHED);
    let paper: Vec<((u32, f64), f64)> = paper.collect();
    for r in rows
        .iter()
        .filter(|r| ["original", MODIFIED_CORNERS, MODIFIED].contains(&r.algorithm))
    {
        let table = usize::from(r.algorithm != "original");
        let ((_, paper_steps), m) = paper
            .iter()
            .skip(3 * table)
            .take(3)
            .find(|((p, _), _)| *p == r.parameter)
            .copied()
            .unwrap_or(((r.parameter, f64::NAN), f64::NAN));
        let reached: Vec<f64> = r
            .detail
            .iter()
            .filter(|d| d.reached)
            .map(|d| f64::from(d.iterations))
            .collect();
        out.counting.push(Counting {
            algorithm: r.algorithm,
            parameter: r.parameter,
            paper_steps,
            paper_not_reached: m,
            paper_implied_reached: (paper_steps - m * K_MAX) / (1.0 - m),
            successes_mean: r.mean_steps,
            reached_mean: mean(&reached),
            all_runs_mean: r.all_runs_steps,
            all_runs_ci: r.all_runs_ci,
        });
    }
    out
}

fn num(x: Option<f64>) -> String {
    x.map_or("—".into(), |x| format!("{x:.1}"))
}

fn diff(p: &Option<Paired>) -> String {
    match p {
        Some(Paired {
            n,
            mean_a: Some(a),
            mean_b: Some(b),
            mean_diff: Some(d),
            diff_ci: Some(ci),
            ..
        }) => format!(
            "{a:.1} -> {b:.1}, {d:+.1} [{:+.1}, {:+.1}] (n {n})",
            ci.lo, ci.hi
        ),
        _ => "—".into(),
    }
}

fn median_and_signs(p: &Option<Paired>) -> String {
    match p {
        Some(Paired {
            median_diff: Some(m),
            b_lower,
            b_higher,
            ..
        }) => format!("{m:+.1} | {b_lower} / {b_higher}"),
        _ => "— | —".into(),
    }
}

/// Mean of the per-setting means of `algorithm` under `f` (how the paper pools).
fn mean_of_means(c: &[Counting], algorithm: &str, f: impl Fn(&Counting) -> Option<f64>) -> String {
    let xs: Vec<f64> = c
        .iter()
        .filter(|r| r.algorithm == algorithm)
        .filter_map(f)
        .collect();
    num(mean(&xs))
}

/// The ablation's tables, in markdown.
pub fn render(a: &Ablation) -> String {
    let mut s = String::new();
    let n = a.rows.first().map_or(0, |r| r.runs);
    let _ = writeln!(s, "\nAblation: the modified algorithm with one modification switched off, pooled over n_lm 5/7/10 ({n} runs a variant), against the original pooled over r_max 1/2/4 on the same tasks. Steps are iterations on the tasks both solve (per task, the mean over the settings that solve it): original -> variant, mean difference [95 %], the median difference, and the tasks where the variant is faster / slower.\n");
    let _ = writeln!(s, "| switched off | corner rule | success [95 %] | detections/run | virtual obstacles/run | iterations, tasks both solve | median difference | variant faster / slower |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    let label = |r: &AblationRow| format!("{} | {}", r.switched_off, r.corner_rule.unwrap_or("—"));
    for r in &a.rows {
        let _ = writeln!(
            s,
            "| {} | {:.1} % [{:.1}, {:.1}] | {:.1} | {:.1} | {} | {} |",
            label(r),
            100.0 * r.successes as f64 / r.runs.max(1) as f64,
            100.0 * r.success_ci.lo,
            100.0 * r.success_ci.hi,
            r.detections_per_run,
            r.obstacles_per_run,
            diff(&r.steps),
            median_and_signs(&r.steps)
        );
    }
    let _ = writeln!(s, "\nThe same variants, other comparisons and step counts (original -> variant, mean difference [95 %]). The last two are not the paper's count (iterations on successes), each labelled by what it counts.\n");
    let _ = writeln!(s, "| switched off | corner rule | against the original at r_max = 1 only, tasks both solve | tasks every run of every setting solves | iterations over all runs, not reached = 1200 | route length through the trace (cells), tasks both solve |");
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for r in a.rows.iter().filter(|r| r.steps.is_some()) {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} |",
            label(r),
            diff(&r.vs_r_max_1),
            diff(&r.common),
            diff(&r.all_runs),
            diff(&r.route)
        );
    }
    let _ = writeln!(s, "\nWhere the steps come from: tasks by which algorithm solves them (in at least one of its three settings); per-task iterations averaged over the solving settings.\n");
    let _ = writeln!(s, "| modified | tasks | n | original iterations | modified iterations | shortest path (cells) | original detections/run |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    for x in &a.splits {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} |",
            x.modified,
            x.group,
            x.tasks,
            num(x.original_steps),
            num(x.modified_steps),
            num(x.shortest),
            num(x.original_detections)
        );
    }
    let _ = writeln!(s, "\nPaired iterations on the tasks both solve, by whether the variant's swarm stalled (a local-minimum detection, n_lm 5/7/10) in its successful runs of the task.\n");
    let _ = writeln!(
        s,
        "| variant | stalled | iterations: original -> variant, mean difference [95 %] | median difference | variant faster / slower |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    for x in &a.stall_splits {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            x.variant,
            if x.stalled { "yes" } else { "no" },
            diff(&Some(x.steps)),
            median_and_signs(&Some(x.steps))
        );
    }
    let _ = writeln!(s, "\nHow steps are counted. The paper: \"average number of steps (iterations) to reach the goal\", not saying whether failed runs are left out. Implied: the paper's mean over the runs that reached the goal if its figure averaged all runs with a never-reached run at 1200, (steps - m 1200)/(1 - m), m its share of runs that never reached (Table 1's breakdown; Table 2's failures all taken as not reached). A different count from the notes' reading, labelled as such.\n");
    let _ = writeln!(s, "| algorithm | setting | paper steps | paper never reached | paper implied mean over reached runs | ours: successes | ours: reached runs | ours: all runs, not reached = 1200 [95 %] |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    for c in &a.counting {
        let _ = writeln!(
            s,
            "| {} | {} | {:.0} | {:.0} % | {:.1} | {} | {} | {} |",
            c.algorithm,
            c.parameter,
            c.paper_steps,
            100.0 * c.paper_not_reached,
            c.paper_implied_reached,
            num(c.successes_mean),
            num(c.reached_mean),
            match (c.all_runs_mean, c.all_runs_ci) {
                (Some(m), Some(ci)) => format!("{m:.1} [{:.1}, {:.1}]", ci.lo, ci.hi),
                _ => "—".into(),
            }
        );
    }
    for (algorithm, paper) in [
        ("original", "182.67"),
        (MODIFIED, "117.33"),
        (MODIFIED_CORNERS, "117.33"),
    ] {
        let _ = writeln!(
            s,
            "| {algorithm} | mean of the 3 | {paper} | | {} | {} | {} | {} |",
            mean_of_means(&a.counting, algorithm, |c| Some(c.paper_implied_reached)),
            mean_of_means(&a.counting, algorithm, |c| c.successes_mean),
            mean_of_means(&a.counting, algorithm, |c| c.reached_mean),
            mean_of_means(&a.counting, algorithm, |c| c.all_runs_mean),
        );
    }
    s
}
