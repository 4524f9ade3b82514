//! Experiment `pso`: seed 003's Tables 1 and 2 — the original swarm algorithm at r_max 1, 2,
//! 4 against the modified one (adaptive weights, virtual obstacles) at n_lm 5, 7, 10 — on
//! 100 x 100 maps of 15 random rectangles, 9 particles, 1200 iterations, 100 runs a setting
//! (`--quick`: 20). Every setting runs on the same maps (paired; the paper does not say), so
//! [`pso_paired`] also compares the steps on the tasks both algorithms solve, and
//! [`pso_ablation`] runs the modified algorithm with one modification switched off at a time.
//! The differences from the paper are discussed in `docs/experiments/pso.md`.

use std::fmt::Write as _;

use hnav_agent::pso::options::{Alternative, CornerRule};
use hnav_agent::pso::{self, Escape, PsoOptions, Swarm, Variant, WeightLaw};
use hnav_runtime::grid::{octile, octile_shortest_path_len, Cell, CornerCutting, Grid};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::stats::{bootstrap_mean, mean, wilson, Interval, Z95};
use super::{pso_ablation, pso_paired};
use super::{Options, Report};

/// Table 1 of the paper: (r_max, mean steps, success %).
pub const PAPER_TABLE_1: [(i32, f64, f64); 3] =
    [(1, 183.0, 90.0), (2, 210.0, 88.0), (4, 155.0, 90.0)];
/// Table 2 of the paper: (n_lm, mean steps, success %).
pub const PAPER_TABLE_2: [(u32, f64, f64); 3] =
    [(5, 159.0, 94.0), (7, 100.0, 98.0), (10, 93.0, 96.0)];
/// The notes' Monte-Carlo estimate of the occupied share under the map assumptions (not a
/// paper number).
pub const NOTES_DENSITY: f64 = 0.195;

const SIDE: u32 = 100;
const RECTANGLES: usize = 15;
const MAX_RECT: u32 = 25;
const CLEARANCE: i64 = 2;
const RESAMPLES: usize = 2000;

/// A random map of the paper's kind: 15 axis-aligned rectangles, sides uniform in [1, 25],
/// lower-left corner uniform over the map, overlap allowed, clipped at the border \[A\].
pub fn random_map(rng: &mut ChaCha8Rng) -> Grid {
    random_rectangles(rng, SIDE, RECTANGLES, MAX_RECT)
}

/// A `side x side` map with `rectangles` random axis-aligned rectangles, sides uniform in
/// [1, `max_rect`], corner uniform over the map, overlap allowed, clipped at the border: the
/// generator of the pso experiment's maps and of the ga-fuzzy experiment's own setting.
pub fn random_rectangles(
    rng: &mut ChaCha8Rng,
    side: u32,
    rectangles: usize,
    max_rect: u32,
) -> Grid {
    let mut blocked = vec![false; (side * side) as usize];
    for _ in 0..rectangles {
        let (w, h) = (rng.gen_range(1..=max_rect), rng.gen_range(1..=max_rect));
        let (x0, y0) = (rng.gen_range(0..side), rng.gen_range(0..side));
        for y in y0..(y0 + h).min(side) {
            for x in x0..(x0 + w).min(side) {
                blocked[(y * side + x) as usize] = true;
            }
        }
    }
    Grid::from_blocked(side, side, &blocked).expect("a non-empty square grid is valid")
}

/// Whether every cell within Chebyshev distance 2 of `c` is inside and free (the paper's
/// "distance to every obstacle at least 2 cells", read as a 2-cell free margin \[A\]).
pub fn clear(grid: &Grid, c: Cell) -> bool {
    (-CLEARANCE..=CLEARANCE).all(|dy| {
        (-CLEARANCE..=CLEARANCE).all(|dx| {
            grid.cell_checked(i64::from(c.x) + dx, i64::from(c.y) + dy)
                .is_some_and(|n| !grid.is_blocked(n))
        })
    })
}

/// A random start and goal with the clearance, distinct; `None` if 10 000 draws find none.
pub fn endpoints(grid: &Grid, rng: &mut ChaCha8Rng) -> Option<(Cell, Cell)> {
    let mut draw = || {
        (0..10_000).find_map(|_| {
            let c = Cell::new(rng.gen_range(0..SIDE), rng.gen_range(0..SIDE));
            clear(grid, c).then_some(c)
        })
    };
    let start = draw()?;
    (0..100)
        .find_map(|_| draw().filter(|&g| g != start))
        .map(|g| (start, g))
}

