//! Reading a framed file back: [`FrameReader`] yields its frames in order and tells a torn
//! tail (the end of the file, cut by a crash during a write) from corruption (anything else).
//!
//! When the file may end torn, a bad spot at offset `p` is a torn tail when either
//! - every byte from `p` to the end of the file is zero (a file system that extended the file
//!   before the last write's data reached the disk), or
//! - the bad bytes reach the end of the file as one cut write would leave them: fewer bytes
//!   than a frame header, a frame length running past the end of the file, or a frame with a
//!   bad length, checksum or payload ending exactly at the end of the file (the final frame);
//!   and no more bytes than one frame can have; and no complete, valid frame starts anywhere
//!   after `p` (so a damaged length field in a middle frame is corruption, not a torn tail).
//!
//! Any other bad spot is corruption ([`FrameError::Corrupt`]). Reading never modifies a file.

use std::fmt;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};

use super::framed::{FrameFormat, FrameProblem};

/// Bytes the torn-tail check checksums at most while looking for a complete frame after a
/// bad one.
const SCAN_BUDGET: u64 = 256 << 20;

/// The incomplete end of a file, left by a crash during a write: truncating the file at
/// `offset` leaves only complete frames.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Torn {
    /// Where the torn bytes start.
    pub offset: u64,
    /// Torn bytes, from `offset` to the end of the file.
    pub bytes: u64,
    /// What is wrong at `offset`.
    pub problem: FrameProblem,
}

impl fmt::Display for Torn {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "torn tail cut at offset {} ({} bytes: {})",
            self.offset, self.bytes, self.problem
        )
    }
}

/// Why reading a framed file stopped.
#[derive(Debug)]
pub enum FrameError {
    /// The file could not be read.
    Io(std::io::Error),
    /// The bytes at `offset` are not a valid frame, and not a torn tail.
    Corrupt {
        /// Byte offset of the bad frame.
        offset: u64,
        /// What is wrong.
        problem: FrameProblem,
    },
}

impl From<std::io::Error> for FrameError {
    fn from(e: std::io::Error) -> Self {
        Self::Io(e)
    }
}

/// One step of a [`FrameReader`].
#[derive(Debug)]
pub enum Step<T> {
    /// A valid frame: its offset, its length (header included) and what it decoded to; its
    /// payload is [`FrameReader::payload`] until the next step.
    Frame {
        /// Byte offset of the frame's header.
        offset: u64,
        /// Bytes of the frame, header included.
        len: u64,
        /// The decoded payload.
        item: T,
    },
    /// The end of the file, after a complete frame.
    End,
    /// A torn tail; nothing follows.
    Torn(Torn),
}

/// Reads the frames of one file from an offset (past the file's own magic or header).
#[derive(Debug)]
pub struct FrameReader<F> {
    format: F,
    file: BufReader<File>,
    pos: u64,
    len: u64,
    may_tear: bool,
    payload: Vec<u8>,
}

impl<F: FrameFormat> FrameReader<F> {
    /// Frames of `file` (of `len` bytes, read up to `pos` already) in `format`; only a file
    /// that `may_tear` (the last one written) can end in a torn tail.
    pub fn new(format: F, file: BufReader<File>, pos: u64, len: u64, may_tear: bool) -> Self {
        Self {
            format,
            file,
            pos,
            len,
            may_tear,
            payload: Vec::new(),
        }
    }

    /// Opens `file` and reads its frames from `pos` on.
    pub fn open(format: F, file: File, pos: u64, may_tear: bool) -> std::io::Result<Self> {
        let len = file.metadata()?.len();
        let mut file = BufReader::new(file);
        file.seek(SeekFrom::Start(pos))?;
        Ok(Self::new(format, file, pos, len, may_tear))
    }

    /// The payload of the frame the last step returned.
    pub fn payload(&self) -> &[u8] {
        &self.payload
    }

    /// The offset of the next frame.
    pub fn pos(&self) -> u64 {
        self.pos
    }

