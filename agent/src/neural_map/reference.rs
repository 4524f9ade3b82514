//! The `f64` reference implementation: the equations of the [module docs](super) written as
//! plainly as possible, every neuron every sweep, no tricks.
//!
//! It is exact (to `f64` rounding) as long as no activation underflows. Activations fall
//! geometrically with the distance from the target (by a factor of roughly 3 to 10 per cell
//! at the wave front), so on maps whose link distances exceed a few hundred cells the far
//! values flush to 0 and this implementation then sees a wave that stops early. It exists to
//! check the fast path ([`super::NeuralMap`]) on maps where it is exact, not to run big maps.

use hnav_runtime::grid::{Cell, Direction, Grid};

use super::driver::{self, SweepEngine, SweepStats};
use super::topology::Topology;
use super::{
    validate_stop, ActivationField, BuildReport, DiagonalRule, Local, NeuralDynamics,
    NeuralMapOptions, OnThreshold, StopRule,
};
use crate::error::{check_inside, Error, Role};

/// A neural map in plain `f64`.
#[derive(Clone, Debug)]
pub struct ReferenceMap {
    topo: Topology,
    options: NeuralMapOptions,
    links: Vec<u8>,
    den: Vec<f64>,
    cur: Vec<f64>,
    next: Vec<f64>,
    target: Option<Cell>,
    threshold: f64,
}

impl ReferenceMap {
    /// A map over `grid`'s obstacles, all neurons 0 until [`NeuralDynamics::build`].
    pub fn new(grid: &Grid, options: NeuralMapOptions) -> Result<ReferenceMap, Error> {
        options.validate()?;
        let topo = Topology::new(grid, options.diagonals);
        let n = topo.len();
        let mut map = ReferenceMap {
            topo,
            options,
            links: vec![0; n],
            den: vec![0.0; n],
            cur: vec![0.0; n],
            next: vec![0.0; n],
            target: None,
            threshold: match options.on_threshold {
                OnThreshold::NonZero => 0.0,
                OnThreshold::Above(t) => t,
            },
        };
        for i in 0..n {
            map.refresh(i);
        }
        Ok(map)
    }

    /// The options the map was created with.
    pub fn options(&self) -> &NeuralMapOptions {
        &self.options
    }

    /// All activations, row-major like the grid.
    pub fn values(&self) -> &[f64] {
        &self.cur
    }

    /// Recomputes the links and denominator of cell `i`.
    fn refresh(&mut self, i: usize) {
        let cell = self.topo.cell(i);
        if self.topo.blocked[i] {
            self.links[i] = 0;
            self.den[i] = 0.0;
        } else {
            self.links[i] = self.topo.links(cell);
            self.den[i] =
                self.topo
                    .denominator(cell, &self.options.weights, self.options.denominator);
        }
    }

    fn check_free(&self, cell: Cell, role: Role) -> Result<(), Error> {
        check_inside(cell, role, self.topo.width, self.topo.height)?;
        if self.topo.is_blocked(cell) {
            return Err(Error::Blocked { role, cell });
        }
        Ok(())
    }

    fn check_stop(&self, stop: &StopRule) -> Result<(), Error> {
        validate_stop(stop)?;
        if let StopRule::PartialActivation { start } = *stop {
            self.check_free(start, Role::Start)?;
        }
        Ok(())
    }
}

impl SweepEngine for ReferenceMap {
    fn sweep(&mut self, want_delta: bool) -> SweepStats {
        let weights = self.options.weights;
        let self_w = weights.gain * weights.self_weight;
        let target = self.target.map(|t| self.topo.index(t));
        let mut s = SweepStats {
            cells: self.cur.len() as u64,
            ..SweepStats::default()
        };
        for i in 0..self.cur.len() {
            let old = self.cur[i];
            let new = if self.topo.blocked[i] {
                0.0
            } else if Some(i) == target {
                1.0
            } else {
                let cell = self.topo.cell(i);
                let mut num = self_w * old;
                for d in Direction::ALL {
                    if self.links[i] & (1 << d.index()) != 0 {
                        if let Some(j) = self.topo.step(cell, d) {
                            num += weights.link(d) * self.cur[self.topo.index(j)];
                        }
                    }
                }
                let u = if self.den[i] > 0.0 {
                    num / self.den[i]
                } else {
                    0.0
                };
                let new = self.options.activation.apply(u);
                if new != old {
                    s.changed += 1;
                }
                if want_delta {
                    s.max_delta = s.max_delta.max((new - old).abs());
                }
                new
            };
            s.newly_on += u64::from(old == 0.0 && new > 0.0);
            s.nonzero += u64::from(new > 0.0);
            s.above += u64::from(new > self.threshold);
            self.next[i] = new;
        }
        s
    }