/// One task: a map and its endpoints, and the length of its shortest path (octile, cells),
/// `None` when the goal is unreachable.
struct Task {
    grid: Grid,
    start: Cell,
    goal: Cell,
    shortest: Option<f64>,
}

fn tasks(n: usize, seed: u64) -> Vec<Task> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let grid = random_map(&mut rng);
        let Some((start, goal)) = endpoints(&grid, &mut rng) else {
            continue;
        };
        let shortest = octile_shortest_path_len(&grid, start, goal, CornerCutting::Allowed);
        out.push(Task {
            grid,
            start,
            goal,
            shortest,
        });
    }
    out
}

/// One setting's figures.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// `"original"` or `"modified"`.
    pub algorithm: &'static str,
    /// r_max (original) or n_lm (modified).
    pub parameter: u32,
    /// The paper's mean steps and success rate (%).
    pub paper_steps: f64,
    /// The paper's success rate (%).
    pub paper_success: f64,
    /// Runs.
    pub runs: u64,
    /// Successes (goal reached, trace connected).
    pub successes: u64,
    /// Wilson 95 % interval of the success rate.
    pub success_ci: Interval,
    /// Mean iterations of the successful runs, and their bootstrap 95 % interval.
    pub mean_steps: Option<f64>,
    /// Bootstrap 95 % interval of `mean_steps`.
    pub steps_ci: Option<Interval>,
    /// Failures by cause: goal not reached in k_max (a local minimum), of which on maps
    /// where the goal is unreachable; trace gaps.
    pub not_reached: u64,
    /// Of `not_reached`, runs whose goal no path reaches.
    pub unsolvable: u64,
    /// Reached with a broken trace.
    pub gaps: u64,
    /// Mean virtual obstacles placed per run.
    pub mean_virtual_obstacles: f64,
    /// Mean local-minimum detections per run (x^G unchanged for more than n_lm iterations;
    /// the original runs the detector at n_lm = 5 without acting on it, which leaves its
    /// moves unchanged).
    pub mean_detections: f64,
    /// The iterations of each run, in task order, `None` where it failed (for pooling and
    /// for the paired comparison).
    #[serde(skip)]
    pub per_task: Vec<Option<f64>>,
    /// Each run's record, in task order.
    #[serde(skip)]
    pub detail: Vec<TaskRun>,
}

/// What one run did, beyond success (the ablation's per-task record).
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct TaskRun {
    /// Goal reached with a connected trace.
    pub success: bool,
    /// Goal reached within k_max (a success, or a gap).
    pub reached: bool,
    /// Iterations run: to the goal (also when the trace then has a gap), k_max otherwise.
    pub iterations: u32,
    /// Octile length (cells) of the route through the trace, on success.
    pub route_len: Option<f64>,
    /// Local-minimum detections.
    pub detections: u32,
    /// Virtual obstacles placed.
    pub obstacles: u32,
}

fn run_setting(tasks: &[Task], options: &PsoOptions, salt: u64, seed: u64) -> anyhow::Result<Row> {
    let mut swarm = Swarm::default();
    let (mut successes, mut not_reached, mut unsolvable, mut gaps) = (0, 0, 0, 0);
    let mut per_task = Vec::with_capacity(tasks.len());
    let mut detail = Vec::with_capacity(tasks.len());
    for (i, t) in tasks.iter().enumerate() {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ (salt << 32) ^ i as u64);
        let out = pso::run(
            &mut swarm,
            &t.grid,
            (t.start, t.goal),
            options,
            CornerCutting::Allowed,
            &mut rng,
        )?;
        per_task.push(out.success().then(|| f64::from(out.iterations)));
        detail.push(TaskRun {
            success: out.success(),
            reached: out.reached,
            iterations: out.iterations,
            route_len: out
                .route
                .as_ref()
                .filter(|_| out.success())
                .map(|r| r.windows(2).map(|w| octile(w[0], w[1])).sum()),
            detections: out.minima.detections,
            obstacles: u32::try_from(out.virtual_obstacles).unwrap_or(u32::MAX),
        });
        if out.success() {
            successes += 1;
        } else if out.reached {
            gaps += 1;
        } else {
            not_reached += 1;
            unsolvable += u64::from(t.shortest.is_none());
        }
    }
    let runs = tasks.len() as u64;
    let steps: Vec<f64> = per_task.iter().flatten().copied().collect();
    let per_run = |f: fn(&TaskRun) -> u32| {
        detail.iter().map(|d| f64::from(f(d))).sum::<f64>() / runs.max(1) as f64
    };
    let (mean_virtual_obstacles, mean_detections) =
        (per_run(|d| d.obstacles), per_run(|d| d.detections));
    Ok(Row {
        algorithm: "",
        parameter: 0,
        paper_steps: 0.0,
        paper_success: 0.0,
        runs,
        successes,
        success_ci: wilson(successes, runs, Z95).unwrap_or(Interval { lo: 0.0, hi: 1.0 }),
        mean_steps: mean(&steps),
        steps_ci: bootstrap_mean(&steps, RESAMPLES, 0.05, seed ^ salt),
        not_reached,
        unsolvable,
        gaps,
        mean_virtual_obstacles,
        mean_detections,
        per_task,
        detail,
    })
}