    /// The next frame, the end, or a torn tail.
    pub fn step(&mut self) -> Result<Step<F::Item>, FrameError> {
        let head_len = F::HEADER_LEN as u64;
        let at = self.pos;
        let left = self.len.saturating_sub(at);
        if left == 0 {
            return Ok(Step::End);
        }
        if left < head_len {
            return self.bad(at, FrameProblem::ShortHeader { have: left }, None);
        }
        let mut header = [0u8; 16];
        let header = &mut header[..F::HEADER_LEN];
        self.file.read_exact(header)?;
        let len = self.format.payload_len(header);
        let have = left - head_len;
        if u64::from(len) > have {
            return self.bad(at, FrameProblem::LengthPastEnd { len, have }, None);
        }
        let end = at + head_len + u64::from(len);
        if !self.format.plausible_len(len) {
            return self.bad(at, FrameProblem::BadLength { len }, Some(end));
        }
        self.payload.resize(len as usize, 0);
        self.file.read_exact(&mut self.payload)?;
        match self.format.decode(header, &self.payload) {
            Ok(item) => {
                self.pos = end;
                Ok(Step::Frame {
                    offset: at,
                    len: end - at,
                    item,
                })
            }
            Err(problem) => self.bad(at, problem, Some(end)),
        }
    }

    /// A bad frame at `at` (ending at `end` if its length is plausible): torn or corrupt.
    fn bad<T>(
        &mut self,
        at: u64,
        problem: FrameProblem,
        end: Option<u64>,
    ) -> Result<Step<T>, FrameError> {
        if self.may_tear {
            let left = self.len - at;
            let torn = if end.is_none_or(|e| e == self.len) {
                // A cut write leaves at most one frame, and no complete frame after it.
                let one_frame = left <= self.format.max_frame_len();
                (one_frame && !self.frame_after(at)?).then(|| problem.clone())
            } else if self.zeros_from(at)? {
                Some(FrameProblem::ZeroFill { bytes: left })
            } else {
                None
            };
            if let Some(problem) = torn {
                return Ok(Step::Torn(Torn {
                    offset: at,
                    bytes: left,
                    problem,
                }));
            }
        }
        Err(FrameError::Corrupt {
            offset: at,
            problem,
        })
    }

    /// Whether a complete, valid frame starts anywhere after `at` (so that the bad frame at
    /// `at` is not the final one, e.g. its length field is damaged). Gives up and answers yes
    /// (corruption, nothing truncated) after checksumming [`SCAN_BUDGET`] bytes.
    fn frame_after(&mut self, at: u64) -> std::io::Result<bool> {
        self.file.seek(SeekFrom::Start(at + 1))?;
        let mut rest = Vec::new();
        self.file.read_to_end(&mut rest)?;
        let head_len = F::HEADER_LEN;
        let mut budget = SCAN_BUDGET;
        for q in 0..rest.len().saturating_sub(head_len) {
            let header = &rest[q..q + head_len];
            let len = self.format.payload_len(header);
            let start = q + head_len;
            if !self.format.plausible_len(len) || len as usize > rest.len() - start {
                continue;
            }
            if budget < u64::from(len) {
                return Ok(true);
            }
            budget -= u64::from(len);
            if self
                .format
                .decode(header, &rest[start..start + len as usize])
                .is_ok()
            {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// Whether every byte from `at` to the end of the file is zero.
    fn zeros_from(&mut self, at: u64) -> std::io::Result<bool> {
        self.file.seek(SeekFrom::Start(at))?;
        let mut left = self.len - at;
        let mut chunk = [0u8; 4096];
        while left > 0 {
            let n = left.min(chunk.len() as u64) as usize;
            self.file.read_exact(&mut chunk[..n])?;
            if chunk[..n].iter().any(|&b| b != 0) {
                return Ok(false);
            }
            left -= n as u64;
        }
        Ok(true)
    }
}
