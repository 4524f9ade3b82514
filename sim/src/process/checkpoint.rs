//! The sim's restart checkpoint: the period counter and the world's dynamic state
//! ([`World::write_snapshot`]) after each stepped period, in two slot files `DIR/sim.ckpt.0`
//! and `DIR/sim.ckpt.1`.
//!
//! A sample does not outlive its publisher in iceoryx2, so what the sim last published cannot
//! be read back from shared memory by its successor: it is kept in a file instead.
//!
//! **Why two slots rewritten in place.** The checkpoint is written in the sim's control loop,
//! every period, so its cost is the loop's. It used to be written whole to a temporary file
//! and renamed over the last one: a file created, an inode freed and a directory changed per
//! period, each a journal transaction, and on ext4 the rename over an existing file also
//! starts the new file's write-back. Under a busy disk (other runs' consensus logs fsyncing
//! every record) one such checkpoint took 100–440 ms and the sim, stuck in the kernel,
//! missed its heartbeat and was SIGKILLed as hung (`tests/tests/rogue.rs`'s flood runs). Now
//! period `p` is written with one `pwrite` at offset 0 of slot `p % 2`, both files opened
//! once: a page-cache copy and no metadata change but the file times.
//!
//! A SIGKILL can cut a write short (the kernel checks for a fatal signal between pages), so
//! a slot can be torn; then it is the slot being written, and the other one holds the
//! period before, complete. Each slot carries its length and a checksum (a
//! [`SlotPair`] of the durable toolkit); [`SimCheckpoint::load`] takes the newest usable one. No fsync: the page cache survives the process's death, which
//! is the failure this is for. The scenario hash ties a slot to its run's scenario.
//!
//! Written after a period is stepped and before its odometry and truth are published, so that
//! a restarted sim never resumes behind what the agents have seen (their tick counters never
//! go back); it publishes that period's odometry and truth again on resuming, in case its
//! predecessor died between the two (the agents drop a reading of a period they have). A
//! torn slot of period `p` means the sim died before publishing `p`, so resuming from `p - 1`
//! is exact.

use std::path::{Path, PathBuf};

use hnav_runtime::durable::{PairError, SlotLayout, SlotLen, SlotPair};

use crate::world::World;

/// The slot: magic `"HNASCK"` v2 (slots with a length), then the scenario hash, the period,
/// the world state's length and the world state; FNV-1a 64.
const LAYOUT: SlotLayout = SlotLayout {
    magic: 0x4b43_5341_4e48_0002,
    what: "sim checkpoint",
    len: SlotLen::Stored { at: 16, base: 24 },
};
/// Payload bytes before the world state: scenario hash, period, world state length.
const BASE: usize = 3 * 8;
/// The slot files, by period parity.
pub const SLOT_FILES: [&str; 2] = ["sim.ckpt.0", "sim.ckpt.1"];

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

impl From<PairError> for CheckpointError {
    fn from(e: PairError) -> Self {
        match e {
            PairError::Io { path, source } => Self::Io { path, source },
            PairError::Unusable { path, what } => Self::Unusable { path, what },
        }
    }
}

/// The sim's checkpoint slots in a run directory (whose buffer is reused, so that a
/// checkpoint allocates nothing once it has grown).
pub struct SimCheckpoint {
    slots: SlotPair,
    scenario_hash: u64,
}

impl SimCheckpoint {
    /// The checkpoint of a run of the scenario with hash `scenario_hash` in `run_dir`.
    pub fn in_dir(run_dir: &Path, scenario_hash: u64) -> Self {
        Self {
            slots: SlotPair::new(SLOT_FILES.map(|f| run_dir.join(f)), LAYOUT),
            scenario_hash,
        }
    }

    /// The slot file period `period` is written to.
    pub fn path(&self, period: u64) -> &Path {
        self.slots.path(period)
    }

    /// Writes the checkpoint of `world` with `period` periods stepped, into slot `period % 2`.
    pub fn store(&mut self, world: &World, period: u64) -> Result<(), CheckpointError> {
        let hash = self.scenario_hash;
        self.slots
            .store(period, |buf| {
                // The world state's length (0 here) is filled in by the slot.
                for w in [hash, period, 0] {
                    buf.extend_from_slice(&w.to_le_bytes());
                }
                world.write_snapshot(buf);
            })
            .map_err(|source| CheckpointError::Io {
                path: self.slots.path(period).to_path_buf(),
                source,
            })
    }

    /// Restores `world` from the newest usable slot, if there is one: `Ok(None)` when no slot
    /// exists (the sim died before it stepped a period), an error when a slot exists but none
    /// can be used (a restarted sim must not silently start its robots over).
    pub fn load(&self, world: &mut World) -> Result<Option<Restored>, CheckpointError> {
        let hash = self.scenario_hash;
        let accept = |payload: &[u8]| {
            if word(payload, 0) != hash {
                return Err("written for another scenario".to_string());
            }
            Ok(word(payload, 1))
        };
        let Some(newest) = self.slots.load(accept)? else {
            return Ok(None);
        };
        world
            .restore_snapshot(&newest.payload[BASE..])
            .map_err(|e| CheckpointError::Unusable {
                path: newest.path.to_path_buf(),
                what: format!("world state {e}"),
            })?;
        Ok(Some(Restored { period: newest.seq }))
    }
}

