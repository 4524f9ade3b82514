//! The experiment's markdown tables (ours beside the dissertation's) and its JSON document,
//! which keeps the machine-independent figures apart from the wall times.

use std::fmt::Write as _;

use serde_json::{json, Value};

use super::measure::{
    Timing, ASTAR, HNAV_LINEAR_FULL, HNAV_LINEAR_PARTIAL, HNAV_TANH_FULL, HNAV_TANH_PARTIAL,
    VARIANTS,
};
use super::movingai::ScenResult;
use super::tasks::{TABLE_3_8, TABLE_3_9};
use super::{Size, TaskResult};

/// The whole report: Table 3-8, Table 3-9, the MovingAI sample and the notes.
pub fn markdown(tasks: &[TaskResult], scen: &[ScenResult], size: Size) -> String {
    let mut s = String::new();
    table_3_8(&mut s, tasks, size);
    table_3_9(&mut s, tasks);
    movingai(&mut s, scen, size);
    s
}

fn cell(t: &Timing, steps: usize) -> String {
    format!(
        "{:.1} [{:.1}-{:.1}] ({steps})",
        t.median_us, t.p25_us, t.p75_us
    )
}

fn table_3_8(s: &mut String, tasks: &[TaskResult], size: Size) {
    let _ = writeln!(s, "## Table 3-8: HNAV against A* on the four 20x20 tasks\n");
    let _ = writeln!(
        s,
        "Dissertation: Python, Xeon X5660, ms. Ours: Rust, this machine, us: median \
         [quartiles] of {} interleaved repetitions of one whole call with a fresh planner. \
         Steps in parentheses. HNAV = linear activation, partial activation (the modified \
         network the table ran); A* = the coordinator's octile A*; corners never cut. \
         Compare the HNAV/A* ratios, not the absolute times.\n",
        size.task_repetitions
    );
    let _ = writeln!(
        s,
        "| task | map | paper A* ms (steps) | paper HNAV ms (steps) | paper HNAV/A* | ours A* us (steps) | ours HNAV us (steps) | ours HNAV/A* | steps as paper |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
    let (mut paper_sum, mut ours_sum) = ((0.0, 0.0), (0.0, 0.0));
    for r in tasks {
        let p = &r.task.paper;
        let (a, h) = (
            &r.measured.timings[ASTAR],
            &r.measured.timings[HNAV_LINEAR_PARTIAL],
        );
        let (fa, fh) = (
            &r.measured.figures[ASTAR],
            &r.measured.figures[HNAV_LINEAR_PARTIAL],
        );
        paper_sum = (paper_sum.0 + p.astar_ms, paper_sum.1 + p.hnav_ms);
        ours_sum = (ours_sum.0 + a.median_us, ours_sum.1 + h.median_us);
        let same = match (fa.steps == p.astar_steps, fh.steps == p.hnav_steps) {
            (true, true) => "both".to_string(),
            (true, false) => format!("A* only (HNAV {} vs {})", fh.steps, p.hnav_steps),
            (false, true) => format!("HNAV only (A* {} vs {})", fa.steps, p.astar_steps),
            (false, false) => "neither".to_string(),
        };
        let _ = writeln!(
            s,
            "| {} {} | `{}` | {:.2} ({}) | {:.2} ({}) | {:.3} | {} | {} | {:.3} | {same} |",
            r.task.number,
            p.task,
            r.task.map_name,
            p.astar_ms,
            p.astar_steps,
            p.hnav_ms,
            p.hnav_steps,
            p.hnav_ms / p.astar_ms,
            cell(a, fa.steps),
            cell(h, fh.steps),
            h.median_us / a.median_us,
        );
    }
    let _ = writeln!(
        s,
        "| all | | {:.2} | {:.2} | {:.3} | {:.1} | {:.1} | {:.3} | |\n",
        paper_sum.0,
        paper_sum.1,
        paper_sum.1 / paper_sum.0,
        ours_sum.0,
        ours_sum.1,
        ours_sum.1 / ours_sum.0
    );
}

fn table_3_9(s: &mut String, tasks: &[TaskResult]) {
    let _ = writeln!(
        s,
        "## Table 3-9: activation function and stop rule, on the same tasks\n"
    );
    let _ = writeln!(s, "Dissertation's claims:");
    for (what, claim) in TABLE_3_9 {
        let _ = writeln!(s, "- {what}: {claim}");
    }
    let _ = writeln!(
        s,
        "\nSweeps (cycles) and steps per variant; time ratios of medians. A ratio above 1 is \
         the dissertation's direction.\n"
    );
    let _ = writeln!(
        s,
        "| task | sweeps lin-part / lin-full / tanh-part / tanh-full | steps, same order | full/partial sweeps (linear) | full/partial time (linear) | tanh/linear time (partial) | tanh/linear time per sweep (full) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    let order = [
        HNAV_LINEAR_PARTIAL,
        HNAV_LINEAR_FULL,
        HNAV_TANH_PARTIAL,
        HNAV_TANH_FULL,
    ];
    for r in tasks {
        let f = &r.measured.figures;
        let t = |i: usize| r.measured.timings[i].median_us;
        let per_sweep = |i: usize| t(i) / f[i].iterations.max(1) as f64;
        let join = |g: &dyn Fn(usize) -> String| {
            order.iter().map(|&i| g(i)).collect::<Vec<_>>().join(" / ")
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} |",
            r.task.number,
            join(&|i| f[i].iterations.to_string()),
            join(&|i| f[i].steps.to_string()),
            f[HNAV_LINEAR_FULL].iterations as f64 / f[HNAV_LINEAR_PARTIAL].iterations as f64,
            t(HNAV_LINEAR_FULL) / t(HNAV_LINEAR_PARTIAL),
            t(HNAV_TANH_PARTIAL) / t(HNAV_LINEAR_PARTIAL),
            per_sweep(HNAV_TANH_FULL) / per_sweep(HNAV_LINEAR_FULL),
        );
    }
    let _ = writeln!(s, "| paper | | | 1.3-3 | 1.3-3 | up to 2.5 | 1.5-2.5 |\n");
}

