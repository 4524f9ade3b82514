//! Reading a log: [`LogReader`] streams the records of every segment in order and tells a
//! torn tail (the end of the last segment, cut by a crash) from corruption (anything else).
//!
//! The frames are read by the durable toolkit's [`FrameReader`], whose rules say what counts
//! as torn; only the last segment may end torn, and in it also a segment magic cut short (a
//! prefix of it) or never written (a segment of only zero bytes). Any other bad spot, and any bad spot in an earlier segment, is
//! [`LogError::Corrupt`]. Reading never modifies a file.

use std::fmt;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use super::error::{FrameProblem, LogError};
use super::frame::{format, LogFormat, MAGIC};
use super::record::Record;
use super::segment::list_segments;
use super::{FORMAT_VERSION, REPLICATED_VERSION};
use crate::durable::{FrameError, FrameReader, Step as FrameStep, Torn};

/// Where a record is: its segment, the offset of its header in the segment file, and its
/// length including the 8-byte header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RecordPos {
    /// Segment number.
    pub segment: u32,
    /// Byte offset of the record's header in the segment file.
    pub offset: u64,
    /// Bytes of the record, header included.
    pub len: u64,
}

impl RecordPos {
    /// The offset just past the record.
    pub fn end(&self) -> u64 {
        self.offset + self.len
    }
}

/// The incomplete end of the last segment, left by a crash during a write.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TornTail {
    /// The (last) segment file.
    pub path: PathBuf,
    /// Its segment number.
    pub segment: u32,
    /// Where the torn bytes start; truncating the file here leaves only complete records
    /// (0 when even the segment magic is incomplete).
    pub offset: u64,
    /// Torn bytes, from `offset` to the end of the file.
    pub bytes: u64,
    /// What is wrong at `offset`.
    pub problem: FrameProblem,
}

impl TornTail {
    fn new(path: &Path, segment: u32, torn: Torn) -> Self {
        Self {
            path: path.to_path_buf(),
            segment,
            offset: torn.offset,
            bytes: torn.bytes,
            problem: torn.problem,
        }
    }
}

impl fmt::Display for TornTail {
    /// `DIR/seg-00000002.hlog: torn tail cut at offset N (B bytes: what)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let torn = Torn {
            offset: self.offset,
            bytes: self.bytes,
            problem: self.problem.clone(),
        };
        write!(f, "{}: {torn}", self.path.display())
    }
}

/// Everything [`read_log`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct LogContents {
    /// All complete records, in order.
    pub records: Vec<Record>,
    /// Where each of `records` is.
    pub positions: Vec<RecordPos>,
    /// The segment files, in order.
    pub segments: Vec<PathBuf>,
    /// The torn tail of the last segment, if any.
    pub torn: Option<TornTail>,
}

/// Reads every record of the log in `dir`. Errors on corruption, a missing header, a version
/// mismatch, missing segments or I/O; a torn tail is reported in [`LogContents::torn`].
pub fn read_log(dir: impl AsRef<Path>) -> Result<LogContents, LogError> {
    let mut reader = LogReader::open(dir)?;
    let mut records = Vec::new();
    let mut positions = Vec::new();
    while let Some((pos, record)) = reader.next_record()? {
        positions.push(pos);
        records.push(record);
    }
    Ok(LogContents {
        records,
        positions,
        segments: reader.segments,
        torn: reader.torn,
    })
}

/// A streaming reader over a log directory's records.
///
/// [`next_record`](Self::next_record) yields records until the end of the log, a torn tail
/// ([`torn_tail`](Self::torn_tail) then says where) or an error, after which it yields
/// `Ok(None)`. It also checks that the first record is a header of [`FORMAT_VERSION`].
#[derive(Debug)]
pub struct LogReader {
    segments: Vec<PathBuf>,
    next_segment: usize,
    cursor: Option<Cursor>,
    count: u64,
    torn: Option<TornTail>,
    finished: bool,
}

impl LogReader {
    /// Lists the segments of the log in `dir` ([`LogError::NoSegments`] if there are none).
    pub fn open(dir: impl AsRef<Path>) -> Result<Self, LogError> {
        let dir = dir.as_ref();
        let segments = list_segments(dir)?;
        if segments.is_empty() {
            return Err(LogError::NoSegments {
                dir: dir.to_path_buf(),
            });
        }
        Ok(Self {
            segments,
            next_segment: 0,
            cursor: None,
            count: 0,
            torn: None,
            finished: false,
        })
    }

    /// The segment files, in order.
    pub fn segments(&self) -> &[PathBuf] {
        &self.segments
    }

    /// The torn tail, once the reader has reached it.
    pub fn torn_tail(&self) -> Option<&TornTail> {
        self.torn.as_ref()
    }

    /// The next complete record, `Ok(None)` at the end (or at a torn tail, or after an error).
    pub fn next_record(&mut self) -> Result<Option<(RecordPos, Record)>, LogError> {
        if self.finished {
            return Ok(None);
        }
        let next = self.advance();
        if !matches!(next, Ok(Some(_))) {
            self.finished = true;
            self.cursor = None;
        }
        next
    }

