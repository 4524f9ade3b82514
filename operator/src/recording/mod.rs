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
//! [`world`] reads them back as a world: the map with the scenario's changes applied by
//! time, the movers' places and each robot's sensed area, for the playback and the report.
//!
//! Both are little-endian, start with an 8-byte magic whose last byte is the format version,
//! and are written append-only through a size cap: a sample beyond the cap is dropped and
//! counted, and [`trajectory::TrajectoryWriter::finish`] marks the file truncated, so a long
//! run cannot fill the disk. Both are frames of the durable toolkit
//! ([`hnav_runtime::durable`]), appended a chunk at a time and synced once, when the recording
//! finishes. A writer killed mid-write leaves a torn tail, which the readers report ("torn
//! tail cut at offset N") and skip rather than treat as corruption.

pub mod maps;
pub mod trajectory;
pub mod world;

use std::path::PathBuf;

use hnav_runtime::durable::{Appender, FrameError, FrameFormat, FrameReader, Step, Torn};

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

/// A recording file's frames waiting to be written, and the file: frames go out a chunk at
/// a time (one write call each), so that a sample costs no system call.
struct Pending {
    out: Appender<std::fs::File>,
    buf: Vec<u8>,
}

impl Pending {
    /// Bytes buffered before they are written.
    const CHUNK: usize = 64 << 10;

    fn new(out: Appender<std::fs::File>) -> Self {
        Self {
            out,
            buf: Vec::with_capacity(Self::CHUNK),
        }
    }

    /// Writes the buffer once it holds a chunk.
    fn write_full(&mut self) -> std::io::Result<()> {
        if self.buf.len() >= Self::CHUNK {
            self.flush()?;
        }
        Ok(())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        if !self.buf.is_empty() {
            self.out.append(&self.buf)?;
            self.buf.clear();
        }
        Ok(())
    }

    /// Writes the buffer and syncs the file (a failed sync is reported, not retried).
    fn finish(&mut self) -> std::io::Result<()> {
        self.flush()?;
        self.out.sync()
    }
}

/// The next frame of a recording file (its offset and what it decoded to); `Ok(None)` at the
/// end or at a torn tail, which goes to `torn`, and ever after.
fn frame_step<F: FrameFormat>(
    frames: &mut Option<FrameReader<F>>,
    torn: &mut Option<Torn>,
    path: &std::path::Path,
) -> Result<Option<(u64, F::Item)>, RecordingError> {
    let Some(reader) = frames else {
        return Ok(None);
    };
    let stop = match reader.step() {
        Ok(Step::Frame { offset, item, .. }) => return Ok(Some((offset, item))),
        Ok(Step::End) => None,
        Ok(Step::Torn(t)) => Some(t),
        Err(FrameError::Io(e)) => return Err(io(path)(e)),
        Err(FrameError::Corrupt { offset, problem }) => {
            return Err(RecordingError::Corrupt {
                path: path.to_path_buf(),
                offset,
                problem: problem.to_string(),
            })
        }
    };
    *frames = None;
    *torn = stop;
    Ok(None)
}

fn io(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> RecordingError + '_ {
    move |source| RecordingError::Io {
        path: path.to_path_buf(),
        source,
    }
}
