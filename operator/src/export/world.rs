//! A changing world as grids over time (`[[events]]`, `[sensing]`): the truth, `/map` again at
//! every close or open the sim applied, and the coordinator's picture, `/map/shared`, at every
//! map change it logged, on which the rounds from then on were decided. Side by side they show
//! how long the swarm took to learn each change.

use serde_json::Value;

use hnav_runtime::consensus_log::Record;
use hnav_runtime::grid::Grid;
use hnav_runtime::scenario::Scenario;

use crate::channels::messages::occupancy;

/// The true map after each close or open of `s`'s events, at its time (the sim applies an
/// event at the first step at or after it, within a control period of this).
pub(super) fn truth(s: &Scenario, cell_m: f64) -> Vec<(u64, Value)> {
    let mut g = s.map.grid.clone();
    let mut out = Vec::new();
    for e in &s.events {
        let Some((cells, close)) = e.change.cells() else {
            continue;
        };
        for &c in cells {
            g.set_blocked(c, close);
        }
        let t = (e.at_s * 1e9).round() as u64;
        out.push((t, occupancy(&g, t, cell_m)));
    }
    out
}

/// The coordinator's map at the start and after each map-change record of `records`, at its
/// round's time.
pub(super) fn shared(
    start: &Grid,
    records: &[Record],
    period_ns: u64,
    cell_m: f64,
) -> Vec<(u64, Value)> {
    let mut g = start.clone();
    let mut out = vec![(0, occupancy(&g, 0, cell_m))];
    for r in records {
        let Record::MapChange(m) = r else { continue };
        for (c, close) in m.changes() {
            if let Some(cell) = g.cell_at(c as usize) {
                g.set_blocked(cell, close);
            }
        }
        let t = m.round.saturating_mul(period_ns);
        out.push((t, occupancy(&g, t, cell_m)));
    }
    out
}