    fn advance(&mut self) -> Result<Option<(RecordPos, Record)>, LogError> {
        loop {
            let cursor = match &mut self.cursor {
                Some(c) => c,
                None => {
                    let Some(path) = self.segments.get(self.next_segment) else {
                        return Ok(None);
                    };
                    let index = self.next_segment as u32;
                    let last = self.next_segment + 1 == self.segments.len();
                    self.next_segment += 1;
                    match Cursor::open(path.clone(), index, last)? {
                        Ok(c) => self.cursor.insert(c),
                        Err(torn) => {
                            self.torn = Some(torn);
                            return Ok(None);
                        }
                    }
                }
            };
            match cursor.step()? {
                Step::Record(pos, record) => {
                    if self.count == 0 {
                        check_header(&cursor.path, pos.offset, &record)?;
                    }
                    self.count += 1;
                    return Ok(Some((pos, record)));
                }
                Step::End => self.cursor = None,
                Step::Torn(torn) => {
                    self.torn = Some(torn);
                    return Ok(None);
                }
            }
        }
    }
}

impl Iterator for LogReader {
    type Item = Result<(RecordPos, Record), LogError>;

    fn next(&mut self) -> Option<Self::Item> {
        self.next_record().transpose()
    }
}

/// Checks that `record`, the first of a log (at `offset` of `path`), is a header of a version
/// this build knows ([`FORMAT_VERSION`], or [`REPLICATED_VERSION`] for a replica's log): the
/// reader's rule for what it reads, the writer's for what it writes.
pub(super) fn check_header(path: &Path, offset: u64, record: &Record) -> Result<(), LogError> {
    match record {
        Record::Header(h) if h.version == FORMAT_VERSION || h.version == REPLICATED_VERSION => {
            Ok(())
        }
        Record::Header(h) => Err(LogError::Version {
            path: path.to_path_buf(),
            offset,
            found: h.version,
            expected: REPLICATED_VERSION,
        }),
        other => Err(LogError::NoHeader {
            path: path.to_path_buf(),
            offset,
            found: other.kind(),
        }),
    }
}

enum Step {
    Record(RecordPos, Record),
    End,
    Torn(TornTail),
}

/// Whether a file of `len` bytes, of which `read` came first and the rest is in `file`, holds
/// only zero bytes (a read error counts as no).
fn zeros(file: &mut BufReader<File>, read: &[u8], len: u64) -> bool {
    let mut rest = Vec::new();
    read.iter().all(|&b| b == 0)
        && file.take(len).read_to_end(&mut rest).is_ok()
        && rest.iter().all(|&b| b == 0)
}

/// Position in one open segment file.
#[derive(Debug)]
struct Cursor {
    path: PathBuf,
    index: u32,
    frames: FrameReader<LogFormat>,
}

impl Cursor {
    /// Opens a segment and checks its magic; `Ok(Err(torn))` for a last segment whose magic
    /// is incomplete.
    fn open(path: PathBuf, index: u32, last: bool) -> Result<Result<Self, TornTail>, LogError> {
        let file = File::open(&path).map_err(|e| LogError::io(&path, e))?;
        let len = file.metadata().map_err(|e| LogError::io(&path, e))?.len();
        let mut file = BufReader::new(file);
        let have = len.min(MAGIC.len() as u64) as usize;
        let mut magic = [0u8; 8];
        file.read_exact(&mut magic[..have])
            .map_err(|e| LogError::io(&path, e))?;
        let whole = |problem| {
            let torn = Torn {
                offset: 0,
                bytes: len,
                problem,
            };
            Ok(Err(TornTail::new(&path, index, torn)))
        };
        if last && magic[..have] != MAGIC[..have] && zeros(&mut file, &magic[..have], len) {
            // The segment was created and extended, but its magic never reached the disk.
            return whole(FrameProblem::ZeroFill { bytes: len });
        }
        if magic[..have] != MAGIC[..have] || (have < MAGIC.len() && !last) {
            return Err(LogError::BadMagic { path });
        }
        if have < MAGIC.len() {
            return whole(FrameProblem::ShortMagic { have: len });
        }
        let frames = FrameReader::new(format(), file, MAGIC.len() as u64, len, last);
        Ok(Ok(Self {
            path,
            index,
            frames,
        }))
    }

    fn step(&mut self) -> Result<Step, LogError> {
        match self.frames.step() {
            Ok(FrameStep::Frame { offset, len, item }) => {
                let pos = RecordPos {
                    segment: self.index,
                    offset,
                    len,
                };
                Ok(Step::Record(pos, item))
            }
            Ok(FrameStep::End) => Ok(Step::End),
            Ok(FrameStep::Torn(torn)) => {
                Ok(Step::Torn(TornTail::new(&self.path, self.index, torn)))
            }
            Err(FrameError::Io(e)) => Err(LogError::io(&self.path, e)),
            Err(FrameError::Corrupt { offset, problem }) => Err(LogError::Corrupt {
                path: self.path.clone(),
                offset,
                problem,
            }),
        }
    }
}
