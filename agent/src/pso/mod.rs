//! Seed 003: swarm (PSO-type) path planning on an unmapped grid with virtual obstacles at
//! swarm-detected local minima (Kostyukov, Medvedev, Medvedev, Pshikhopov 2024; rebuilt in
//! `docs/experiments/pso.md` from the notes of the seed).
//!
//! Nine particles start on the start cell's 3 x 3 block and move one cell per iteration
//! toward the best cells found so far; the run succeeds when a particle stands on the goal
//! within k_max iterations and the trace still connects start and goal. [`run`] is one run
//! (what the `pso` experiment counts); [`PsoPlanner`] is the same as a
//! [`RoutePlanner`]: the robot follows the shortest route through the swarm's trace.
//!
//! | module | what |
//! |---|---|
//! | [`options`] | [`PsoOptions`]: the paper's parameters and one option per \[A\] choice |
//! | [`swarm`] | the particles and their update, eqs. (1)-(9), (20), Pseudocode 1 |
//! | [`weights`] | the adaptive tanh local/global weights, eqs. (10)-(19) |
//! | [`minimum`] | local-minimum detection, the 24-cell analysis, virtual obstacles (Pseudocode 2) |
//! | [`field`] | what the swarm senses of the map, and the virtual-obstacle layer |
//! | [`trace`] | the trace as a route, and its gaps |

pub mod field;
pub mod minimum;
pub mod options;
pub mod swarm;
pub mod trace;
pub mod weights;

use hnav_runtime::grid::{Cell, CornerCutting, Grid};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

pub use options::{Escape, GapRule, PsoOptions, Variant, WeightLaw};
pub use swarm::Swarm;

use crate::error::{check_inside, Error, Role};
use crate::route::RoutePlanner;

/// How one run ended.
#[derive(Clone, PartialEq, Debug)]
pub struct Outcome {
    /// Iterations run: to the goal on success, k_max otherwise.
    pub iterations: u32,
    /// A particle reached the goal within k_max.
    pub reached: bool,
    /// The trace is broken under the options' [`GapRule`] (only judged when `reached`).
    pub gap: bool,
    /// The route through the trace, start to goal, when reached and connected.
    pub route: Option<Vec<Cell>>,
    /// What the local-minimum handling did: detections, exits tried, exits that placed
    /// obstacles (all zero under [`options::Escape::Off`]).
    pub minima: minimum::MinimumCounts,
    /// Virtual obstacles placed.
    pub virtual_obstacles: usize,
}

impl Outcome {
    /// The paper's success: goal reached and no gap.
    pub fn success(&self) -> bool {
        self.reached && !self.gap
    }
}

fn endpoint(grid: &Grid, cell: Cell, role: Role) -> Result<(), Error> {
    check_inside(cell, role, grid.width(), grid.height())?;
    if grid.is_blocked(cell) {
        return Err(Error::Blocked { role, cell });
    }
    Ok(())
}

/// One run of the swarm from `start` to `goal` (Pseudocode 1 to its stopping rules).
pub fn run(
    swarm: &mut Swarm,
    grid: &Grid,
    (start, goal): (Cell, Cell),
    options: &PsoOptions,
    rule: CornerCutting,
    rng: &mut ChaCha8Rng,
) -> Result<Outcome, Error> {
    options.validate()?;
    endpoint(grid, start, Role::Start)?;
    endpoint(grid, goal, Role::Goal)?;
    let p = |c: Cell| [i64::from(c.x), i64::from(c.y)];
    swarm.reset(grid, p(start), p(goal), options);
    let mut iterations = 0;
    let mut arrived = swarm
        .particles
        .iter()
        .position(|q| swarm::objective(q.pos, p(goal)) < options.epsilon);
    while arrived.is_none() && iterations < options.k_max {
        iterations += 1;
        arrived = swarm.step(grid, options, rng);
    }
    let route =
        arrived.and_then(|_| trace::route_through(grid, &swarm.particles, start, goal, rule));
    let gap = match (arrived, options.gap_rule) {
        (None, _) => false,
        (Some(_), GapRule::Graph) => route.is_none(),
        (Some(i), GapRule::Steps) => trace::has_step_gap(&swarm.particles[i].trajectory),
    };
    Ok(Outcome {
        iterations,
        reached: arrived.is_some(),
        gap,
        route,
        minima: swarm.minima,
        virtual_obstacles: swarm.field.placed(),
    })
}

/// Seed 003's swarm as a route planner: each query is one run; its route is the shortest path
/// through the trace, `None` when the swarm fails (trapped, out of iterations, or a gap).
#[derive(Clone, Debug)]
pub struct PsoPlanner {
    options: PsoOptions,
    rule: CornerCutting,
    rng: ChaCha8Rng,
    swarm: Swarm,
}

impl PsoPlanner {
    /// A planner with `options` whose routes obey `rule`, its random stream seeded by `seed`
    /// (a query's answer depends on the queries before it, deterministically).
    pub fn new(options: PsoOptions, rule: CornerCutting, seed: u64) -> Result<PsoPlanner, Error> {
        options.validate()?;
        Ok(PsoPlanner {
            options,
            rule,
            rng: ChaCha8Rng::seed_from_u64(seed),
            swarm: Swarm::default(),
        })
    }
}

impl RoutePlanner for PsoPlanner {
    fn name(&self) -> &'static str {
        "pso"
    }

    fn route(&mut self, grid: &Grid, start: Cell, goal: Cell) -> Result<Option<Vec<Cell>>, Error> {
        let out = run(
            &mut self.swarm,
            grid,
            (start, goal),
            &self.options,
            self.rule,
            &mut self.rng,
        )?;
        Ok(if out.success() { out.route } else { None })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 24 x 24, a wall across the middle open only at its right end: a swarm heading from the
    /// top left to the bottom left stalls against it.
    fn walled() -> Grid {
        let mut rows = vec![".".repeat(24); 24];
        rows[12] = format!("{}{}", "@".repeat(20), "....");
        let rows: Vec<&str> = rows.iter().map(String::as_str).collect();
        Grid::from_rows(&rows).unwrap()
    }

    fn once(o: &PsoOptions, seed: u64) -> Outcome {
        let (start, goal) = (Cell::new(3, 3), Cell::new(3, 20));
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        run(
            &mut Swarm::default(),
            &walled(),
            (start, goal),
            o,
            CornerCutting::Allowed,
            &mut rng,
        )
        .unwrap()
    }

    #[test]
    fn detect_only_moves_as_without_escape_and_counts_its_detections() {
        let mut detected = 0;
        for seed in 0..6 {
            let off = PsoOptions {
                escape: Escape::Off,
                ..PsoOptions::modified(5)
            };
            let detect = PsoOptions {
                escape: Escape::DetectOnly,
                ..off
            };
            let (a, b) = (once(&off, seed), once(&detect, seed));
            assert_eq!(
                (a.iterations, a.reached, &a.route),
                (b.iterations, b.reached, &b.route)
            );
            assert_eq!(a.minima, minimum::MinimumCounts::default());
            assert_eq!((b.minima.checks, b.minima.accepted), (0, 0));
            assert_eq!(b.virtual_obstacles, 0);
            detected += b.minima.detections;
            let full = once(&PsoOptions::modified(5), seed);
            let m = full.minima;
            assert!(m.accepted <= m.detections && m.detections <= m.checks.max(m.detections));
            assert!(full.virtual_obstacles >= m.accepted as usize, "{full:?}");
        }
        assert!(detected > 0, "the wall stalls the swarm at least once");
    }
}
