//! Reading a log: [`LogReader`] streams the records of every segment in order and tells a
//! torn tail (the end of the last segment, cut by a crash) from corruption (anything else).
//!
//! In the last segment, a bad spot at offset `p` is a torn tail when either
//! - every byte from `p` to the end of the file is zero (a file system that extended the file
//!   before the last write's data reached the disk), or
//! - the bad bytes reach the end of the file as one cut write would leave them: fewer than 8
//!   bytes of segment magic (a prefix of it) or of a record header, a record length running
//!   past the end of the file, or a record with a bad length, checksum or payload ending
//!   exactly at the end of the file (the final record); and no more bytes than one record can
//!   have; and no complete, valid record starts anywhere after `p` (so a damaged length
//!   field in a middle record is corruption, not a torn tail).
//!
//! Any other bad spot, and any bad spot in an earlier segment, is [`LogError::Corrupt`].
//! Reading never modifies a file.

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use super::error::{FrameProblem, LogError};
use super::frame::{decode_payload, parse_frame_header, plausible_len, FRAME_HEADER_LEN, MAGIC};
use super::record::Record;
use super::segment::list_segments;
use super::{FORMAT_VERSION, MAX_RECORD_LEN, REPLICATED_VERSION};

/// Bytes the torn-tail check checksums at most while looking for a complete frame after a
/// bad one.
const SCAN_BUDGET: u64 = 256 << 20;

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
    payload: Vec<u8>,
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
            payload: Vec::new(),
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
            match cursor.step(&mut self.payload)? {
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

/// Position in one open segment file.
#[derive(Debug)]
struct Cursor {
    path: PathBuf,
    index: u32,
    file: BufReader<File>,
    pos: u64,
    len: u64,
    last: bool,
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
        if magic[..have] != MAGIC[..have] || (have < MAGIC.len() && !last) {
            return Err(LogError::BadMagic { path });
        }
        if have < MAGIC.len() {
            return Ok(Err(TornTail {
                path,
                segment: index,
                offset: 0,
                bytes: len,
                problem: FrameProblem::ShortMagic { have: len },
            }));
        }
        Ok(Ok(Self {
            path,
            index,
            file,
            pos: MAGIC.len() as u64,
            len,
            last,
        }))
    }

    fn io(&self, e: std::io::Error) -> LogError {
        LogError::io(&self.path, e)
    }

    fn step(&mut self, payload: &mut Vec<u8>) -> Result<Step, LogError> {
        let at = self.pos;
        let left = self.len - at;
        if left == 0 {
            return Ok(Step::End);
        }
        if left < FRAME_HEADER_LEN as u64 {
            return self.bad(at, FrameProblem::ShortHeader { have: left }, None);
        }
        let mut header = [0u8; FRAME_HEADER_LEN];
        self.file.read_exact(&mut header).map_err(|e| self.io(e))?;
        let (len, crc) = parse_frame_header(&header);
        let have = left - FRAME_HEADER_LEN as u64;
        if u64::from(len) > have {
            return self.bad(at, FrameProblem::LengthPastEnd { len, have }, None);
        }
        let end = at + FRAME_HEADER_LEN as u64 + u64::from(len);
        if !plausible_len(len) {
            return self.bad(at, FrameProblem::BadLength { len }, Some(end));
        }
        payload.resize(len as usize, 0);
        self.file.read_exact(payload).map_err(|e| self.io(e))?;
        match decode_payload(payload, crc) {
            Ok(record) => {
                self.pos = end;
                let pos = RecordPos {
                    segment: self.index,
                    offset: at,
                    len: end - at,
                };
                Ok(Step::Record(pos, record))
            }
            Err(problem) => self.bad(at, problem, Some(end)),
        }
    }

    /// A bad frame at `at` (ending at `end` if its length is plausible): torn or corrupt.
    fn bad(&mut self, at: u64, problem: FrameProblem, end: Option<u64>) -> Result<Step, LogError> {
        if self.last {
            let left = self.len - at;
            let torn = if end.is_none_or(|e| e == self.len) {
                // A cut write leaves at most one frame, and no complete frame after it.
                let one_frame = left <= FRAME_HEADER_LEN as u64 + u64::from(MAX_RECORD_LEN);
                (one_frame && !self.frame_after(at)?).then(|| problem.clone())
            } else if self.zeros_from(at)? {
                Some(FrameProblem::ZeroFill { bytes: left })
            } else {
                None
            };
            if let Some(problem) = torn {
                return Ok(Step::Torn(TornTail {
                    path: self.path.clone(),
                    segment: self.index,
                    offset: at,
                    bytes: self.len - at,
                    problem,
                }));
            }
        }
        Err(LogError::Corrupt {
            path: self.path.clone(),
            offset: at,
            problem,
        })
    }

    /// Whether a complete, valid frame starts anywhere after `at` (so that the bad frame at
    /// `at` is not the final one, e.g. its length field is damaged). Gives up and answers yes
    /// (corruption, nothing truncated) after checksumming [`SCAN_BUDGET`] bytes.
    fn frame_after(&mut self, at: u64) -> Result<bool, LogError> {
        self.file
            .seek(SeekFrom::Start(at + 1))
            .map_err(|e| self.io(e))?;
        let mut rest = Vec::new();
        self.file.read_to_end(&mut rest).map_err(|e| self.io(e))?;
        let mut budget = SCAN_BUDGET;
        for q in 0..rest.len().saturating_sub(FRAME_HEADER_LEN) {
            let mut header = [0u8; FRAME_HEADER_LEN];
            header.copy_from_slice(&rest[q..q + FRAME_HEADER_LEN]);
            let (len, crc) = parse_frame_header(&header);
            let start = q + FRAME_HEADER_LEN;
            if !plausible_len(len) || len as usize > rest.len() - start {
                continue;
            }
            if budget < u64::from(len) {
                return Ok(true);
            }
            budget -= u64::from(len);
            if decode_payload(&rest[start..start + len as usize], crc).is_ok() {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// Whether every byte from `at` to the end of the file is zero.
    fn zeros_from(&mut self, at: u64) -> Result<bool, LogError> {
        self.file
            .seek(SeekFrom::Start(at))
            .map_err(|e| self.io(e))?;
        let mut left = self.len - at;
        let mut chunk = [0u8; 4096];
        while left > 0 {
            let n = left.min(chunk.len() as u64) as usize;
            self.file
                .read_exact(&mut chunk[..n])
                .map_err(|e| self.io(e))?;
            if chunk[..n].iter().any(|&b| b != 0) {
                return Ok(false);
            }
            left -= n as u64;
        }
        Ok(true)
    }
}
