//! What the report draws of a changing world beyond the log's map changes: the movers'
//! tracks, and the cells the robots' range sensors saw during the run.
//!
//! Both come from the recording. The sensed area is the union of every robot's view,
//! rebuilt with [`RecordedWorld`] (the sim's line of sight on the map as the scenario's
//! events had changed it by then, movers blocking the cells of their centres), from the
//! recorded truth each time a robot entered another cell or the map changed: a view is a
//! function of the robot's cell and the world, so that is where the union can grow. It needs
//! the scenario (its sensor range and events), read through `invocation.json` when it still
//! hashes as the log says.

use std::path::Path;

use hnav_runtime::grid::Grid;
use hnav_runtime::msg::View;

use super::RunData;
use crate::invocation::Invocation;
use crate::recording::world::{world_steps, RecordedWorld};
use crate::recording::{PoseSource, TrajectoryReader};
use crate::report::ReportError;

impl RunData {
    /// The movers' tracks and, when the run sensed, the sensed cells, from the recording
    /// `trajectories` of the run in `dir` (cells of `cell_size` m).
    pub(super) fn read_world(
        &mut self,
        dir: &Path,
        trajectories: &Path,
        cell_size: f64,
    ) -> Result<(), ReportError> {
        let scenario = match Invocation::logged_scenario(dir, self.scenario_hash) {
            Ok(s) => Some(s),
            // A run directory without invocation.json (made by hand) says nothing of a world.
            Err(_) if !dir.join(crate::invocation::FILE).exists() => None,
            Err(why) => {
                self.notes.push(format!("no sensed area drawn: {why}"));
                None
            }
        };
        let start = Grid::from_blocked(self.width, self.height, &self.blocked).ok();
        // The world to sense in, when the run sensed.
        let mut sensing = match (&scenario, start) {
            (Some(s), Some(grid)) => s.sensing.map(|sensing| {
                let steps = world_steps(s, &grid);
                (sensing.range, RecordedWorld::new(grid, steps, cell_size))
            }),
            _ => None,
        };
        if sensing.is_some() {
            self.sensed = vec![false; self.blocked.len()];
        }
        let mut r = TrajectoryReader::open(trajectories)?;
        self.movers = vec![Vec::new(); usize::from(r.header().movers)];
        // Per robot: the cell its view was last taken from, and the world's epoch then.
        let mut last: Vec<Option<(u32, u32, u64)>> = vec![None; self.starts.len()];
        let (mut epoch, mut view) = (0u64, View::default());
        while let Some(s) = r.next_sample()? {
            let pose = s.pose();
            match s.source {
                PoseSource::Mover => {
                    if let Some(track) = self.movers.get_mut(usize::from(s.robot)) {
                        track.push((pose.x_m / cell_size, pose.y_m / cell_size));
                    }
                    if let Some((_, world)) = &mut sensing {
                        world.place_mover(u32::from(s.robot), pose);
                    }
                }
                PoseSource::Truth => {
                    let Some((range, world)) = &mut sensing else {
                        continue;
                    };
                    let range = *range;
                    epoch += u64::from(world.advance(s.t_ns));
                    let Some(cell) = world.cell_of(&pose) else {
                        continue;
                    };
                    let key = Some((cell.x, cell.y, epoch));
                    let Some(seen) = last.get_mut(usize::from(s.robot)) else {
                        continue;
                    };
                    if *seen == key {
                        continue;
                    }
                    *seen = key;
                    world.fill_view(u32::from(s.robot), &pose, range, s.t_ns, &mut view);
                    for (x, y, _) in view.cells() {
                        if let Some(v) = self.sensed.get_mut((y * self.width + x) as usize) {
                            *v = true;
                        }
                    }
                }
                PoseSource::Estimate => {}
            }
        }
        Ok(())
    }
}
