//! Per setting (a MovingAI map, or the seed's own setting) and planner: the success rate with
//! its Wilson interval, the mean length over the optimal on the tasks every planner solves
//! (paired, so an easy task solved by one planner only does not flatter it) with a bootstrap
//! interval, the ticks to the goal, collisions with the moving obstacles, and the mean wall
//! time of a query.

use std::fmt::Write as _;

use serde::Serialize;

use super::own;
use super::planners::PLANNERS;
use super::{Size, Task};
use crate::experiment::stats::{bootstrap_mean, mean, wilson, Interval, Z95};

/// The name of the seed's own setting in the tables.
pub const OWN: &str = "seed 004 setting (moving robots)";

const RESAMPLES: usize = 2000;

/// One planner on one setting.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// The setting.
    pub setting: String,
    /// The planner.
    pub planner: &'static str,
    /// Tasks.
    pub tasks: u64,
    /// Tasks it returned a route on.
    pub found: u64,
    /// Wilson 95 % interval of the success rate.
    pub found_ci: Interval,
    /// Tasks every planner solved.
    pub paired: u64,
    /// Mean of length / optimal over the paired tasks.
    pub length_ratio: Option<f64>,
    /// Bootstrap 95 % interval of `length_ratio`.
    pub length_ratio_ci: Option<Interval>,
    /// Mean ticks to the goal (waits included) over the paired tasks.
    pub ticks: Option<f64>,
    /// Tasks solved without a collision with a moving obstacle.
    pub collision_free: u64,
    /// Wilson 95 % interval of the collision-free rate.
    pub collision_free_ci: Interval,
    /// Mean collisions per found route.
    pub mean_collisions: Option<f64>,
    /// Mean wall time of a query, µs (not the same on two runs; never compared).
    #[serde(skip)]
    pub mean_time_us: f64,
}

fn unit() -> Interval {
    Interval { lo: 0.0, hi: 1.0 }
}

/// Summarises every setting's tasks; the bootstrap streams derive from `seed`.
pub fn summarise(settings: &[(String, Vec<Task>)], seed: u64) -> Vec<Summary> {
    let mut out = Vec::with_capacity(settings.len() * PLANNERS.len());
    for (s, (setting, tasks)) in settings.iter().enumerate() {
        let paired: Vec<&Task> = tasks
            .iter()
            .filter(|t| t.answers.iter().all(|a| a.found))
            .collect();
        for (k, p) in PLANNERS.iter().enumerate() {
            let n = tasks.len() as u64;
            let found: Vec<_> = tasks
                .iter()
                .map(|t| t.answers[k])
                .filter(|a| a.found)
                .collect();
            let free = found.iter().filter(|a| a.conflicts == 0).count() as u64;
            let ratios: Vec<f64> = paired
                .iter()
                .map(|t| t.answers[k].length / t.optimal)
                .collect();
            let ticks: Vec<f64> = paired.iter().map(|t| t.answers[k].ticks as f64).collect();
            let collisions: Vec<f64> = found.iter().map(|a| a.conflicts as f64).collect();
            let times: Vec<f64> = tasks.iter().map(|t| t.answers[k].time_us).collect();
            let stream = seed ^ ((s as u64) << 8 | k as u64);
            out.push(Summary {
                setting: setting.clone(),
                planner: p.name(),
                tasks: n,
                found: found.len() as u64,
                found_ci: wilson(found.len() as u64, n, Z95).unwrap_or_else(unit),
                paired: paired.len() as u64,
                length_ratio: mean(&ratios),
                length_ratio_ci: bootstrap_mean(&ratios, RESAMPLES, 0.05, stream),
                ticks: mean(&ticks),
                collision_free: free,
                collision_free_ci: wilson(free, n, Z95).unwrap_or_else(unit),
                mean_collisions: mean(&collisions),
                mean_time_us: mean(&times).unwrap_or(f64::NAN),
            });
        }
    }
    out
}