/// The little-endian word `i` of a slot's payload (which holds it: the slot checked its
/// length).
fn word(payload: &[u8], i: usize) -> u64 {
    let mut w = [0u8; 8];
    w.copy_from_slice(&payload[8 * i..8 * i + 8]);
    u64::from_le_bytes(w)
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::grid::geometry::cell_centre_pose;
    use hnav_runtime::grid::{Cell, Grid};
    use hnav_runtime::scenario::params::{RobotParams, SimParams};
    use std::os::unix::fs::FileExt;

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

    fn stepped(periods: usize) -> World {
        let mut w = world();
        w.apply_command(0, 0, 5.0, 4.0, 0).unwrap();
        for _ in 0..periods {
            w.step();
        }
        w
    }

    #[test]
    fn a_checkpoint_round_trips_through_alternating_slots() {
        let dir = tempfile::tempdir().unwrap();
        let mut ck = SimCheckpoint::in_dir(dir.path(), 7);
        let mut fresh = world();
        assert_eq!(ck.load(&mut fresh).unwrap(), None, "no slot yet");
        let (w3, w4) = (stepped(30), stepped(40));
        ck.store(&w3, 3).unwrap();
        assert_eq!(ck.load(&mut fresh).unwrap(), Some(Restored { period: 3 }));
        assert_eq!(fresh.pose(0), w3.pose(0));
        ck.store(&w4, 4).unwrap();
        assert_ne!(ck.path(3), ck.path(4), "consecutive periods use both slots");
        assert_eq!(ck.load(&mut fresh).unwrap(), Some(Restored { period: 4 }));
        assert_eq!(fresh.pose(0), w4.pose(0));
        assert_eq!(fresh.ticks(0), w4.ticks(0));
        // A shorter record over a longer one: its length, not the file's, bounds it.
        let long = std::fs::metadata(ck.path(4)).unwrap().len();
        std::fs::OpenOptions::new()
            .append(true)
            .open(ck.path(4))
            .unwrap()
            .write_all_at(&[0xAA; 64], long)
            .unwrap();
        assert_eq!(ck.load(&mut fresh).unwrap(), Some(Restored { period: 4 }));
    }

    /// The regression the slots fix: a checkpoint per period created a file, freed an inode
    /// and renamed, a journal transaction each, which stalled the sim for hundreds of
    /// milliseconds on a busy disk (see the module docs).
    #[test]
    fn a_checkpoint_rewrites_its_slot_in_place_and_creates_no_file() {
        use std::os::unix::fs::MetadataExt;
        let dir = tempfile::tempdir().unwrap();
        let mut ck = SimCheckpoint::in_dir(dir.path(), 7);
        ck.store(&stepped(10), 1).unwrap();
        ck.store(&stepped(20), 2).unwrap();
        let inodes =
            |ck: &SimCheckpoint| [1, 2].map(|p| std::fs::metadata(ck.path(p)).unwrap().ino());
        let before = inodes(&ck);
        for period in 3..40 {
            ck.store(&stepped(period as usize), period).unwrap();
        }
        assert_eq!(inodes(&ck), before, "the same two files, rewritten");
        let mut names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        names.sort();
        assert_eq!(names, SLOT_FILES);
    }

    #[test]
    fn a_torn_slot_falls_back_to_the_period_before() {
        let dir = tempfile::tempdir().unwrap();
        let mut ck = SimCheckpoint::in_dir(dir.path(), 7);
        let (w5, w6) = (stepped(50), stepped(60));
        ck.store(&w5, 5).unwrap();
        ck.store(&w6, 6).unwrap();
        // The write of period 6 cut short after its first bytes (a SIGKILL between pages).
        let mut torn = std::fs::read(ck.path(6)).unwrap();
        torn[40..].fill(0);
        std::fs::write(ck.path(6), &torn).unwrap();
        let mut fresh = world();
        assert_eq!(ck.load(&mut fresh).unwrap(), Some(Restored { period: 5 }));
        assert_eq!(fresh.pose(0), w5.pose(0));
    }

    #[test]
    fn damaged_or_foreign_slots_are_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let mut ck = SimCheckpoint::in_dir(dir.path(), 7);
        ck.store(&stepped(30), 3).unwrap();
        let other = SimCheckpoint::in_dir(dir.path(), 8);
        let err = other.load(&mut world()).unwrap_err().to_string();
        assert!(
            err.ends_with("sim.ckpt.1: written for another scenario"),
            "{err}"
        );
        let mut bytes = std::fs::read(ck.path(3)).unwrap();
        bytes[40] ^= 4;
        std::fs::write(ck.path(3), &bytes).unwrap();
        let err = ck.load(&mut world()).unwrap_err().to_string();
        assert!(err.contains("checksum mismatch"), "{err}");
        bytes[24..32].copy_from_slice(&u64::MAX.to_le_bytes());
        std::fs::write(ck.path(3), &bytes).unwrap();
        let err = ck.load(&mut world()).unwrap_err().to_string();
        assert!(err.contains("length beyond the file"), "{err}");
        std::fs::write(ck.path(3), b"x").unwrap();
        let err = ck.load(&mut world()).unwrap_err().to_string();
        assert!(err.contains("too short"), "{err}");
    }
}
