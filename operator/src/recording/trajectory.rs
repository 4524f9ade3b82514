//! `trajectories.bin`: every robot's pose over the run, from the sim's ground truth and from
//! the agent's dead reckoning, as fixed-size samples.
//!
//! Fixed-size records because the readers want columns (a robot's track, every robot at a
//! time) and a reader can then seek by arithmetic; `f32` coordinates because 24 bytes a
//! sample keep 256 robots x 2 sources at 20 Hz under 250 KB/s, and an `f32` metre is good to
//! 10 um on a 1000-cell map of 0.16 m cells.
//!
//! ```text
//! header, 32 bytes                      sample, 24 bytes
//!   0  magic  "HNAVTRJ" + version 1       0  t_ns       u64  simulated time since Start
//!   8  robots        u16                  8  robot      u16
//!  10  rate_hz       u16 (0 = every       10 source     u8   1 truth, 2 estimate, 3 mover
//!                     truth message)      11 reserved   u8   0
//!  12  flags         u16 (bit 0:          12 x_m        f32
//!                     truncated by cap)   16 y_m        f32
//!  14  movers        u16                  20 theta_rad  f32
//!                                         (source 3: robot is the mover's index)
//!  16  cell_size_m   f32
//!  20  width, height u32, u32 (cells)
//!  28  control period u32, microseconds
//!        (0 = not recorded)
//! ```
//!
//! ```
//! use hnav_operator::recording::{PoseSample, PoseSource, TrajectoryHeader, TrajectoryReader, TrajectoryWriter};
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("trajectories.bin");
//! let header = TrajectoryHeader { robots: 2, rate_hz: 20, cell_size_m: 0.16, width: 12, height: 12, truncated: false, control_period_us: 10_000, movers: 0 };
//! let mut w = TrajectoryWriter::create(&path, header, 1 << 20).unwrap();
//! let s = PoseSample { t_ns: 50_000_000, robot: 1, source: PoseSource::Truth, x_m: 0.24, y_m: 0.4, theta_rad: 1.57 };
//! assert!(w.push(&s).unwrap());
//! w.finish().unwrap();
//! let r = TrajectoryReader::open(&path).unwrap();
//! assert_eq!(r.header().robots, 2);
//! let (samples, torn) = r.read_all().unwrap();
//! assert_eq!((samples, torn), (vec![s], 0));
//! ```

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use hnav_runtime::durable::{Appender, DiskFile, Fixed, FrameReader, Torn};

use super::{frame_step, io, Pending, RecordingError, Written};

const MAGIC: &[u8; 7] = b"HNAVTRJ";
const VERSION: u8 = 1;
/// Bytes of the file header.
pub const HEADER_LEN: usize = 32;
/// Bytes of one sample.
pub const SAMPLE_LEN: usize = 24;
const FLAG_TRUNCATED: u16 = 1;
const WHAT: &str = "trajectory";

/// Where a pose comes from.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[repr(u8)]
pub enum PoseSource {
    /// The sim's ground truth.
    Truth = 1,
    /// The agent's dead-reckoned estimate (what it believes).
    Estimate = 2,
    /// A moving obstacle's place (the sim's `movers`); the sample's `robot` is the mover's
    /// index, in the order the movers appeared.
    Mover = 3,
}

impl PoseSource {
    /// Decodes a source byte.
    pub fn from_u8(v: u8) -> Option<Self> {
        match v {
            1 => Some(Self::Truth),
            2 => Some(Self::Estimate),
            3 => Some(Self::Mover),
            _ => None,
        }
    }
}

/// What the file says about the run it records.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct TrajectoryHeader {
    /// Robots in the run; every sample's `robot` is below it.
    pub robots: u16,
    /// Samples per second per robot and source (0: every truth message).
    pub rate_hz: u16,
    /// Edge of a grid cell in metres (poses are metres; cell `(x, y)` spans
    /// `[x c, (x + 1) c)`).
    pub cell_size_m: f32,
    /// Map width in cells.
    pub width: u32,
    /// Map height in cells.
    pub height: u32,
    /// Whether the size cap was reached and later samples dropped.
    pub truncated: bool,
    /// The run's control period in microseconds (one odometry period, one lockstep round), so
    /// a playback can place each round's decisions in simulated time; 0 when not recorded.
    /// It took a field that earlier writers of version 1 left zero, hence no version bump.
    pub control_period_us: u32,
    /// The scenario's movers (`[[events]]` movers): every [`PoseSource::Mover`] sample's
    /// index is below it. Also a field version 1 writers left zero (no movers).
    pub movers: u16,
}

