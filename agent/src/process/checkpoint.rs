//! The agent's checkpoint: what a restarted agent needs to resume "from the committed state"
//! (ARCHITECTURE, Faults) — its row, its target and where its dead reckoning stood.
//!
//! A robot's controller would keep this in battery-backed RAM; here it is a small fixed-size
//! file rewritten in place (`pwrite` at offset 0, no fsync) after every control period. The
//! page cache survives the agent's SIGKILL, which is the failure this is for; a machine crash
//! ends the run anyway. A checksum over the record rejects a torn or foreign file, and a
//! restarted agent without a usable checkpoint starts from its scenario start.

use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use hnav_runtime::hash::Fnv1a64;
use hnav_runtime::msg::Pose;

const MAGIC: u64 = 0x4b43_5641_4e48_0001; // "HNAVCK" v1
const FIELDS: usize = 11;
const SIZE: usize = 8 * (FIELDS + 1);

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
    fn encode(&self) -> [u8; SIZE] {
        let words: [u64; FIELDS] = [
            MAGIC,
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
        ];
        let mut out = [0u8; SIZE];
        let mut h = Fnv1a64::new();
        for (i, w) in words.iter().enumerate() {
            out[8 * i..8 * i + 8].copy_from_slice(&w.to_le_bytes());
            h.u64(*w);
        }
        out[8 * FIELDS..].copy_from_slice(&h.finish().to_le_bytes());
        out
    }

    fn decode(b: &[u8]) -> Option<Checkpoint> {
        if b.len() != SIZE {
            return None;
        }
        let word = |i: usize| u64::from_le_bytes(b[8 * i..8 * i + 8].try_into().unwrap_or([0; 8]));
        let mut h = Fnv1a64::new();
        h.bytes(&b[..8 * FIELDS]);
        if word(0) != MAGIC || word(FIELDS) != h.finish() {
            return None;
        }
        let cell = |i: usize| u32::try_from(word(i)).ok();
        Some(Checkpoint {
            period: word(1),
            ticks_left: word(2) as i64,
            ticks_right: word(3) as i64,
            pose: Pose {
                x_m: f64::from_bits(word(4)),
                y_m: f64::from_bits(word(5)),
                theta_rad: f64::from_bits(word(6)),
            },
            current: cell(7)?,
            next: cell(8)?,
            target: cell(9)?,
            last_commit: word(10),
        })
    }
}

/// The checkpoint file of one agent.
pub struct CheckpointFile {
    path: PathBuf,
    file: File,
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
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)?;
        Ok(CheckpointFile {
            path: path.to_path_buf(),
            file,
        })
    }

    /// The stored checkpoint, if the file holds a valid one.
    pub fn load(&self) -> Option<Checkpoint> {
        let mut buf = [0u8; SIZE];
        self.file.read_exact_at(&mut buf, 0).ok()?;
        Checkpoint::decode(&buf)
    }

    /// Overwrites the stored checkpoint (one write, no allocation).
    pub fn store(&self, c: &Checkpoint) -> std::io::Result<()> {
        self.file.write_all_at(&c.encode(), 0)
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
        let mut b = sample().encode();
        for i in [0, 9, 40, SIZE - 1] {
            b[i] ^= 0x10;
            assert_eq!(Checkpoint::decode(&b), None, "byte {i}");
            b[i] ^= 0x10;
        }
        assert_eq!(Checkpoint::decode(&b[..SIZE - 1]), None);
        assert_eq!(Checkpoint::decode(&b), Some(sample()));
    }
}