fn pct(k: u64, n: u64, ci: Interval) -> String {
    format!(
        "{:.1} % ({k}/{n}) [{:.1}, {:.1}]",
        100.0 * k as f64 / n.max(1) as f64,
        100.0 * ci.lo,
        100.0 * ci.hi
    )
}

fn ratio(m: Option<f64>, ci: Option<Interval>) -> String {
    match (m, ci) {
        (Some(m), Some(ci)) => format!("{m:.4} [{:.4}, {:.4}]", ci.lo, ci.hi),
        _ => "—".to_string(),
    }
}

fn time(us: f64) -> String {
    if us >= 1000.0 {
        format!("{:.2} ms", us / 1000.0)
    } else {
        format!("{us:.1} µs")
    }
}

/// The report's markdown: one table, a line on the missing paper figures and on the setting.
pub fn markdown(summaries: &[Summary], size: Size) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Seed 004 (GA coarse route + fuzzy fine switch) against A* and HNAV (linear, partial); \
         {} entries per MovingAI `.scen`, {} worlds of the seed's setting. 95 % intervals \
         (Wilson, bootstrap). Length / optimal and ticks are over the tasks all three planners \
         solve (paired).\n",
        size.entries_per_file, size.worlds
    );
    let _ = writeln!(s, "| setting | planner | success [95 %] | length / optimal [95 %] (paired n) | ticks to goal | collision-free [95 %] | collisions / route | time / query |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    for m in summaries {
        let moving = m.setting == OWN;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} ({}) | {} | {} | {} | {} |",
            m.setting,
            m.planner,
            pct(m.found, m.tasks, m.found_ci),
            ratio(m.length_ratio, m.length_ratio_ci),
            m.paired,
            m.ticks.map_or("—".into(), |t| format!("{t:.1}")),
            if moving {
                pct(m.collision_free, m.tasks, m.collision_free_ci)
            } else {
                "— (static)".to_string()
            },
            match (moving, m.mean_collisions) {
                (true, Some(c)) => format!("{c:.2}"),
                _ => "—".to_string(),
            },
            time(m.mean_time_us)
        );
    }
    let _ = writeln!(
        s,
        "\nPaper: seed 004 publishes no result table, timing or map (the article is truncated \
         after Fig. 2), so there is no figure of theirs to put beside ours."
    );
    let _ = writeln!(
        s,
        "Seed's setting [inferred]: {side} x {side} grid, {rect} random rectangles (sides 1-{mr}), \
         {robots} other robots on shortest routes known for N = {depth} ticks, start and goal \
         at least {md} apart. A* and HNAV plan on the walls only; every route is scored on the \
         same time layers (node t at tick t). Times are wall times of one call with a fresh \
         planner, on this machine.",
        side = own::SIDE,
        rect = own::RECTANGLES,
        mr = own::MAX_RECT,
        robots = own::ROBOTS,
        depth = own::DEPTH,
        md = own::MIN_DISTANCE
    );
    s
}

/// The JSON document: the figures (the same for a seed) apart from the wall times.
pub fn json(
    settings: &[(String, Vec<Task>)],
    summaries: &[Summary],
    size: Size,
) -> serde_json::Value {
    let timings: Vec<_> = summaries
        .iter()
        .map(|m| serde_json::json!({"setting": m.setting, "planner": m.planner, "mean_time_us": m.mean_time_us}))
        .collect();
    let tasks: Vec<_> = settings
        .iter()
        .map(|(name, tasks)| serde_json::json!({"setting": name, "tasks": tasks}))
        .collect();
    serde_json::json!({
        "figures": {
            "size": size,
            "planners": PLANNERS.map(|p| p.name()),
            "summaries": summaries,
            "settings": tasks,
            "own_setting": {
                "side": own::SIDE, "rectangles": own::RECTANGLES, "max_rect": own::MAX_RECT,
                "robots": own::ROBOTS, "depth": own::DEPTH, "min_distance": own::MIN_DISTANCE,
            },
            "paper": null,
        },
        "timings": timings,
    })
}
