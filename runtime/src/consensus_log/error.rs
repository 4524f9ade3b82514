//! [`LogError`], every way reading or writing a consensus log can fail, and [`FrameProblem`],
//! what is wrong with the bytes at one place of a segment.

use std::path::PathBuf;

/// What is wrong with the bytes at one offset of a segment file: the durable toolkit's, since
/// segments are [`Checksummed`](crate::durable::Checksummed) frames.
///
/// In the last segment's final bytes such a problem is a [torn tail](super::TornTail) (a write
/// the crash interrupted); anywhere else it is [corruption](LogError::Corrupt).
pub use crate::durable::FrameProblem;

/// An error reading, verifying or writing a consensus log. Every variant names the file (or
/// directory) and, where one applies, the byte offset.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// An operating-system error on a file or directory.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The error.
        #[source]
        source: std::io::Error,
    },
    /// The directory holds no `seg-NNNNNNNN.hlog` file.
    #[error("{}: no consensus-log segments (seg-00000000.hlog missing)", dir.display())]
    NoSegments {
        /// The directory.
        dir: PathBuf,
    },
    /// Segment numbers are not 0, 1, 2, ... without gaps.
    #[error("{}: segment {} missing (found segment {found} instead)", dir.display(), super::segment_name(*expected))]
    SegmentGap {
        /// The directory.
        dir: PathBuf,
        /// The segment number that should come next.
        expected: u32,
        /// The number found in its place.
        found: u32,
    },
    /// A segment does not start with `HNAVLOG1`.
    #[error("{}: byte 0: not a consensus-log segment (missing or unknown magic)", path.display())]
    BadMagic {
        /// The segment file.
        path: PathBuf,
    },
    /// Bad bytes before the last complete record (or anywhere in an earlier segment).
    #[error("{}: byte {offset}: corrupt: {problem}", path.display())]
    Corrupt {
        /// The segment file.
        path: PathBuf,
        /// Offset of the bad record's header in the file.
        offset: u64,
        /// What is wrong.
        problem: FrameProblem,
    },
    /// The log's first record is not a [`RunHeader`](super::RunHeader).
    #[error("{}: byte {offset}: the first record is a {found} record, not a header", path.display())]
    NoHeader {
        /// The segment file.
        path: PathBuf,
        /// Offset of the first record.
        offset: u64,
        /// The kind found instead.
        found: &'static str,
    },
    /// The header's format version is not [`FORMAT_VERSION`](super::FORMAT_VERSION).
    #[error("{}: byte {offset}: log format version {found}, this build reads versions 1 and {expected}", path.display())]
    Version {
        /// The segment file.
        path: PathBuf,
        /// Offset of the header record.
        offset: u64,
        /// The version in the header.
        found: u32,
        /// The newest version this build reads (it reads every version from 1 up).
        expected: u32,
    },
    /// A replicated log whose Raft entries do not make a log: an entry that skips indices,
    /// goes back in term, or holds no record.
    #[error("{}: Raft entry {index}: {what}", dir.display())]
    Raft {
        /// The log directory.
        dir: PathBuf,
        /// The entry's index.
        index: u64,
        /// What is wrong.
        what: String,
    },
    /// A record to append encodes to more than [`MAX_RECORD_LEN`](super::MAX_RECORD_LEN).
    #[error("record of {len} bytes exceeds the maximum of {max}")]
    TooLarge {
        /// The encoded length.
        len: usize,
        /// The maximum.
        max: u32,
    },
    /// A record to append could not be encoded.
    #[error("cannot encode record: {0}")]
    Encode(#[from] bincode::error::EncodeError),
    /// Another process holds the log's writer lock: two writers would interleave their
    /// records.
    #[error("{}: the consensus log is already being written by another process{}; a log has one writer", dir.display(), holder.as_ref().map(|p| format!(" (pid {p})")).unwrap_or_default())]
    Locked {
        /// The log directory.
        dir: PathBuf,
        /// The pid the lock file names, if it could be read.
        holder: Option<String>,
    },
    /// The disk holding the log is full. Fatal for the run: a restart would meet the same
    /// full disk. The log stays readable: a partial record was cut off.
    #[error("no space left on device writing the consensus log in {}", dir.display())]
    NoSpace {
        /// The log directory.
        dir: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// An earlier write or fsync failed; the writer refuses further appends because the
    /// file's durable state is unknown. Reopen the log to recover.
    #[error("{}: an earlier write or fsync failed; reopen the log", path.display())]
    Poisoned {
        /// The segment file.
        path: PathBuf,
    },
}

impl LogError {
    /// An [`Io`](Self::Io) error for `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }

    /// Whether this error means the log could not be read at all (an I/O error, or no
    /// segments), as opposed to a log with bad contents.
    pub fn is_unreadable(&self) -> bool {
        matches!(self, Self::Io { .. } | Self::NoSegments { .. })
    }
}
