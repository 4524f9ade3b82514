//! A changing world as grids over time (`[[events]]`, `[sensing]`): the truth, `/map` again at
//! every close or open the sim applied, and the coordinator's picture, `/map/shared`, at every
//! map change it logged, on which the rounds from then on were decided. Side by side they show
//! how long the swarm took to learn each change. With `[sensing]`, `/map/sensed` has the floor
//! the robots' sensors see (`occupied` 1: seen by some robot), once a second of sim time,
//! rebuilt from the recording as the playback and the report rebuild it.

use std::path::Path;

use serde_json::Value;

use hnav_runtime::consensus_log::Record;
use hnav_runtime::grid::Grid;
use hnav_runtime::scenario::Scenario;

use crate::channels::messages::occupancy;
use crate::recording::world::{world_steps, RecordedWorld};
use crate::recording::{PoseSource, RecordingError, TrajectoryReader};
use hnav_runtime::msg::{Pose, View};

/// How often `/map/sensed` is written, ns of sim time.
const SENSED_EVERY_NS: u64 = 1_000_000_000;

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

/// What the robots' sensors see, once a second of sim time, from the recording at
/// `trajectories` of a run of `s` (which senses with `range`).
pub(super) fn sensed(
    s: &Scenario,
    range: u32,
    trajectories: &Path,
    cell_m: f64,
) -> Result<Vec<(u64, Value)>, RecordingError> {
    let grid = &s.map.grid;
    let mut world = RecordedWorld::new(grid.clone(), world_steps(s, grid), cell_m);
    let mut poses = vec![None::<Pose>; s.agents.len()];
    let (mut r, mut out) = (TrajectoryReader::open(trajectories)?, Vec::new());
    let (mut at, mut next_ns) = (None::<u64>, 0u64);
    let mut view = View::default();
    let mut seen = vec![false; grid.len()];
    let mut emit = |t: u64, world: &mut RecordedWorld, poses: &[Option<Pose>]| {
        world.advance(t);
        seen.iter_mut().for_each(|v| *v = false);
        for (i, p) in poses.iter().enumerate() {
            let Some(p) = p else { continue };
            world.fill_view(i as u32, p, range, t, &mut view);
            for (x, y, _) in view.cells() {
                if let Some(v) = seen.get_mut((y * grid.width() + x) as usize) {
                    *v = true;
                }
            }
        }
        if let Ok(g) = Grid::from_blocked(grid.width(), grid.height(), &seen) {
            out.push((t, occupancy(&g, t, cell_m)));
        }
    };
    while let Some(sample) = r.next_sample()? {
        match sample.source {
            PoseSource::Mover => world.place_mover(u32::from(sample.robot), sample.pose()),
            PoseSource::Truth => {
                // A new time: the last one's poses are complete (its movers came after them).
                if let Some(t) = at.filter(|&t| t != sample.t_ns && t >= next_ns) {
                    emit(t, &mut world, &poses);
                    next_ns = t + SENSED_EVERY_NS;
                }
                at = Some(sample.t_ns);
                if let Some(p) = poses.get_mut(usize::from(sample.robot)) {
                    *p = Some(sample.pose());
                }
            }
            PoseSource::Estimate => {}
        }
    }
    if let Some(t) = at {
        emit(t, &mut world, &poses);
    }
    Ok(out)
}