    fn commit(&mut self) {
        std::mem::swap(&mut self.cur, &mut self.next);
    }

    fn counts(&self) -> (u64, u64) {
        let nonzero = self.cur.iter().filter(|&&v| v > 0.0).count() as u64;
        let above = self.cur.iter().filter(|&&v| v > self.threshold).count() as u64;
        (nonzero, above)
    }

    fn is_above(&self, cell: Cell) -> bool {
        self.cur[self.topo.index(cell)] > self.threshold
    }

    fn is_nonzero(&self, cell: Cell) -> bool {
        self.cur[self.topo.index(cell)] > 0.0
    }
}

impl ActivationField for ReferenceMap {
    fn width(&self) -> u32 {
        self.topo.width
    }

    fn height(&self) -> u32 {
        self.topo.height
    }

    fn is_blocked(&self, cell: Cell) -> bool {
        self.topo.is_blocked(cell)
    }

    fn diagonal_rule(&self) -> DiagonalRule {
        self.topo.rule
    }

    fn target(&self) -> Option<Cell> {
        self.target
    }

    fn local(&self, cell: Cell) -> Local {
        let mut values = [0.0; 9];
        if self.topo.contains(cell) {
            for d in Direction::ALL {
                if let Some(n) = self.topo.step(cell, d) {
                    values[d.index()] = self.cur[self.topo.index(n)];
                }
            }
            values[8] = self.cur[self.topo.index(cell)];
        }
        Local {
            values,
            log2_scale: 0,
        }
    }

    fn log2_value(&self, cell: Cell) -> f64 {
        if self.topo.contains(cell) {
            self.cur[self.topo.index(cell)].log2()
        } else {
            f64::NEG_INFINITY
        }
    }

    fn value(&self, cell: Cell) -> f64 {
        if self.topo.contains(cell) {
            self.cur[self.topo.index(cell)]
        } else {
            0.0
        }
    }
}

impl NeuralDynamics for ReferenceMap {
    fn build(&mut self, target: Cell, stop: StopRule) -> Result<BuildReport, Error> {
        self.check_free(target, Role::Target)?;
        self.check_stop(&stop)?;
        self.cur.fill(0.0);
        self.next.fill(0.0);
        self.cur[self.topo.index(target)] = 1.0;
        self.target = Some(target);
        let cap = self.options.sweep_cap(self.cur.len());
        Ok(driver::run(self, stop, cap))
    }

    fn continue_sweeps(&mut self, stop: StopRule) -> Result<BuildReport, Error> {
        if self.target.is_none() {
            return Err(Error::option(
                "target",
                "build the map before continuing it",
            ));
        }
        self.check_stop(&stop)?;
        let cap = self.options.sweep_cap(self.cur.len());
        Ok(driver::run(self, stop, cap))
    }

    fn add_obstacles(&mut self, cells: &[Cell]) -> Result<(), Error> {
        for &cell in cells {
            check_inside(cell, Role::Obstacle, self.topo.width, self.topo.height)?;
            if Some(cell) == self.target {
                return Err(Error::Blocked {
                    role: Role::Target,
                    cell,
                });
            }
        }
        for &cell in cells {
            let i = self.topo.index(cell);
            self.topo.blocked[i] = true;
            self.cur[i] = 0.0;
            self.next[i] = 0.0;
        }
        // A cell's links and denominator depend only on its 3x3 neighbourhood.
        for &cell in cells {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    if let Some(c) = cell.offset(dx, dy).filter(|&c| self.topo.contains(c)) {
                        self.refresh(self.topo.index(c));
                    }
                }
            }
        }
        Ok(())
    }
}
