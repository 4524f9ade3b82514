//! The agent's checkpoint: what a restarted agent needs to resume "from the committed state"
//! (ARCHITECTURE, Faults) — its row, its target and where its dead reckoning stood.
//!
//! A robot's controller would keep this in battery-backed RAM; here it is a small fixed-size
//! [slot](hnav_runtime::durable::slot) rewritten in place (`pwrite` at offset 0, no fsync)
//! after every control period. The page cache survives the agent's SIGKILL, which is the
//! failure this is for; a machine crash ends the run anyway. The slot's checksum rejects a
//! torn or foreign file, and a restarted agent without a usable checkpoint starts from its
//! scenario start.

use std::cell::RefCell;
use std::path::{Path, PathBuf};

use hnav_runtime::durable::{SlotFile, SlotLayout, SlotLen, SlotRead};
use hnav_runtime::msg::Pose;

/// The slot: magic `"HNAVCK" v1`, the ten words of a [`Checkpoint`], FNV-1a 64.
const LAYOUT: SlotLayout = SlotLayout {
    magic: 0x4b43_5641_4e48_0001,
    what: "agent checkpoint",
    len: SlotLen::Fixed(8 * FIELDS),
};
const FIELDS: usize = 10;

/// One agent's resumable state.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Checkpoint {
    /// Control period of the last odometry reading folded into `pose`.
    pub period: u64,
    /// Cumulative left ticks at `pose`.
    pub ticks_left: i64,
    /// Cumulative right ticks at `pose`.
    pub ticks_right: i64,
    /// The dead-reckoned pose.
    pub pose: Pose,
    /// Row: current cell index.
    pub current: u32,
    /// Row: next cell index.
    pub next: u32,
    /// The map's target cell index.
    pub target: u32,
    /// Last commit round applied.
    pub last_commit: u64,
}

impl Checkpoint {
    fn words(&self) -> [u64; FIELDS] {
        [
            self.period,
            self.ticks_left as u64,
            self.ticks_right as u64,
            self.pose.x_m.to_bits(),
            self.pose.y_m.to_bits(),
            self.pose.theta_rad.to_bits(),
            u64::from(self.current),
            u64::from(self.next),
            u64::from(self.target),
            self.last_commit,
        ]
    }

    /// The checkpoint in a slot's payload; `None` for a cell index beyond `u32`.
    fn decode(payload: &[u8]) -> Option<Checkpoint> {
        if payload.len() != 8 * FIELDS {
            return None;
        }
        let word = |i: usize| {
            let mut w = [0u8; 8];
            w.copy_from_slice(&payload[8 * i..8 * i + 8]);
            u64::from_le_bytes(w)
        };
        let cell = |i: usize| u32::try_from(word(i)).ok();
        Some(Checkpoint {
            period: word(0),
            ticks_left: word(1) as i64,
            ticks_right: word(2) as i64,
            pose: Pose {
                x_m: f64::from_bits(word(3)),
                y_m: f64::from_bits(word(4)),
                theta_rad: f64::from_bits(word(5)),
            },
            current: cell(6)?,
            next: cell(7)?,
            target: cell(8)?,
            last_commit: word(9),
        })
    }
}

/// The checkpoint file of one agent.
pub struct CheckpointFile {
    slot: RefCell<SlotFile>,
    path: PathBuf,
}

impl CheckpointFile {
    /// The path of agent `index`'s checkpoint under a run directory.
    pub fn path_in(run_dir: &Path, index: u32) -> PathBuf {
        run_dir.join("agents").join(format!("{index}.ckpt"))
    }

    /// Opens (creating) the file.
    pub fn open(path: &Path) -> std::io::Result<Self> {
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        let mut slot = SlotFile::new(path, LAYOUT);
        slot.open()?;
        Ok(CheckpointFile {
            slot: RefCell::new(slot),
            path: path.to_path_buf(),
        })
    }

    /// The stored checkpoint, if the file holds a valid one.
    pub fn load(&self) -> Option<Checkpoint> {
        match self.slot.borrow().load().ok()? {
            SlotRead::Usable(payload) => Checkpoint::decode(&payload),
            SlotRead::Missing | SlotRead::Unusable(_) => None,
        }
    }

    /// Overwrites the stored checkpoint (one write, no allocation).
    pub fn store(&self, c: &Checkpoint) -> std::io::Result<()> {
        self.slot.borrow_mut().store(|buf| {
            for w in c.words() {
                buf.extend_from_slice(&w.to_le_bytes());
            }
        })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Checkpoint {
        Checkpoint {
            period: 77,
            ticks_left: -12,
            ticks_right: 345,
            pose: Pose {
                x_m: 1.25,
                y_m: -0.5,
                theta_rad: 3.0,
            },
            current: 5,
            next: 6,
            target: 99,
            last_commit: 76,
        }
    }

    #[test]
    fn round_trips_through_a_file() {
        let dir = tempfile::tempdir().unwrap();
        let f = CheckpointFile::open(&CheckpointFile::path_in(dir.path(), 3)).unwrap();
        assert_eq!(f.load(), None);
        f.store(&sample()).unwrap();
        assert_eq!(f.load(), Some(sample()));
    }

    #[test]
    fn a_damaged_record_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = CheckpointFile::path_in(dir.path(), 0);
        let f = CheckpointFile::open(&path).unwrap();
        f.store(&sample()).unwrap();
        let good = std::fs::read(&path).unwrap();
        assert_eq!(
            good.len(),
            96,
            "magic, ten words, checksum: the format of before"
        );
        for i in [0, 9, 40, 95] {
            let mut b = good.clone();
            b[i] ^= 0x10;
            std::fs::write(&path, &b).unwrap();
            assert_eq!(f.load(), None, "byte {i}");
        }
        std::fs::write(&path, &good[..95]).unwrap();
        assert_eq!(f.load(), None);
        std::fs::write(&path, &good).unwrap();
        assert_eq!(f.load(), Some(sample()));
    }

    /// The bytes of a checkpoint as the agent wrote them before the slot was shared with the
    /// sim: old files stay readable.
    #[test]
    fn the_slot_bytes_are_those_of_before() {
        let c = sample();
        let mut words = vec![0x4b43_5641_4e48_0001u64];
        words.extend(c.words());
        let mut h = hnav_runtime::hash::Fnv1a64::new();
        for w in &words {
            h.u64(*w);
        }
        words.push(h.finish());
        let old: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.ckpt");
        std::fs::write(&path, &old).unwrap();
        let f = CheckpointFile::open(&path).unwrap();
        assert_eq!(f.load(), Some(c));
        f.store(&c).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), old);
    }
}
