//! The dissertation's guide: a neural map toward the target, climbed one cell at a time by
//! the path constructor (`planner = "hnav"`).

use hnav_runtime::grid::{Cell, CornerCutting, Direction, Grid};
use hnav_runtime::msg::ActivationKind;

use super::sense::{RepairKind, PARTIAL_SWEEPS};
use super::Proposal;
use crate::error::Error;
use crate::neural_map::repair::{partial_correction, path_hits};
use crate::neural_map::{BuildReport, NeuralDynamics, NeuralMap, Outcome, StopRule};
use crate::path_constructor::{DirectionMask, PathConstructor, PathOptions, Walker};
use crate::plan::{PlanOptions, PlanStop};
use hnav_runtime::scenario::RepairRule;

/// The neural map, its last build, and the walker that climbs it.
pub(super) struct Climb {
    map: NeuralMap,
    report: BuildReport,
    constructor: PathConstructor,
    walker: Walker,
    mask: DirectionMask,
}

impl Climb {
    /// A map of `grid` built toward `target`, climbed from `from`.
    pub(super) fn new(
        grid: &Grid,
        corner_cutting: CornerCutting,
        from: Cell,
        target: Cell,
    ) -> Result<Climb, Error> {
        let options = PlanOptions {
            stop: PlanStop::Full,
            corner_cutting,
            ..PlanOptions::default()
        };
        let mut map = NeuralMap::new(grid, options.map_options())?;
        let report = map.build(target, StopRule::FullActivation)?;
        let constructor = PathConstructor::new(PathOptions {
            heading_bonus: true,
            ..PathOptions::default()
        })?;
        Ok(Climb {
            map,
            report,
            constructor,
            walker: Walker::new(grid.width(), grid.height(), from),
            mask: DirectionMask::default(),
        })
    }

    /// One step up the map from the walker's cell, the directions refused last round masked
    /// out. Right after a block a step down is allowed: the sidestep of a yielding robot.
    pub(super) fn propose(&mut self, grid: &Grid, current: Cell) -> Proposal {
        let mask = std::mem::take(&mut self.mask);
        let (dir, g) = self.walker.propose(&self.constructor, &self.map, mask);
        match dir {
            Some(d) if g.values[d.index()] > 0.0 || mask.0 != 0 => {
                grid.step(current, d).map_or(Proposal::Wait, Proposal::Step)
            }
            _ => Proposal::Extremum,
        }
    }

    /// Whether the last build says the target cannot be reached from where the wave got.
    pub(super) fn no_path(&self) -> bool {
        matches!(
            self.report.outcome,
            Outcome::Unreachable | Outcome::SweepLimit
        )
    }

    /// An accepted move in direction `dir`; `chosen` when the coordinator picked the cell
    /// (PIBT), after which the climb starts afresh from it.
    pub(super) fn accepted(&mut self, dir: Direction, chosen: bool) {
        self.walker.advance(dir);
        if chosen {
            self.walker.forget_visited();
        }
    }

    /// The coordinator refused these directions (bit `d` = direction `d`).
    pub(super) fn refused(&mut self, refused: u8) {
        self.mask = DirectionMask(self.mask.0 | refused);
    }

    /// `cell` has become an obstacle: the map learns it and is rebuilt toward `target`.
    pub(super) fn learn_obstacle(&mut self, cell: Cell, target: Cell) -> Result<(), Error> {
        self.map.add_obstacles(&[cell])?;
        self.report = self.map.build(target, StopRule::FullActivation)?;
        Ok(())
    }

    /// Repairs the map after `closed` cells closed (and others opened, if `opened`) in
    /// `grid`, the robot at `from` heading for `target`, as `rule` says (`sense.rs`).
    pub(super) fn repair(
        &mut self,
        grid: &Grid,
        closed: &[Cell],
        opened: bool,
        (from, target): (Cell, Cell),
        rule: RepairRule,
    ) -> Result<RepairKind, Error> {
        let rebuild = opened
            || match rule {
                RepairRule::Rebuild => true,
                RepairRule::Partial => false,
                RepairRule::Auto => self
                    .constructor
                    .trace(&self.map, from)
                    .map_or(true, |p| path_hits(&p.cells, closed)),
            };
        if rebuild {
            self.map = NeuralMap::new(grid, *self.map.options())?;
            self.report = self.map.build(target, StopRule::FullActivation)?;
            return Ok(RepairKind::Rebuild);
        }
        self.report = partial_correction(&mut self.map, closed, PARTIAL_SWEEPS)?;
        Ok(RepairKind::Partial)
    }

    /// A new map of `grid` toward `target`, climbed afresh from `from`.
    pub(super) fn retarget(&mut self, grid: &Grid, from: Cell, target: Cell) -> Result<(), Error> {
        self.map = NeuralMap::new(grid, *self.map.options())?;
        self.report = self.map.build(target, StopRule::FullActivation)?;
        self.walker = Walker::new(grid.width(), grid.height(), from);
        self.mask = DirectionMask::default();
        Ok(())
    }

    /// Sweeps of the last build.
    pub(super) fn iterations(&self) -> u32 {
        self.report.sweeps
    }

    /// The map's activation function.
    pub(super) fn kind(&self) -> ActivationKind {
        self.map.options().activation.to_kind()
    }

    /// Writes the activations into `out`, one slot per cell.
    pub(super) fn write(&self, out: &mut [f32]) -> Result<(), Error> {
        self.map.write_values_f32(out)
    }

    /// The neural map.
    pub(super) fn map(&self) -> &NeuralMap {
        &self.map
    }
}
