//! `maps.bin`: neural-map snapshots as the agents published them, one checksummed frame each.
//!
//! Variable-size frames (a map is `width x height` activations), each with its length and a
//! CRC-32C, because unlike a pose sample a torn or damaged snapshot must not be mistaken for
//! a map. The snapshot's fields are those of [`MapHeader`], plus the simulated time it was
//! received at.
//!
//! ```text
//! magic "HNAVMAP" + version 1 (8 bytes), then frames:
//!   0  len        u32   bytes of the body (40 + 4 width height)
//!   4  crc32c     u32   of the body
//!   body:
//!   0  t_ns       u64   simulated time when the recorder received it
//!   8  round      u64   MapHeader fields, in their order
//!  16  agent, width, height, iterations, target   u32 x 5
//!  36  activation u8, reserved [u8; 3]
//!  40  values     f32 x width height, row-major (cell (x, y) at y width + x)
//! ```

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use hnav_runtime::durable::framed::seal_checksummed;
use hnav_runtime::durable::{Appender, Checksummed, FrameProblem, FrameReader, Torn};
use hnav_runtime::msg::MapHeader;

use super::{frame_step, io, Pending, RecordingError, Written};

const MAGIC: &[u8; 7] = b"HNAVMAP";
const VERSION: u8 = 1;
const WHAT: &str = "neural-map";
/// Bytes of a frame's body before the values.
pub const BODY_HEADER_LEN: usize = 40;
/// The largest map a frame may hold (cells); a larger length is corruption, not a map, and
/// is refused before anything is allocated for it.
pub const MAX_CELLS: usize = 1 << 24;

/// One neural-map snapshot read back.
#[derive(Clone, PartialEq, Debug)]
pub struct MapSnapshot {
    /// Simulated time when the recorder received it, ns since `Start`.
    pub t_ns: u64,
    /// The snapshot's header as the agent published it.
    pub header: MapHeader,
    /// One activation per cell, row-major.
    pub values: Vec<f32>,
}

/// The frames of `maps.bin`: a body of 40 bytes and up to [`MAX_CELLS`] values.
type MapFormat = Checksummed<fn(&[u8]) -> Result<MapSnapshot, FrameProblem>>;

fn format() -> MapFormat {
    Checksummed {
        min_len: BODY_HEADER_LEN as u32,
        max_len: (BODY_HEADER_LEN + 4 * MAX_CELLS) as u32,
        decode: decode_body,
    }
}

/// Appends snapshots to a new `maps.bin`, up to a size cap.
pub struct MapWriter {
    path: PathBuf,
    out: Pending,
    max_bytes: u64,
    written: Written,
}

impl MapWriter {
    /// Creates (or replaces) the file. Snapshots stop being written once the file would grow
    /// past `max_bytes`.
    pub fn create(path: &Path, max_bytes: u64) -> Result<Self, RecordingError> {
        let file = File::create(path).map_err(io(path))?;
        let mut out = Pending::new(Appender::new(file, 0));
        out.buf.extend_from_slice(MAGIC);
        out.buf.push(VERSION);
        Ok(MapWriter {
            path: path.to_path_buf(),
            out,
            max_bytes,
            written: Written {
                bytes: 8,
                ..Written::default()
            },
        })
    }

    /// Appends one snapshot (straight from a received sample: `values` is its payload);
    /// `Ok(false)` when the cap dropped it. `values` must hold `width x height` cells.
    pub fn push(
        &mut self,
        t_ns: u64,
        header: &MapHeader,
        values: &[f32],
    ) -> Result<bool, RecordingError> {
        let cells = header.width as usize * header.height as usize;
        if values.len() != cells || cells > MAX_CELLS {
            return Err(RecordingError::Corrupt {
                path: self.path.clone(),
                offset: self.written.bytes,
                problem: format!(
                    "snapshot of agent {} has {} values for a {} x {} map",
                    header.agent,
                    values.len(),
                    header.width,
                    header.height
                ),
            });
        }
        let body_len = BODY_HEADER_LEN + 4 * cells;
        if self.written.bytes + 8 + body_len as u64 > self.max_bytes {
            self.written.dropped += 1;
            return Ok(false);
        }
        let buf = &mut self.out.buf;
        let start = buf.len();
        buf.extend_from_slice(&[0; 8]);
        buf.extend_from_slice(&encode_body_header(t_ns, header));
        for v in values {
            buf.extend_from_slice(&v.to_le_bytes());
        }
        seal_checksummed(buf, start);
        self.out.write_full().map_err(io(&self.path))?;
        self.written.records += 1;
        self.written.bytes += 8 + body_len as u64;
        Ok(true)
    }

