//! The `pso` experiment's tasks and runs, below [`super::pso`], [`super::pso_paired`] and
//! [`super::pso_ablation`], which all read them: the paper's published rows, the random maps
//! and endpoints, and one setting run on every task ([`Row`], one [`TaskRun`] a task).

use hnav_agent::pso::{self, PsoOptions, Swarm};
use hnav_runtime::grid::{octile, octile_shortest_path_len, Cell, CornerCutting, Grid};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::stats::{bootstrap_mean, mean, wilson, Interval, Z95};

/// The rows of the modified algorithm as it runs by default: a virtual obstacle at every
/// detected minimum (`CornerRule::Always`), the rule that reproduces the paper's success rates.
pub const MODIFIED: &str = "modified";
/// The rows of the modified algorithm with the notes' corner analysis (`CornerRule::Sides`),
/// the option.
pub const MODIFIED_CORNERS: &str = "modified-corners";

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
pub struct Task {
    /// The map.
    pub grid: Grid,
    /// The start cell.
    pub start: Cell,
    /// The goal cell.
    pub goal: Cell,
    /// The shortest path's octile length, `None` when no path reaches the goal.
    pub shortest: Option<f64>,
}

/// `n` tasks from the stream seeded by `seed`.
pub fn tasks(n: usize, seed: u64) -> Vec<Task> {
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
    /// The other count: mean iterations over all runs, a run that never reaches the goal
    /// counted at k_max (1200). The paper does not say which of the two it printed.
    pub all_runs_steps: Option<f64>,
    /// Bootstrap 95 % interval of `all_runs_steps`.
    pub all_runs_ci: Option<Interval>,
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

/// One setting (`options`) run on every task, each run on its own stream (from `seed`, `salt`
/// and the task's index). The row's labels and paper figures are left for the caller.
pub fn run_setting(
    tasks: &[Task],
    options: &PsoOptions,
    salt: u64,
    seed: u64,
) -> anyhow::Result<Row> {
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
    let all_runs: Vec<f64> = detail.iter().map(|d| f64::from(d.iterations)).collect();
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
        all_runs_steps: mean(&all_runs),
        all_runs_ci: bootstrap_mean(&all_runs, RESAMPLES, 0.05, seed ^ (0xad_0000 | salt)),
        not_reached,
        unsolvable,
        gaps,
        mean_virtual_obstacles,
        mean_detections,
        per_task,
        detail,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