fn movingai(s: &mut String, scen: &[ScenResult], size: Size) {
    let _ = writeln!(s, "## The same planners on MovingAI scenario files\n");
    let _ = writeln!(
        s,
        "{} entries sampled per file with the seed; the `.scen` optimal length is the oracle. \
         Times: median over the entries of each entry's median of {} repetitions; the ratio \
         is the median over the entries of (planner / A*).\n",
        size.entries_per_file, size.entry_repetitions
    );
    let _ = writeln!(
        s,
        "| scen | planner | entries | found | optimal | length/optimal mean | p95 | max | mean sweeps or expansions | median us | time / A* |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|");
    for r in scen {
        for (k, v) in VARIANTS.iter().enumerate() {
            let m = &r.summaries[k];
            let _ = writeln!(
                s,
                "| `{}` | {} | {} | {} | {} | {:.4} | {:.4} | {:.4} | {:.1} | {:.1} | {:.3} |",
                r.scen,
                v.name(),
                m.queries,
                m.found,
                m.optimal,
                m.mean_ratio,
                m.p95_ratio,
                m.max_ratio,
                r.mean_iterations[k],
                r.median_time_us(k),
                r.median_ratio_to_astar(k),
            );
        }
    }
    let _ = writeln!(
        s,
        "\nTable 3-9's ratios on these samples (mean sweeps; median times over the entries):\n"
    );
    let _ = writeln!(
        s,
        "| scen | full/partial sweeps (linear) | full/partial time (linear) | tanh/linear time (partial) | tanh/linear time (full) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    for r in scen {
        let (it, t) = (&r.mean_iterations, |k: usize| r.median_time_us(k));
        let _ = writeln!(
            s,
            "| `{}` | {:.2} | {:.2} | {:.2} | {:.2} |",
            r.scen,
            it[HNAV_LINEAR_FULL] / it[HNAV_LINEAR_PARTIAL],
            t(HNAV_LINEAR_FULL) / t(HNAV_LINEAR_PARTIAL),
            t(HNAV_TANH_PARTIAL) / t(HNAV_LINEAR_PARTIAL),
            t(HNAV_TANH_FULL) / t(HNAV_LINEAR_FULL),
        );
    }
    let _ = writeln!(s, "| paper | 1.3-3 | 1.3-3 | up to 2.5 | up to 2.5 |\n");
}

/// The JSON document: `figures` (deterministic for a seed) and `timings` (this run's).
pub fn json(tasks: &[TaskResult], scen: &[ScenResult], size: Size) -> Value {
    let task_figures: Vec<Value> = tasks
        .iter()
        .map(|r| {
            let e = &r.task.entry;
            json!({
                "task": r.task.number,
                "map": r.task.map_name,
                "start": e.start,
                "goal": e.goal,
                "optimal": e.optimal_length,
                "paper": r.task.paper,
                "planners": r.measured.figures,
            })
        })
        .collect();
    let task_timings: Vec<Value> = tasks
        .iter()
        .map(|r| json!({"task": r.task.number, "planners": r.measured.timings}))
        .collect();
    let scen_figures: Vec<Value> = scen.iter().map(scen_figures).collect();
    let scen_timings: Vec<Value> = scen
        .iter()
        .map(|r| {
            let per = |f: &dyn Fn(usize) -> f64| (0..VARIANTS.len()).map(f).collect::<Vec<_>>();
            json!({
                "scen": r.scen,
                "median_us": per(&|k| r.median_time_us(k)),
                "ratio_to_astar": per(&|k| r.median_ratio_to_astar(k)),
                "entries": r.timings,
            })
        })
        .collect();
    json!({
        "planners": VARIANTS.iter().map(|v| v.name()).collect::<Vec<_>>(),
        "size": {
            "task_repetitions": size.task_repetitions,
            "entries_per_file": size.entries_per_file,
            "entry_repetitions": size.entry_repetitions,
        },
        "paper_table_3_8": TABLE_3_8,
        "figures": {"tasks": task_figures, "movingai": scen_figures},
        "timings": {"tasks": task_timings, "movingai": scen_timings},
    })
}

fn scen_figures(r: &ScenResult) -> Value {
    let summaries: Vec<Value> = VARIANTS
        .iter()
        .enumerate()
        .map(|(k, v)| {
            let m = &r.summaries[k];
            json!({
                "planner": v.name(),
                "queries": m.queries,
                "found": m.found,
                "optimal": m.optimal,
                "mean_ratio": m.mean_ratio,
                "p95_ratio": m.p95_ratio,
                "max_ratio": m.max_ratio,
                "mean_iterations": r.mean_iterations[k],
            })
        })
        .collect();
    json!({"scen": r.scen, "entries": r.entries, "summaries": summaries})
}