    /// Counts so far.
    pub fn written(&self) -> Written {
        self.written
    }

    /// Writes what is buffered and syncs the file: the recording is durable when it returns.
    pub fn finish(mut self) -> Result<Written, RecordingError> {
        self.out.finish().map_err(io(&self.path))?;
        Ok(self.written)
    }
}

fn encode_body_header(t_ns: u64, h: &MapHeader) -> [u8; BODY_HEADER_LEN] {
    let mut b = [0u8; BODY_HEADER_LEN];
    b[..8].copy_from_slice(&t_ns.to_le_bytes());
    b[8..16].copy_from_slice(&h.round.to_le_bytes());
    for (i, v) in [h.agent, h.width, h.height, h.iterations, h.target]
        .into_iter()
        .enumerate()
    {
        b[16 + 4 * i..20 + 4 * i].copy_from_slice(&v.to_le_bytes());
    }
    b[36] = h.activation;
    b[37..40].copy_from_slice(&h.reserved);
    b
}

/// A frame's body as a snapshot, if its map's size is the frame's.
fn decode_body(body: &[u8]) -> Result<MapSnapshot, FrameProblem> {
    let values = body.len() - BODY_HEADER_LEN;
    let undecodable = |detail| Err(FrameProblem::Undecodable { detail });
    if !values.is_multiple_of(4) {
        return undecodable(format!("a body of {} bytes", body.len()));
    }
    let (t_ns, header) = decode_body_header(body);
    let cells = header.width as usize * header.height as usize;
    if cells != values / 4 {
        return undecodable(format!(
            "a {} x {} map in a frame of {} values",
            header.width,
            header.height,
            values / 4
        ));
    }
    let values = body[BODY_HEADER_LEN..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    Ok(MapSnapshot {
        t_ns,
        header,
        values,
    })
}

fn decode_body_header(b: &[u8]) -> (u64, MapHeader) {
    let u64_at = |i: usize| {
        let mut a = [0u8; 8];
        a.copy_from_slice(&b[i..i + 8]);
        u64::from_le_bytes(a)
    };
    let u32_at = |i: usize| u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
    let header = MapHeader {
        round: u64_at(8),
        agent: u32_at(16),
        width: u32_at(20),
        height: u32_at(24),
        iterations: u32_at(28),
        target: u32_at(32),
        activation: b[36],
        reserved: [b[37], b[38], b[39]],
    };
    (u64_at(0), header)
}

/// Reads a `maps.bin` frame by frame.
pub struct MapReader {
    path: PathBuf,
    frames: Option<FrameReader<MapFormat>>,
    torn: Option<Torn>,
}

impl MapReader {
    /// Opens the file and checks its magic.
    pub fn open(path: &Path) -> Result<Self, RecordingError> {
        let file = File::open(path).map_err(io(path))?;
        let len = file.metadata().map_err(io(path))?.len();
        let mut input = BufReader::new(file);
        let mut magic = [0u8; 8];
        let bad = || RecordingError::BadMagic {
            path: path.to_path_buf(),
            what: WHAT,
        };
        match input.read_exact(&mut magic) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Err(bad()),
            Err(e) => return Err(io(path)(e)),
        }
        if &magic[..7] != MAGIC {
            return Err(bad());
        }
        if magic[7] != VERSION {
            return Err(RecordingError::Version {
                path: path.to_path_buf(),
                what: WHAT,
                version: magic[7],
                supported: VERSION,
            });
        }
        Ok(MapReader {
            path: path.to_path_buf(),
            frames: Some(FrameReader::new(format(), input, 8, len, true)),
            torn: None,
        })
    }

    /// The next snapshot; `Ok(None)` at the end. A torn tail (a frame cut by a crash, see
    /// [`hnav_runtime::durable::read`]) reads as the end, and [`MapReader::torn`] tells
    /// where it is.
    pub fn next_snapshot(&mut self) -> Result<Option<MapSnapshot>, RecordingError> {
        Ok(frame_step(&mut self.frames, &mut self.torn, &self.path)?.map(|(_, s)| s))
    }

    /// Every remaining snapshot, and the bytes of a torn tail (0 if none).
    pub fn read_all(mut self) -> Result<(Vec<MapSnapshot>, u64), RecordingError> {
        let mut out = Vec::new();
        while let Some(s) = self.next_snapshot()? {
            out.push(s);
        }
        Ok((out, self.torn_tail()))
    }

    /// Bytes of a torn tail found at the end (0 until the end is reached, or if none).
    pub fn torn_tail(&self) -> u64 {
        self.torn.as_ref().map_or(0, |t| t.bytes)
    }

    /// The torn tail found at the end, if any: `torn tail cut at offset N (...)`.
    pub fn torn(&self) -> Option<&Torn> {
        self.torn.as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(agent: u32, round: u64) -> MapHeader {
        MapHeader {
            round,
            agent,
            width: 3,
            height: 2,
            iterations: 4,
            target: 5,
            activation: 2,
            reserved: [0; 3],
        }
    }

    const VALUES: [f32; 6] = [0.0, 0.1, 0.2, 0.3, 0.4, 1.0];

    #[test]
    fn snapshots_round_trip_and_the_cap_drops() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.bin");
        let frame = 8 + BODY_HEADER_LEN as u64 + 24;
        let mut w = MapWriter::create(&path, 8 + 2 * frame).unwrap();
        for r in 0..3 {
            assert_eq!(w.push(r * 10, &header(1, r), &VALUES).unwrap(), r < 2);
        }
        let written = w.finish().unwrap();
        assert_eq!((written.records, written.dropped), (2, 1));
        let (maps, torn) = MapReader::open(&path).unwrap().read_all().unwrap();
        assert_eq!(torn, 0);
        assert_eq!(maps.len(), 2);
        assert_eq!(maps[1].t_ns, 10);
        assert_eq!(maps[1].header, header(1, 1));
        assert_eq!(maps[1].values, VALUES);
    }

    #[test]
    fn a_torn_frame_is_the_end_and_a_damaged_one_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.bin");
        let mut w = MapWriter::create(&path, u64::MAX).unwrap();
        for r in 0..2 {
            w.push(r, &header(0, r), &VALUES).unwrap();
        }
        w.finish().unwrap();
        let full = std::fs::read(&path).unwrap();
        std::fs::write(&path, &full[..full.len() - 5]).unwrap();
        let (maps, torn) = MapReader::open(&path).unwrap().read_all().unwrap();
        assert_eq!((maps.len(), torn), (1, 8 + BODY_HEADER_LEN as u64 + 24 - 5));
        // The final frame damaged is what a cut write can leave: a torn tail, located.
        let mut damaged = full.clone();
        let last = damaged.len() - 1;
        damaged[last] ^= 0x40;
        std::fs::write(&path, &damaged).unwrap();
        let mut r = MapReader::open(&path).unwrap();
        while r.next_snapshot().unwrap().is_some() {}
        let torn = r.torn().unwrap().to_string();
        assert!(torn.starts_with("torn tail cut at offset 80 (72 bytes: checksum mismatch"));
        // A damaged frame with another after it is corruption.
        let mut damaged = full.clone();
        damaged[20] ^= 0x40;
        std::fs::write(&path, &damaged).unwrap();
        let e = MapReader::open(&path).unwrap().read_all().err().unwrap();
        assert!(
            e.to_string().contains("at byte 8: checksum mismatch"),
            "{e}"
        );
        let mut huge = full[..8].to_vec();
        huge.extend_from_slice(&u32::MAX.to_le_bytes());
        huge.extend_from_slice(&[0; 4]);
        huge.extend_from_slice(&full[8..]);
        std::fs::write(&path, &huge).unwrap();
        let e = MapReader::open(&path).unwrap().read_all().err().unwrap();
        assert!(
            e.to_string()
                .ends_with("at byte 8: record length 4294967295 runs past the end of the file (144 bytes left)"),
            "{e}"
        );
    }

    #[test]
    fn a_snapshot_of_the_wrong_size_is_refused_at_write() {
        let dir = tempfile::tempdir().unwrap();
        let mut w = MapWriter::create(&dir.path().join("m.bin"), u64::MAX).unwrap();
        let e = w.push(0, &header(2, 0), &VALUES[..5]).err().unwrap();
        assert!(
            e.to_string()
                .ends_with("snapshot of agent 2 has 5 values for a 3 x 2 map"),
            "{e}"
        );
    }
}
