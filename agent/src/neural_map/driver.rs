//! The stop rules, written once for both implementations.
//!
//! An engine computes one synchronous sweep into its back buffer and reports counts; the
//! driver decides whether to keep (commit) that sweep and when to stop. Full activation is
//! "every reachable free neuron is on"; the driver needs no reachability search for it: the
//! set of non-zero neurons grows by exactly the cells one link away each sweep, so a sweep
//! that turns no new neuron non-zero proves the previous state already covered every reachable
//! neuron. That check sweep is then discarded (not committed), so the returned map is the
//! state after exactly the reported number of sweeps.

use hnav_runtime::grid::Cell;

use super::{BuildReport, Outcome, StopRule};

/// Counts over one sweep's result (the back buffer), target included.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SweepStats {
    /// Neurons that were 0 and are now positive.
    pub newly_on: u64,
    /// Neurons that are positive.
    pub nonzero: u64,
    /// Neurons above the on-threshold.
    pub above: u64,
    /// Free non-target neurons whose value changed at all.
    pub changed: u64,
    /// Largest absolute change of a free non-target neuron (only when asked for).
    pub max_delta: f64,
    /// Neuron updates computed.
    pub cells: u64,
}

/// One implementation's sweep machinery.
pub(crate) trait SweepEngine {
    /// Computes one sweep from the current state into the back buffer.
    fn sweep(&mut self, want_delta: bool) -> SweepStats;
    /// Makes the back buffer current.
    fn commit(&mut self);
    /// `(nonzero, above)` over the current state.
    fn counts(&self) -> (u64, u64);
    /// Whether an inside cell is above the on-threshold in the current state.
    fn is_above(&self, cell: Cell) -> bool;
    /// Whether an inside cell is positive in the current state.
    fn is_nonzero(&self, cell: Cell) -> bool;
}

/// Sweeps `engine` until `stop` holds or `cap` sweeps have been kept.
pub(crate) fn run<E: SweepEngine>(engine: &mut E, stop: StopRule, cap: u32) -> BuildReport {
    let (mut nonzero_prev, mut above_prev) = engine.counts();
    let mut sweeps = 0u32;
    let mut cells_updated = 0u64;
    let report = |sweeps, outcome, cells_updated, cells_on| BuildReport {
        sweeps,
        outcome,
        cells_updated,
        cells_on,
    };
    match stop {
        StopRule::PartialActivation { start } if engine.is_above(start) => {
            return report(0, Outcome::StartReached, 0, above_prev);
        }
        StopRule::Sweeps(0) => return report(0, Outcome::SweepsDone, 0, above_prev),
        _ => {}
    }
    loop {
        if sweeps >= cap {
            return report(sweeps, Outcome::SweepLimit, cells_updated, above_prev);
        }
        let s = engine.sweep(matches!(stop, StopRule::Converged { .. }));
        cells_updated += s.cells;
        let grew = s.newly_on > 0;
        if let StopRule::FullActivation = stop {
            if !grew && above_prev == nonzero_prev {
                // The check sweep found nothing new: the current state was complete.
                return report(sweeps, Outcome::FullyActivated, cells_updated, above_prev);
            }
        }
        engine.commit();
        sweeps += 1;
        let done = match stop {
            StopRule::FullActivation => {
                (!grew && s.above == s.nonzero).then_some(Outcome::FullyActivated)
            }
            StopRule::PartialActivation { start } => {
                if engine.is_above(start) {
                    Some(Outcome::StartReached)
                } else if !grew && !engine.is_nonzero(start) {
                    Some(Outcome::Unreachable)
                } else {
                    None
                }
            }
            StopRule::Converged { tolerance } => {
                (s.changed == 0 || s.max_delta < tolerance).then_some(Outcome::Converged)
            }
            StopRule::Sweeps(n) => (sweeps >= n).then_some(Outcome::SweepsDone),
        };
        if let Some(outcome) = done {
            return report(sweeps, outcome, cells_updated, s.above);
        }
        nonzero_prev = s.nonzero;
        above_prev = s.above;
    }
}