impl TrajectoryHeader {
    fn encode(&self) -> [u8; HEADER_LEN] {
        let mut b = [0u8; HEADER_LEN];
        b[..7].copy_from_slice(MAGIC);
        b[7] = VERSION;
        b[8..10].copy_from_slice(&self.robots.to_le_bytes());
        b[10..12].copy_from_slice(&self.rate_hz.to_le_bytes());
        let flags = if self.truncated { FLAG_TRUNCATED } else { 0 };
        b[12..14].copy_from_slice(&flags.to_le_bytes());
        b[14..16].copy_from_slice(&self.movers.to_le_bytes());
        b[16..20].copy_from_slice(&self.cell_size_m.to_le_bytes());
        b[20..24].copy_from_slice(&self.width.to_le_bytes());
        b[24..28].copy_from_slice(&self.height.to_le_bytes());
        b[28..32].copy_from_slice(&self.control_period_us.to_le_bytes());
        b
    }

    fn decode(b: &[u8; HEADER_LEN], path: &Path) -> Result<Self, RecordingError> {
        if &b[..7] != MAGIC {
            return Err(RecordingError::BadMagic {
                path: path.to_path_buf(),
                what: WHAT,
            });
        }
        if b[7] != VERSION {
            return Err(RecordingError::Version {
                path: path.to_path_buf(),
                what: WHAT,
                version: b[7],
                supported: VERSION,
            });
        }
        let u16_at = |i: usize| u16::from_le_bytes([b[i], b[i + 1]]);
        let u32_at = |i: usize| u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
        Ok(TrajectoryHeader {
            robots: u16_at(8),
            rate_hz: u16_at(10),
            truncated: u16_at(12) & FLAG_TRUNCATED != 0,
            cell_size_m: f32::from_bits(u32_at(16)),
            width: u32_at(20),
            height: u32_at(24),
            control_period_us: u32_at(28),
            movers: u16_at(14),
        })
    }
}

/// One pose of one robot at one time.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct PoseSample {
    /// Simulated time since `Start`, ns.
    pub t_ns: u64,
    /// Robot (agent) index.
    pub robot: u16,
    /// Ground truth or estimate.
    pub source: PoseSource,
    /// x, metres.
    pub x_m: f32,
    /// y, metres.
    pub y_m: f32,
    /// Heading, radians.
    pub theta_rad: f32,
}

impl PoseSample {
    /// The sample's pose, in the messages' type.
    pub fn pose(&self) -> hnav_runtime::msg::Pose {
        hnav_runtime::msg::Pose {
            x_m: f64::from(self.x_m),
            y_m: f64::from(self.y_m),
            theta_rad: f64::from(self.theta_rad),
        }
    }

    fn encode(&self) -> [u8; SAMPLE_LEN] {
        let mut b = [0u8; SAMPLE_LEN];
        b[..8].copy_from_slice(&self.t_ns.to_le_bytes());
        b[8..10].copy_from_slice(&self.robot.to_le_bytes());
        b[10] = self.source as u8;
        b[12..16].copy_from_slice(&self.x_m.to_le_bytes());
        b[16..20].copy_from_slice(&self.y_m.to_le_bytes());
        b[20..24].copy_from_slice(&self.theta_rad.to_le_bytes());
        b
    }

    /// Decodes a sample, or says what is impossible about it.
    fn decode(b: &[u8; SAMPLE_LEN], header: &TrajectoryHeader) -> Result<Self, String> {
        let f32_at = |i: usize| f32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
        let robot = u16::from_le_bytes([b[8], b[9]]);
        let source = PoseSource::from_u8(b[10]).ok_or_else(|| format!("source byte {}", b[10]))?;
        let (what, of) = match source {
            PoseSource::Mover => ("mover", header.movers),
            PoseSource::Truth | PoseSource::Estimate => ("robot", header.robots),
        };
        if robot >= of {
            return Err(format!("{what} {robot}, the run has {of}"));
        }
        if b[11] != 0 {
            return Err(format!("reserved byte {}", b[11]));
        }
        let (x_m, y_m, theta_rad) = (f32_at(12), f32_at(16), f32_at(20));
        if !(x_m.is_finite() && y_m.is_finite() && theta_rad.is_finite()) {
            return Err(format!("non-finite pose ({x_m}, {y_m}, {theta_rad})"));
        }
        let mut t = [0u8; 8];
        t.copy_from_slice(&b[..8]);
        Ok(PoseSample {
            t_ns: u64::from_le_bytes(t),
            robot,
            source,
            x_m,
            y_m,
            theta_rad,
        })
    }
}

