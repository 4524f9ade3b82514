//! The GA loop (seed 004 §B.3; the loop's parameters are the review's Ahn & Ramakrishna GA,
//! notes §C.5, where the seed gives none) and [`GaPlanner`], the [`RoutePlanner`] "ga-fuzzy".
//!
//! * Population of [`GaOptions::population`] goal-biased walks (initialisation).
//! * Each generation: parents by pairwise tournament (Ahn & Ramakrishna), crossover with
//!   probability [`GaOptions::crossover`], mutation with probability
//!   [`GaOptions::mutation`] (the review: 5-10 %); then the worst of parents and children
//!   are dropped (Ahn & Ramakrishna's "the worst part is replaced by offspring").
//! * Stop after [`GaOptions::generations`] generations or [`GaOptions::stall`] without a
//!   better best `\[inferred\]`; the best route then goes through the fine switch
//!   ([`super::fine`]).
//!
//! Deterministic: each query draws from a ChaCha stream seeded by the options' seed, the
//! start and the goal, so the same query gets the same route whatever came before it.

use hnav_runtime::grid::{Cell, CornerCutting, Grid};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::chromosome::Operators;
use super::fine::refine;
use super::fitness::{score, Score, Weights};
use super::fuzzy::FuzzyRules;
use super::time_grid::TimeGrid;
use crate::error::{check_inside, Error, Role};
use crate::route::RoutePlanner;

/// The GA's parameters. Every default but the mutation rate and the tournament is
/// `\[inferred\]`: the seed gives no population size, rates, selection or stopping rule.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct GaOptions {
    /// Individuals per generation.
    pub population: usize,
    /// Most generations.
    pub generations: usize,
    /// Generations without a better best after which the search stops.
    pub stall: usize,
    /// Probability that two parents are crossed.
    pub crossover: f64,
    /// Probability that a child is mutated (the review's 5-10 %: 0.1).
    pub mutation: f64,
    /// Goal bias of the walks: probability of the step nearest the goal.
    pub greed: f64,
    /// `alpha_1`, `alpha_2`.
    pub weights: Weights,
    /// Whether the fine switch runs on the best coarse route.
    pub fine: bool,
    /// The corner rule of the moves (MovingAI's by default).
    pub corner_cutting: CornerCutting,
    /// `N`, the longest chromosome, for a static grid; `None`: the number of cells.
    pub depth: Option<usize>,
    /// Seed of the query streams.
    pub seed: u64,
}

impl Default for GaOptions {
    fn default() -> Self {
        GaOptions {
            population: 40,
            generations: 80,
            stall: 20,
            crossover: 0.9,
            mutation: 0.1,
            greed: 0.7,
            weights: Weights::default(),
            fine: true,
            corner_cutting: CornerCutting::Forbidden,
            depth: None,
            seed: 4,
        }
    }
}

impl GaOptions {
    /// Checks every option's domain.
    pub fn validate(&self) -> Result<(), Error> {
        if self.population < 2 {
            return Err(Error::option(
                "population",
                format!("{}: at least 2", self.population),
            ));
        }
        for (name, p) in [
            ("crossover", self.crossover),
            ("mutation", self.mutation),
            ("greed", self.greed),
        ] {
            if !(0.0..=1.0).contains(&p) {
                return Err(Error::option(name, format!("{p}: a probability in [0, 1]")));
            }
        }
        self.weights.validate()
    }
}

/// What a GA query found.
#[derive(Clone, PartialEq, Debug)]
pub struct GaRoute {
    /// The route, start first, goal last; node `t` is held at tick `t`.
    pub cells: Vec<Cell>,
    /// Its score.
    pub score: Score,
    /// Generations run.
    pub generations: usize,
    /// Stretches the fine switch replaced.
    pub switched: usize,
}

/// Seed 004's hybrid planner: the GA's coarse route, then the fuzzy fine switch.
#[derive(Clone, Debug, Default)]
pub struct GaPlanner {
    options: GaOptions,
    rules: FuzzyRules,
    ops: Operators,
    population: Vec<(Score, Vec<Cell>)>,
    spare: Vec<Vec<Cell>>,
    fine: (Vec<Cell>, Vec<Cell>),
}

impl GaPlanner {
    /// A planner with `options` (checked).
    pub fn new(options: GaOptions) -> Result<GaPlanner, Error> {
        options.validate()?;
        Ok(GaPlanner {
            options,
            ..GaPlanner::default()
        })
    }

    /// The options.
    pub fn options(&self) -> &GaOptions {
        &self.options
    }

