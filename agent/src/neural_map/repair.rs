//! Repairing a map when obstacles appear (§2.10).
//!
//! * **A, partial correction**: zero the new obstacles' neurons in the current map and run `n`
//!   more sweeps starting from it (not from zero). Cheap; the larger `n`, the wider the
//!   reduced-potential zone around the new obstacle and the earlier the path bends away from it
//!   (§2.10's Fig. 2-17: `n = 1` and `n = 5` on 20 x 20).
//! * **Б, new map with partial activation**: rebuild from zero with the new obstacles, stopping
//!   as soon as the robot's neuron is on (13 instead of 19 sweeps on the Fig. 2-16 maze).
//!
//! Both work on either implementation through [`NeuralDynamics`].

use hnav_runtime::grid::Cell;

use super::{BuildReport, NeuralDynamics, StopRule};
use crate::error::Error;

/// §2.10 A: blocks `new_obstacles`, zeroes their neurons and runs `sweeps` more sweeps from the
/// current map. The map must have been built.
pub fn partial_correction<M: NeuralDynamics + ?Sized>(
    map: &mut M,
    new_obstacles: &[Cell],
    sweeps: u32,
) -> Result<BuildReport, Error> {
    if map.target().is_none() {
        return Err(Error::option("map", "build the map before correcting it"));
    }
    map.add_obstacles(new_obstacles)?;
    map.continue_sweeps(StopRule::Sweeps(sweeps))
}

/// §2.10 Б: blocks `new_obstacles` and rebuilds the map for the same target from zero, stopping
/// when the neuron at `current` (the robot) is on. The map must have been built.
pub fn rebuild_partial<M: NeuralDynamics + ?Sized>(
    map: &mut M,
    new_obstacles: &[Cell],
    current: Cell,
) -> Result<BuildReport, Error> {
    let Some(target) = map.target() else {
        return Err(Error::option("map", "build the map before rebuilding it"));
    };
    map.add_obstacles(new_obstacles)?;
    map.build(target, StopRule::PartialActivation { start: current })
}

/// Whether any of `obstacles` lies on `path`: §2.10 Б rebuilds only then.
pub fn path_hits(path: &[Cell], obstacles: &[Cell]) -> bool {
    path.iter().any(|c| obstacles.contains(c))
}