/// Appends samples to a new `trajectories.bin`, up to a size cap.
pub struct TrajectoryWriter {
    path: PathBuf,
    out: Pending,
    header: TrajectoryHeader,
    max_bytes: u64,
    written: Written,
}

impl TrajectoryWriter {
    /// Creates (or replaces) the file and writes its header. Samples stop being written once
    /// the file would grow past `max_bytes` (at least the header is always written).
    pub fn create(
        path: &Path,
        header: TrajectoryHeader,
        max_bytes: u64,
    ) -> Result<Self, RecordingError> {
        let file = File::create(path).map_err(io(path))?;
        let mut out = Pending::new(Appender::new(file, 0));
        out.buf.extend_from_slice(&header.encode());
        Ok(TrajectoryWriter {
            path: path.to_path_buf(),
            out,
            header,
            max_bytes,
            written: Written {
                bytes: HEADER_LEN as u64,
                ..Written::default()
            },
        })
    }

    /// Appends one sample; `Ok(false)` when the cap dropped it.
    pub fn push(&mut self, s: &PoseSample) -> Result<bool, RecordingError> {
        if self.written.bytes + SAMPLE_LEN as u64 > self.max_bytes {
            self.written.dropped += 1;
            return Ok(false);
        }
        self.out.buf.extend_from_slice(&s.encode());
        self.out.write_full().map_err(io(&self.path))?;
        self.written.records += 1;
        self.written.bytes += SAMPLE_LEN as u64;
        Ok(true)
    }

    /// Counts so far.
    pub fn written(&self) -> Written {
        self.written
    }

    /// Writes the samples, marks the header truncated if any were dropped, and syncs the
    /// file: the recording is durable when it returns.
    pub fn finish(mut self) -> Result<Written, RecordingError> {
        self.out.flush().map_err(io(&self.path))?;
        if self.written.dropped > 0 {
            self.header.truncated = true;
            self.out
                .out
                .file()
                .write_at(0, &self.header.encode())
                .map_err(io(&self.path))?;
        }
        self.out.finish().map_err(io(&self.path))?;
        Ok(self.written)
    }
}

/// Reads a `trajectories.bin`.
pub struct TrajectoryReader {
    path: PathBuf,
    frames: Option<FrameReader<Fixed>>,
    header: TrajectoryHeader,
    torn: Option<Torn>,
}

