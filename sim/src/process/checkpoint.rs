//! The sim's restart checkpoint, `DIR/sim.ckpt`: the period counter and the world's dynamic
//! state ([`World::write_snapshot`]) after each stepped period.
//!
//! A sample does not outlive its publisher in iceoryx2, so what the sim last published cannot
//! be read back from shared memory by its successor: it is kept in a file instead. Unlike the
//! agents' fixed-size checkpoint (rewritten in place), the world's state grows with its
//! collisions, so each checkpoint is written whole to `sim.ckpt.tmp` and renamed over
//! `sim.ckpt`: a SIGKILL at any instant leaves the previous one or the new one, never a mix.
//! No fsync: the page cache survives the process's death, which is the failure this is for.
//! A checksum over the file rejects a torn or foreign one; the scenario hash ties it to its
//! run's scenario.
//!
//! Written after a period is stepped and before its odometry and truth are published, so that
//! a restarted sim never resumes behind what the agents have seen (their tick counters never
//! go back); it publishes that period's odometry and truth again on resuming, in case its
//! predecessor died between the two (the agents drop a reading of a period they have).

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use hnav_runtime::hash::Fnv1a64;

use crate::world::World;

const MAGIC: u64 = 0x4b43_5341_4e48_0001; // "HNASCK" v1
/// Header words: magic, scenario hash, period.
const HEADER: usize = 3 * 8;

/// What a checkpoint file restores.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Restored {
    /// The period counter: periods stepped so far (the last one published is this minus 1).
    pub period: u64,
}

/// Why a checkpoint could not be used.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// The file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// The file does not hold a checkpoint of this scenario.
    #[error("{path}: {what}")]
    Unusable {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        what: String,
    },
}

/// The sim's checkpoint file in a run directory, with the buffer it is encoded in (reused,
/// so that a checkpoint allocates nothing once the buffer has grown).
pub struct SimCheckpoint {
    path: PathBuf,
    tmp: PathBuf,
    scenario_hash: u64,
    buf: Vec<u8>,
}

impl SimCheckpoint {
    /// The checkpoint of a run of the scenario with hash `scenario_hash` in `run_dir`.
    pub fn in_dir(run_dir: &Path, scenario_hash: u64) -> Self {
        Self {
            path: run_dir.join("sim.ckpt"),
            tmp: run_dir.join("sim.ckpt.tmp"),
            scenario_hash,
            buf: Vec::new(),
        }
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes the checkpoint of `world` with `period` periods stepped.
    pub fn store(&mut self, world: &World, period: u64) -> Result<(), CheckpointError> {
        self.buf.clear();
        for w in [MAGIC, self.scenario_hash, period] {
            self.buf.extend_from_slice(&w.to_le_bytes());
        }
        world.write_snapshot(&mut self.buf);
        let sum = Fnv1a64::new().bytes(&self.buf).finish();
        self.buf.extend_from_slice(&sum.to_le_bytes());
        let written = File::create(&self.tmp)
            .and_then(|mut f| f.write_all(&self.buf))
            .and_then(|()| std::fs::rename(&self.tmp, &self.path));
        written.map_err(|source| CheckpointError::Io {
            path: self.path.clone(),
            source,
        })
    }

    /// Restores `world` from the checkpoint, if there is one: `Ok(None)` when the file does
    /// not exist (the sim died before it stepped a period), an error when it exists but
    /// cannot be used (a restarted sim must not silently start its robots over).
    pub fn load(&self, world: &mut World) -> Result<Option<Restored>, CheckpointError> {
        let bytes = match std::fs::read(&self.path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(source) => {
                return Err(CheckpointError::Io {
                    path: self.path.clone(),
                    source,
                })
            }
        };
        let unusable = |what: String| CheckpointError::Unusable {
            path: self.path.clone(),
            what,
        };
        let Some((body, sum)) = bytes
            .split_last_chunk::<8>()
            .filter(|(body, _)| body.len() >= HEADER)
        else {
            return Err(unusable("too short for a sim checkpoint".into()));
        };
        if Fnv1a64::new().bytes(body).finish() != u64::from_le_bytes(*sum) {
            return Err(unusable("checksum mismatch (torn or damaged)".into()));
        }
        let word = |i: usize| {
            let mut w = [0u8; 8];
            w.copy_from_slice(&body[8 * i..8 * i + 8]);
            u64::from_le_bytes(w)
        };
        if word(0) != MAGIC {
            return Err(unusable("not a sim checkpoint of this version".into()));
        }
        if word(1) != self.scenario_hash {
            return Err(unusable("written for another scenario".into()));
        }
        world
            .restore_snapshot(&body[HEADER..])
            .map_err(|e| unusable(format!("world state {e}")))?;
        Ok(Some(Restored { period: word(2) }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::grid::geometry::cell_centre_pose;
    use hnav_runtime::grid::{Cell, Grid};
    use hnav_runtime::scenario::params::{RobotParams, SimParams};

    fn world() -> World {
        let robot = RobotParams::default();
        let start = cell_centre_pose(robot.cell_size_m, Cell::new(1, 1), 0.0);
        World::new(
            &robot,
            &SimParams::default(),
            Grid::new(6, 4).unwrap(),
            &[start],
        )
        .unwrap()
    }

    #[test]
    fn a_checkpoint_round_trips_and_a_damaged_or_foreign_one_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let mut w = world();
        w.apply_command(0, 0, 5.0, 4.0, 0).unwrap();
        for _ in 0..30 {
            w.step();
        }
        let mut ck = SimCheckpoint::in_dir(dir.path(), 7);
        let mut fresh = world();
        assert_eq!(ck.load(&mut fresh).unwrap(), None, "no file yet");
        ck.store(&w, 3).unwrap();
        assert_eq!(ck.load(&mut fresh).unwrap(), Some(Restored { period: 3 }));
        assert_eq!(fresh.pose(0), w.pose(0));
        assert_eq!(fresh.ticks(0), w.ticks(0));
        assert!(!dir.path().join("sim.ckpt.tmp").exists());

        let other = SimCheckpoint::in_dir(dir.path(), 8);
        let err = other.load(&mut world()).unwrap_err().to_string();
        assert!(
            err.ends_with("sim.ckpt: written for another scenario"),
            "{err}"
        );
        let mut bytes = std::fs::read(ck.path()).unwrap();
        bytes[30] ^= 4;
        std::fs::write(ck.path(), &bytes).unwrap();
        let err = ck.load(&mut world()).unwrap_err().to_string();
        assert!(err.contains("checksum mismatch"), "{err}");
        std::fs::write(ck.path(), b"x").unwrap();
        let err = ck.load(&mut world()).unwrap_err().to_string();
        assert!(err.contains("too short"), "{err}");
    }
}