/// The ablation's settings (after the tables' nine): the modified algorithm at n_lm 5, 7, 10
/// with one modification reverted to the original's, each under both corner rules where the
/// rule matters. Their names are the rows' `algorithm`; [`pso_ablation`] describes them.
fn ablation_settings() -> Vec<(&'static str, u32, f64, f64, PsoOptions)> {
    let mut out = Vec::new();
    for (n_lm, s, p) in PAPER_TABLE_2 {
        let m = PsoOptions::modified(n_lm);
        let always = PsoOptions {
            corner_rule: CornerRule::Always,
            ..m
        };
        let no_obstacles = PsoOptions {
            escape: Escape::DetectOnly,
            ..m
        };
        let fixed = |o: PsoOptions| PsoOptions {
            weight_law: WeightLaw::Fixed,
            ..o
        };
        let blocked = |o: PsoOptions| PsoOptions {
            variant: Variant::Original,
            r_max: 1,
            alternative: Alternative::Sum,
            ..o
        };
        out.extend([
            ("no-virtual-obstacles", n_lm, s, p, no_obstacles),
            ("fixed-weights", n_lm, s, p, fixed(m)),
            ("fixed-weights-always", n_lm, s, p, fixed(always)),
            ("original-blocked-move", n_lm, s, p, blocked(m)),
            ("original-blocked-move-always", n_lm, s, p, blocked(always)),
        ]);
    }
    out
}

/// Pooled figures of one algorithm over its three settings.
#[derive(Clone, Debug, Serialize)]
pub struct Pooled {
    /// Successes of all its runs.
    pub successes: u64,
    /// Runs.
    pub runs: u64,
    /// Wilson 95 % interval.
    pub success_ci: Interval,
    /// Mean of the three settings' mean steps (how the paper averages).
    pub mean_of_means: Option<f64>,
    /// Mean steps over every successful run, and its bootstrap interval.
    pub mean_steps: Option<f64>,
    /// Bootstrap 95 % interval of `mean_steps`.
    pub steps_ci: Option<Interval>,
}

fn pool(rows: &[Row], seed: u64) -> Pooled {
    let successes = rows.iter().map(|r| r.successes).sum();
    let runs = rows.iter().map(|r| r.runs).sum();
    let all: Vec<f64> = rows
        .iter()
        .flat_map(|r| r.per_task.iter().flatten().copied())
        .collect();
    let means: Vec<f64> = rows.iter().filter_map(|r| r.mean_steps).collect();
    Pooled {
        successes,
        runs,
        success_ci: wilson(successes, runs, Z95).unwrap_or(Interval { lo: 0.0, hi: 1.0 }),
        mean_of_means: (means.len() == rows.len()).then(|| mean(&means)).flatten(),
        mean_steps: mean(&all),
        steps_ci: bootstrap_mean(&all, RESAMPLES, 0.05, seed),
    }
}

/// The pooled two-proportion z statistic of `b` against `a` (successes, runs).
pub fn two_proportion_z(a: (u64, u64), b: (u64, u64)) -> f64 {
    let (pa, pb) = (a.0 as f64 / a.1 as f64, b.0 as f64 / b.1 as f64);
    let p = (a.0 + b.0) as f64 / (a.1 + b.1) as f64;
    let se = (p * (1.0 - p) * (1.0 / a.1 as f64 + 1.0 / b.1 as f64)).sqrt();
    (pb - pa) / se
}

