//! A run's recording on disk: what the robots did, in files that outlive the run.
//!
//! Live topics are superseding state ("latest"): once a run ends, nothing of where the robots
//! drove or what their neural maps looked like is left but the consensus log, which holds
//! decisions, not poses. The recorder (a thread of the supervisor, off every process's hot
//! path) samples the live topics and writes them here; the run report, the MCAP export and
//! the replay into `hnav top` read them back.
//!
//! | file in `DIR/recording/` | module | what it holds |
//! |---|---|---|
//! | [`TRAJECTORIES`] | [`trajectory`] | fixed 24-byte pose samples: ground truth and each agent's dead-reckoned estimate |
//! | [`MAPS`] | [`maps`] | neural-map snapshots, one checksummed frame each |
//!
//! Both are little-endian, start with an 8-byte magic whose last byte is the format version,
//! and are written append-only through a size cap: a sample beyond the cap is dropped and
//! counted, and [`trajectory::TrajectoryWriter::finish`] marks the file truncated, so a long
//! run cannot fill the disk. A writer killed mid-write leaves a torn tail, which the readers
//! report and skip rather than treat as corruption.

pub mod maps;
pub mod trajectory;

use std::path::PathBuf;

pub use maps::{MapReader, MapSnapshot, MapWriter};
pub use trajectory::{
    PoseSample, PoseSource, TrajectoryHeader, TrajectoryReader, TrajectoryWriter,
};

/// The recording's directory inside a run directory.
pub const DIR: &str = "recording";
/// The pose samples' file inside [`DIR`].
pub const TRAJECTORIES: &str = "trajectories.bin";
/// The neural-map snapshots' file inside [`DIR`].
pub const MAPS: &str = "maps.bin";

/// Every way reading or writing a recording can fail; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// An operating-system error on the file.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The file does not start with the format's magic (or is shorter than its header).
    #[error("{}: not an HNAV {what} file (bad magic or header)", path.display())]
    BadMagic {
        /// The file.
        path: PathBuf,
        /// `trajectory` or `neural-map`.
        what: &'static str,
    },
    /// The magic names a format version this build does not read.
    #[error("{}: {what} format version {version}, this build reads version {supported}", path.display())]
    Version {
        /// The file.
        path: PathBuf,
        /// `trajectory` or `neural-map`.
        what: &'static str,
        /// The file's version.
        version: u8,
        /// The version this build reads.
        supported: u8,
    },
    /// The bytes at `offset` are not a valid record (not a torn tail: more follows, or the
    /// record itself says something impossible).
    #[error("{}: at byte {offset}: {problem}", path.display())]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// Byte offset of the bad record.
        offset: u64,
        /// What is wrong.
        problem: String,
    },
}

/// Where a writer stands against its size cap.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct Written {
    /// Records written.
    pub records: u64,
    /// Records dropped because the cap was reached.
    pub dropped: u64,
    /// Bytes in the file.
    pub bytes: u64,
}

/// Reads up to `buf.len()` bytes, fewer only at the end of the file: both readers tell a torn
/// tail from the end by how many bytes came.
fn read_up_to(
    input: &mut impl std::io::Read,
    buf: &mut [u8],
    path: &std::path::Path,
) -> Result<usize, RecordingError> {
    let mut have = 0;
    while have < buf.len() {
        match input.read(&mut buf[have..]) {
            Ok(0) => break,
            Ok(n) => have += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(io(path)(e)),
        }
    }
    Ok(have)
}

fn io(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> RecordingError + '_ {
    move |source| RecordingError::Io {
        path: path.to_path_buf(),
        source,
    }
}
