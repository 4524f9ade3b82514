//! Frame formats of append-only files: [`FrameFormat`], what a frame looks like, and the two
//! kinds HNAV writes, [`Checksummed`] (`u32 LE payload length | u32 LE crc32c(payload) |
//! payload`: the consensus log's segments and `maps.bin`) and [`Fixed`] (fixed-size records
//! without a checksum: `trajectories.bin`); [`FrameProblem`], what is wrong with the bytes at
//! one place of such a file.
//!
//! A format only says how a frame starts, how long it is and whether it is valid; where the
//! frames of a file start (after its magic or header) is the file owner's business.

use std::fmt;

/// A frame format: header, payload length, and the check of a whole frame.
pub trait FrameFormat {
    /// What a valid frame decodes to.
    type Item;

    /// Bytes of a frame before its payload.
    const HEADER_LEN: usize;

    /// The payload length `header` (of [`HEADER_LEN`](Self::HEADER_LEN) bytes) announces.
    fn payload_len(&self, header: &[u8]) -> u32;

    /// Whether a payload can be `len` bytes long; a larger or smaller stored length is
    /// garbage, refused before anything is allocated for it.
    fn plausible_len(&self, len: u32) -> bool;

    /// The most bytes one frame can take, header included: a torn tail is never longer.
    fn max_frame_len(&self) -> u64;

    /// Checks a complete frame and decodes its payload.
    fn decode(&self, header: &[u8], payload: &[u8]) -> Result<Self::Item, FrameProblem>;
}

/// `u32 LE payload length | u32 LE crc32c(payload) | payload`, the payload decoded by `D`.
#[derive(Clone, Copy, Debug)]
pub struct Checksummed<D> {
    /// The smallest payload.
    pub min_len: u32,
    /// The largest payload.
    pub max_len: u32,
    /// Decodes a payload whose checksum matched.
    pub decode: D,
}

impl<T, D: Fn(&[u8]) -> Result<T, FrameProblem>> FrameFormat for Checksummed<D> {
    type Item = T;

    const HEADER_LEN: usize = 8;

    fn payload_len(&self, header: &[u8]) -> u32 {
        u32::from_le_bytes([header[0], header[1], header[2], header[3]])
    }

    fn plausible_len(&self, len: u32) -> bool {
        (self.min_len..=self.max_len).contains(&len)
    }

    fn max_frame_len(&self) -> u64 {
        Self::HEADER_LEN as u64 + u64::from(self.max_len)
    }

    fn decode(&self, header: &[u8], payload: &[u8]) -> Result<T, FrameProblem> {
        let stored = u32::from_le_bytes([header[4], header[5], header[6], header[7]]);
        let computed = crc32c::crc32c(payload);
        if computed != stored {
            return Err(FrameProblem::BadChecksum { stored, computed });
        }
        (self.decode)(payload)
    }
}

/// Writes the header of a [`Checksummed`] frame whose payload follows it in `buf[start..]`
/// (8 bytes reserved at `start`).
pub fn seal_checksummed(buf: &mut [u8], start: usize) {
    let payload = &buf[start + 8..];
    let len = payload.len() as u32;
    let crc = crc32c::crc32c(payload);
    buf[start..start + 4].copy_from_slice(&len.to_le_bytes());
    buf[start + 4..start + 8].copy_from_slice(&crc.to_le_bytes());
}

/// Records of `len` bytes each, without header or checksum: every complete record is a
/// frame (the owner judges its content) except one of only zero bytes, which is what a file
/// system leaves when it extended the file before the data reached the disk. A record cut
/// short by the end of the file, or zeros up to it, is a torn tail.
#[derive(Clone, Copy, Debug)]
pub struct Fixed {
    /// Bytes of a record.
    pub len: u32,
}

impl FrameFormat for Fixed {
    type Item = ();

    const HEADER_LEN: usize = 0;

    fn payload_len(&self, _: &[u8]) -> u32 {
        self.len
    }

    fn plausible_len(&self, len: u32) -> bool {
        len == self.len
    }

    fn max_frame_len(&self) -> u64 {
        u64::from(self.len)
    }

    fn decode(&self, _: &[u8], record: &[u8]) -> Result<(), FrameProblem> {
        if record.iter().all(|&b| b == 0) {
            return Err(FrameProblem::ZeroFill {
                bytes: record.len() as u64,
            });
        }
        Ok(())
    }
}

/// What is wrong with the bytes at one offset of a framed file.
///
/// In the final bytes of a file that may end torn such a problem is a
/// [torn tail](super::read::Torn) (a write the crash interrupted); anywhere else it is
/// corruption.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FrameProblem {
    /// Fewer than 8 bytes of segment magic.
    ShortMagic {
        /// Bytes present.
        have: u64,
    },
    /// Fewer than the 8 bytes of a record header (length and checksum).
    ShortHeader {
        /// Bytes present.
        have: u64,
    },
    /// The record's length runs past the end of the file.
    LengthPastEnd {
        /// The stored payload length.
        len: u32,
        /// Bytes present after the record header.
        have: u64,
    },
    /// A payload length the format cannot have (for the consensus log: 0 or above
    /// [`MAX_RECORD_LEN`](crate::consensus_log::MAX_RECORD_LEN)).
    BadLength {
        /// The stored payload length.
        len: u32,
    },
    /// The payload's CRC-32C differs from the stored one.
    BadChecksum {
        /// The stored checksum.
        stored: u32,
        /// The checksum of the payload as read.
        computed: u32,
    },
    /// The checksum matches but the payload is not a record of the format.
    Undecodable {
        /// The decoder's message.
        detail: String,
    },
    /// Only zero bytes from here to the end of the file (a file system extended the file
    /// before the data of the last write reached the disk).
    ZeroFill {
        /// The zero bytes.
        bytes: u64,
    },
}

impl fmt::Display for FrameProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::ShortMagic { have } => write!(f, "only {have} of 8 segment magic bytes"),
            Self::ShortHeader { have } => write!(f, "only {have} of 8 record header bytes"),
            Self::LengthPastEnd { len, have } => write!(
                f,
                "record length {len} runs past the end of the file ({have} bytes left)"
            ),
            Self::BadLength { len } => write!(f, "impossible record length {len}"),
            Self::BadChecksum { stored, computed } => write!(
                f,
                "checksum mismatch (stored {stored:#010x}, computed {computed:#010x})"
            ),
            Self::Undecodable { detail } => write!(f, "undecodable record: {detail}"),
            Self::ZeroFill { bytes } => write!(f, "{bytes} zero bytes up to the end of the file"),
        }
    }
}