impl TrajectoryReader {
    /// Opens the file and checks its header.
    pub fn open(path: &Path) -> Result<Self, RecordingError> {
        let file = File::open(path).map_err(io(path))?;
        let len = file.metadata().map_err(io(path))?.len();
        let mut input = BufReader::new(file);
        let mut b = [0u8; HEADER_LEN];
        match input.read_exact(&mut b) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
                return Err(RecordingError::BadMagic {
                    path: path.to_path_buf(),
                    what: WHAT,
                })
            }
            Err(e) => return Err(io(path)(e)),
        }
        let header = TrajectoryHeader::decode(&b, path)?;
        let samples = Fixed {
            len: SAMPLE_LEN as u32,
        };
        Ok(TrajectoryReader {
            path: path.to_path_buf(),
            frames: Some(FrameReader::new(
                samples,
                input,
                HEADER_LEN as u64,
                len,
                true,
            )),
            header,
            torn: None,
        })
    }

    /// The file's header.
    pub fn header(&self) -> &TrajectoryHeader {
        &self.header
    }

    /// The next sample; `Ok(None)` at the end. A partial sample at the end of the file is a
    /// torn tail (the writer was killed): it reads as the end, and
    /// [`TrajectoryReader::torn`] tells where it is.
    pub fn next_sample(&mut self) -> Result<Option<PoseSample>, RecordingError> {
        let Some((offset, ())) = frame_step(&mut self.frames, &mut self.torn, &self.path)? else {
            return Ok(None);
        };
        let mut b = [0u8; SAMPLE_LEN];
        if let Some(frames) = &self.frames {
            b.copy_from_slice(frames.payload());
        }
        let s =
            PoseSample::decode(&b, &self.header).map_err(|problem| RecordingError::Corrupt {
                path: self.path.clone(),
                offset,
                problem,
            })?;
        Ok(Some(s))
    }

    /// Every remaining sample, and the bytes of a torn tail (0 if none).
    pub fn read_all(mut self) -> Result<(Vec<PoseSample>, u64), RecordingError> {
        let mut out = Vec::new();
        while let Some(s) = self.next_sample()? {
            out.push(s);
        }
        Ok((out, self.torn_tail()))
    }

    /// Bytes of a partial sample found at the end (0 until the end is reached, or if none).
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

    fn header() -> TrajectoryHeader {
        TrajectoryHeader {
            robots: 3,
            rate_hz: 20,
            cell_size_m: 0.16,
            width: 32,
            height: 32,
            truncated: false,
            control_period_us: 10_000,
            movers: 0,
        }
    }

    fn sample(i: u64) -> PoseSample {
        PoseSample {
            t_ns: i * 50_000_000,
            robot: (i % 3) as u16,
            source: if i.is_multiple_of(2) {
                PoseSource::Truth
            } else {
                PoseSource::Estimate
            },
            x_m: i as f32 * 0.01,
            y_m: 1.0 - i as f32 * 0.01,
            theta_rad: -0.5,
        }
    }

    #[test]
    fn mover_samples_are_checked_against_the_movers_not_the_robots() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.bin");
        let h = TrajectoryHeader {
            movers: 2,
            ..header()
        };
        let mut w = TrajectoryWriter::create(&path, h, u64::MAX).unwrap();
        let mover = |robot| PoseSample {
            robot,
            source: PoseSource::Mover,
            ..sample(0)
        };
        w.push(&mover(1)).unwrap();
        w.push(&mover(2)).unwrap();
        w.finish().unwrap();
        let mut r = TrajectoryReader::open(&path).unwrap();
        assert_eq!(r.header().movers, 2);
        assert_eq!(r.next_sample().unwrap(), Some(mover(1)));
        let e = r.next_sample().unwrap_err().to_string();
        assert!(e.contains("mover 2, the run has 2"), "{e}");
    }

    #[test]
    fn samples_round_trip_and_the_cap_truncates() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.bin");
        let cap = (HEADER_LEN + 10 * SAMPLE_LEN) as u64;
        let mut w = TrajectoryWriter::create(&path, header(), cap).unwrap();
        for i in 0..15 {
            assert_eq!(w.push(&sample(i)).unwrap(), i < 10);
        }
        let written = w.finish().unwrap();
        assert_eq!(
            (written.records, written.dropped, written.bytes),
            (10, 5, cap)
        );
        assert_eq!(std::fs::metadata(&path).unwrap().len(), cap);
        let r = TrajectoryReader::open(&path).unwrap();
        assert!(r.header().truncated);
        assert_eq!(r.header().width, 32);
        let (samples, torn) = r.read_all().unwrap();
        assert_eq!(torn, 0);
        assert_eq!(samples, (0..10).map(sample).collect::<Vec<_>>());
    }

    #[test]
    fn a_torn_tail_is_skipped_and_measured() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.bin");
        let mut w = TrajectoryWriter::create(&path, header(), u64::MAX).unwrap();
        for i in 0..4 {
            w.push(&sample(i)).unwrap();
        }
        w.finish().unwrap();
        let f = std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .unwrap();
        f.set_len((HEADER_LEN + 3 * SAMPLE_LEN + 7) as u64).unwrap();
        let mut r = TrajectoryReader::open(&path).unwrap();
        let mut samples = 0;
        while r.next_sample().unwrap().is_some() {
            samples += 1;
        }
        assert_eq!((samples, r.torn_tail()), (3, 7));
        let torn = r.torn().unwrap().to_string();
        assert_eq!(
            torn,
            "torn tail cut at offset 104 (7 bytes: record length 24 runs past the end of the file (7 bytes left))"
        );
    }

    #[test]
    fn bad_files_name_what_is_wrong() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.bin");
        std::fs::write(&path, b"HNAVTRJ").unwrap();
        let e = TrajectoryReader::open(&path).err().unwrap();
        assert!(
            e.to_string()
                .ends_with("not an HNAV trajectory file (bad magic or header)"),
            "{e}"
        );
        let mut bytes = header().encode().to_vec();
        bytes[7] = 9;
        std::fs::write(&path, &bytes).unwrap();
        let e = TrajectoryReader::open(&path).err().unwrap();
        assert!(
            e.to_string()
                .ends_with("trajectory format version 9, this build reads version 1"),
            "{e}"
        );
        let mut bytes = header().encode().to_vec();
        let mut s = sample(1).encode();
        s[8] = 7; // robot 7 of 3
        bytes.extend_from_slice(&sample(0).encode());
        bytes.extend_from_slice(&s);
        std::fs::write(&path, &bytes).unwrap();
        let mut r = TrajectoryReader::open(&path).unwrap();
        assert!(r.next_sample().unwrap().is_some());
        let e = r.next_sample().err().unwrap();
        assert!(
            e.to_string()
                .ends_with("at byte 56: robot 7, the run has 3"),
            "{e}"
        );
    }
}