/// Runs the experiment.
pub fn run(options: Options) -> anyhow::Result<Report> {
    let n = if options.quick { 20 } else { 100 };
    let tasks = tasks(n, options.seed);
    let mut settings: Vec<(&'static str, u32, f64, f64, PsoOptions)> = Vec::new();
    for (r, s, p) in PAPER_TABLE_1 {
        // The detector only counts here: the original's moves are those of `Escape::Off`.
        let original = PsoOptions {
            escape: Escape::DetectOnly,
            ..PsoOptions::original(r)
        };
        settings.push(("original", r as u32, s, p, original));
    }
    for (n_lm, s, p) in PAPER_TABLE_2 {
        settings.push(("modified", n_lm, s, p, PsoOptions::modified(n_lm)));
    }
    for (n_lm, s, p) in PAPER_TABLE_2 {
        let always = PsoOptions {
            corner_rule: CornerRule::Always,
            ..PsoOptions::modified(n_lm)
        };
        settings.push(("modified-always", n_lm, s, p, always));
    }
    let tables = settings.len();
    settings.extend(ablation_settings());
    let mid = settings.len() / 2;
    // Two threads (the machine's two cores), each a fixed half of the settings: the figures
    // do not depend on the split, since every run has its own seeded stream.
    let rows: Vec<Row> = std::thread::scope(|scope| {
        let work = |range: std::ops::Range<usize>| {
            let (tasks, settings) = (&tasks, &settings);
            move || -> anyhow::Result<Vec<Row>> {
                range
                    .map(|k| {
                        let (algorithm, parameter, paper_steps, paper_success, o) = settings[k];
                        let row = run_setting(tasks, &o, k as u64 + 1, options.seed)?;
                        Ok(Row {
                            algorithm,
                            parameter,
                            paper_steps,
                            paper_success,
                            ..row
                        })
                    })
                    .collect()
            }
        };
        let a = scope.spawn(work(0..mid));
        let b = scope.spawn(work(mid..settings.len()));
        let mut rows = a
            .join()
            .map_err(|_| anyhow::anyhow!("a worker panicked"))??;
        rows.extend(
            b.join()
                .map_err(|_| anyhow::anyhow!("a worker panicked"))??,
        );
        Ok::<_, anyhow::Error>(rows)
    })?;
    let (rows, ablation_rows) = {
        let mut rows = rows;
        let rest = rows.split_off(tables);
        (rows, rest)
    };
    let original = pool(&rows[..3], options.seed ^ 0x0a);
    let modified = pool(&rows[3..6], options.seed ^ 0x0b);
    let always = pool(&rows[6..], options.seed ^ 0x0c);
    let density = tasks.iter().map(|t| t.grid.blocked_fraction()).sum::<f64>() / n as f64;
    let unsolvable = tasks.iter().filter(|t| t.shortest.is_none()).count();
    let shortest: Vec<Option<f64>> = tasks.iter().map(|t| t.shortest).collect();
    let z = two_proportion_z(
        (original.successes, original.runs),
        (modified.successes, modified.runs),
    );
    let z_always = two_proportion_z(
        (original.successes, original.runs),
        (always.successes, always.runs),
    );
    let paired = pso_paired::compare(&rows, options.seed);
    let mut markdown = render(
        &rows,
        [&original, &modified, &always],
        [z, z_always],
        (density, unsolvable, n),
    );
    markdown.push_str(&pso_paired::render(&paired));
    let all_rows: Vec<&Row> = rows.iter().chain(&ablation_rows).collect();
    let ablation = pso_ablation::analyse(&all_rows, &shortest, options.seed);
    markdown.push_str(&pso_ablation::render(&ablation));
    let data = serde_json::json!({
        "runs_per_setting": n,
        "rows": rows,
        "paired_steps": paired,
        "ablation": ablation,
        "pooled": { "original": original, "modified": modified, "z_success": z,
                    "modified_always": always, "z_success_always": z_always },
        "maps": { "mean_blocked_fraction": density, "notes_estimate": NOTES_DENSITY, "unsolvable": unsolvable },
    });
    Ok(Report {
        name: "pso",
        quick: options.quick,
        seed: options.seed,
        markdown,
        data,
    })
}

fn pct(i: Interval) -> String {
    format!("[{:.1}, {:.1}]", 100.0 * i.lo, 100.0 * i.hi)
}

fn steps(m: Option<f64>, ci: Option<Interval>) -> String {
    match (m, ci) {
        (Some(m), Some(ci)) => format!("{m:.1} [{:.1}, {:.1}]", ci.lo, ci.hi),
        _ => "—".to_string(),
    }
}

fn render(rows: &[Row], pooled: [&Pooled; 3], z: [f64; 2], maps: (f64, usize, usize)) -> String {
    let mut s = String::new();
    let n = rows.first().map_or(0, |r| r.runs);
    let _ = writeln!(s, "Seed 003 (Kostyukov et al. 2024), {n} runs per setting, same maps for every setting; 95 % intervals (Wilson, bootstrap).\n");
    for (title, alg, par) in [
        ("Table 1: original algorithm", "original", "r_max"),
        ("Table 2: modified algorithm", "modified", "n_lm"),
        (
            "Table 2, again: modified algorithm, a virtual obstacle at every detected minimum (no corner analysis)",
            "modified-always",
            "n_lm",
        ),
    ] {
        let _ = writeln!(s, "{title}\n");
        let _ = writeln!(s, "| {par} | paper steps | our steps [95 %] | paper success | our success | [95 %] | not reached (unsolvable) | gaps | detections/run | virtual obstacles/run |");
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
        for r in rows.iter().filter(|r| r.algorithm == alg) {
            let _ = writeln!(
                s,
                "| {} | {:.0} | {} | {:.0} % | {:.1} % ({}/{}) | {} | {} ({}) | {} | {:.1} | {:.1} |",
                r.parameter,
                r.paper_steps,
                steps(r.mean_steps, r.steps_ci),
                r.paper_success,
                100.0 * r.successes as f64 / r.runs as f64,
                r.successes,
                r.runs,
                pct(r.success_ci),
                r.not_reached,
                r.unsolvable,
                r.gaps,
                r.mean_detections,
                r.mean_virtual_obstacles
            );
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(s, "Pooled (paper: success 89.33 % -> 96 %, mean steps 182.67 -> 117.33, printed 183 -> 118)\n");
    let _ = writeln!(
        s,
        "| algorithm | success | [95 %] | mean of the 3 means | steps over all successes [95 %] |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    let names = ["original", "modified", "modified, no corner analysis"];
    for (name, p) in names.into_iter().zip(pooled) {
        let _ = writeln!(
            s,
            "| {name} | {:.1} % ({}/{}) | {} | {} | {} |",
            100.0 * p.successes as f64 / p.runs.max(1) as f64,
            p.successes,
            p.runs,
            pct(p.success_ci),
            p.mean_of_means.map_or("—".into(), |m| format!("{m:.1}")),
            steps(p.mean_steps, p.steps_ci)
        );
    }
    let _ = writeln!(s, "\nModified against original, success: z = {:.2}; without the corner analysis z = {:.2} (paper's pooled 268/300 vs 288/300: z = {:.2}).", z[0], z[1], two_proportion_z((268, 300), (288, 300)));
    let _ = writeln!(
        s,
        "Maps: {:.1} % of cells blocked on average (the notes' estimate: {:.1} %); {} of {} tasks have no path at all.",
        100.0 * maps.0, 100.0 * NOTES_DENSITY, maps.1, maps.2
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_papers_summary_figures_follow_from_its_tables() {
        let m = |t: &[f64]| t.iter().sum::<f64>() / t.len() as f64;
        let steps1 = m(&PAPER_TABLE_1.map(|r| r.1));
        let succ1 = m(&PAPER_TABLE_1.map(|r| r.2));
        let steps2 = m(&PAPER_TABLE_2.map(|r| r.1));
        let succ2 = m(&PAPER_TABLE_2.map(|r| r.2));
        assert_eq!(
            format!("{steps1:.2} {succ1:.2} {steps2:.2} {succ2:.2}"),
            "182.67 89.33 117.33 96.00"
        );
        // The paper's "35.5 %" uses its rounded 118 and 183; "6.67 %" is percentage points.
        assert_eq!(format!("{:.3}", 1.0 - 118.0 / 183.0), "0.355");
        assert_eq!(format!("{:.2}", succ2 - succ1), "6.67");
        // The notes' z of the pooled 268/300 against 288/300.
        assert_eq!(
            format!("{:.1}", two_proportion_z((268, 300), (288, 300))),
            "3.1"
        );
        // The notes' binomial half-widths at n = 100: 5.9, 3.8, 2.7 points.
        let half = |p: f64| 100.0 * Z95 * (p * (1.0 - p) / 100.0f64).sqrt();
        assert_eq!(
            format!("{:.1} {:.1} {:.1}", half(0.90), half(0.96), half(0.98)),
            "5.9 3.8 2.7"
        );
    }

    #[test]
    fn maps_and_endpoints_are_seeded_and_clear() {
        let a = tasks(3, 9);
        let b = tasks(3, 9);
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.grid, y.grid);
            assert_eq!((x.start, x.goal), (y.start, y.goal));
            assert!(clear(&x.grid, x.start) && clear(&x.grid, x.goal) && x.start != x.goal);
            assert!(x.grid.blocked_count() > 0);
        }
    }
}