    /// Plans from `start` to `goal` over the time layers of `tg`. `Ok(None)` when no route
    /// within `tg.depth()` nodes exists (the initial walks find none).
    pub fn plan(
        &mut self,
        tg: &TimeGrid,
        start: Cell,
        goal: Cell,
    ) -> Result<Option<GaRoute>, Error> {
        let grid = tg.grid();
        for (c, role) in [(start, Role::Start), (goal, Role::Goal)] {
            check_inside(c, role, grid.width(), grid.height())?;
            if grid.is_blocked(c) {
                return Err(Error::Blocked { role, cell: c });
            }
        }
        let o = self.options;
        let mix = (u64::from(start.x) << 48)
            ^ (u64::from(start.y) << 32)
            ^ (u64::from(goal.x) << 16)
            ^ u64::from(goal.y);
        let mut rng = ChaCha8Rng::seed_from_u64(o.seed ^ mix.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        if !self.initialise(tg, start, goal, &mut rng) {
            return Ok(None);
        }
        let timed = !tg.is_static();
        let (mut best, mut stall, mut generations) = (self.population[0].0.fitness, 0, 0);
        while generations < o.generations && stall < o.stall {
            generations += 1;
            self.generation(tg, timed, &mut rng);
            if self.population[0].0.fitness > best + 1e-12 {
                (best, stall) = (self.population[0].0.fitness, 0);
            } else {
                stall += 1;
            }
        }
        let mut cells = self.population[0].1.clone();
        let switched = if o.fine {
            let (f, t) = &mut self.fine;
            refine(tg, &self.rules, &mut cells, f, t)
        } else {
            0
        };
        Ok(Some(GaRoute {
            score: score(&cells, tg, o.weights),
            cells,
            generations,
            switched,
        }))
    }

    fn initialise(&mut self, tg: &TimeGrid, start: Cell, goal: Cell, rng: &mut ChaCha8Rng) -> bool {
        let o = self.options;
        self.spare.extend(self.population.drain(..).map(|(_, r)| r));
        for _ in 0..o.population {
            let mut r = self.spare.pop().unwrap_or_default();
            // A walk through the time layers can paint itself into a corner (its visited
            // cells stay marked while the obstacles move on): a few tries, then a walk that
            // sees only the walls, whose collisions the fitness then weighs [inferred].
            let timed_ok = !tg.is_static()
                && (0..8).any(|_| {
                    self.ops
                        .random_walk(tg, Some(0), start, goal, tg.depth(), o.greed, rng, &mut r)
                });
            if !timed_ok
                && !self
                    .ops
                    .random_walk(tg, None, start, goal, tg.depth(), o.greed, rng, &mut r)
            {
                self.spare.push(r);
                return false;
            }
            self.population.push((score(&r, tg, o.weights), r));
        }
        sort(&mut self.population);
        true
    }

    fn generation(&mut self, tg: &TimeGrid, timed: bool, rng: &mut ChaCha8Rng) {
        let o = self.options;
        let n = self.population.len();
        for _ in 0..n.div_ceil(2) {
            let a = tournament(&self.population, rng);
            let b = tournament(&self.population, rng);
            let mut ca = self.spare.pop().unwrap_or_default();
            let mut cb = self.spare.pop().unwrap_or_default();
            let (pa, pb) = (&self.population[a].1, &self.population[b].1);
            let crossed = rng.gen_bool(o.crossover)
                && self.ops.crossover(tg.grid(), pa, pb, rng, &mut ca, &mut cb)
                && ca.len() <= tg.depth()
                && cb.len() <= tg.depth();
            if !crossed {
                ca.clear();
                ca.extend_from_slice(pa);
                cb.clear();
                cb.extend_from_slice(pb);
            }
            for mut c in [ca, cb] {
                if rng.gen_bool(o.mutation) {
                    self.ops.mutate(tg, &mut c, o.greed, timed, rng);
                }
                self.population.push((score(&c, tg, o.weights), c));
            }
        }
        sort(&mut self.population);
        self.spare
            .extend(self.population.drain(n..).map(|(_, r)| r));
    }
}

/// Best first; equal fitness: fewer nodes first (a stable sort keeps the rest in order).
fn sort(pop: &mut [(Score, Vec<Cell>)]) {
    pop.sort_by(|a, b| {
        b.0.fitness
            .total_cmp(&a.0.fitness)
            .then(a.1.len().cmp(&b.1.len()))
    });
}

/// Pairwise tournament: the fitter of two drawn at random (the better index on a tie, since
/// the population is sorted).
fn tournament(pop: &[(Score, Vec<Cell>)], rng: &mut ChaCha8Rng) -> usize {
    let a = rng.gen_range(0..pop.len());
    let b = rng.gen_range(0..pop.len());
    a.min(b)
}

impl RoutePlanner for GaPlanner {
    fn name(&self) -> &'static str {
        "ga-fuzzy"
    }

    fn route(&mut self, grid: &Grid, start: Cell, goal: Cell) -> Result<Option<Vec<Cell>>, Error> {
        let depth = self.options.depth.unwrap_or(grid.len()).max(2);
        let tg = TimeGrid::fixed(grid.clone(), self.options.corner_cutting, depth)?;
        Ok(self.plan(&tg, start, goal)?.map(|r| r.cells))
    }
}
