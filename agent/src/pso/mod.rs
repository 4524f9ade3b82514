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

pub use options::{GapRule, PsoOptions, Variant};
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
    /// Minima declared, and how many of them got virtual obstacles.
    pub minima: (u32, u32),
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
