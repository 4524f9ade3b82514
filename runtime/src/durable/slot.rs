//! Checkpoint slots: a small record rewritten in place (one `pwrite` at offset 0, no new
//! file, no rename) in a file that is opened once, for state written every control period.
//!
//! A slot holds `u64 LE magic | payload | u64 LE FNV-1a 64 of magic and payload`. The payload
//! is the owner's; its length is fixed or stored in it ([`SlotLen`]), so that a shorter record
//! over a longer one is bounded by its own length, not the file's.
//!
//! Slots are not fsynced: they are for a process killed (SIGKILL) and restarted, whose
//! written pages the kernel keeps; a machine crash ends the run anyway, and an fsync per
//! control period would be the control loop's cost. A SIGKILL can still tear a write that
//! spans pages, which the checksum rejects: a [`SlotFile`] then reads
//! [`SlotRead::Unusable`], and a [`SlotPair`] (two files written alternately) falls back to
//! its other, complete slot, one step older.

use std::path::{Path, PathBuf};

use super::disk::{Disk, DiskFile, RealDisk};
use crate::hash::Fnv1a64;

/// How long a slot's payload is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlotLen {
    /// Always this many bytes.
    Fixed(usize),
    /// `base` bytes plus the `u64 LE` stored at payload offset `at` (which lies inside the
    /// base); [`SlotFile::store`] fills it in.
    Stored {
        /// Offset of the length word in the payload.
        at: usize,
        /// Bytes of the payload not counted by the length word.
        base: usize,
    },
}

/// A slot format: the owner's magic, its name in messages, and how long its payload is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SlotLayout {
    /// The first 8 bytes (little-endian): names the owner and its format version.
    pub magic: u64,
    /// What a slot holds, for messages: `sim checkpoint`.
    pub what: &'static str,
    /// The payload's length.
    pub len: SlotLen,
}

impl SlotLayout {
    /// The shortest payload: the fixed length, or the base (which holds the length word).
    fn min_payload(&self) -> usize {
        match self.len {
            SlotLen::Fixed(n) => n,
            SlotLen::Stored { at, base } => base.max(at + 8),
        }
    }

    /// The payload of a slot file's `bytes`, or what is wrong with them.
    pub fn check<'b>(&self, bytes: &'b [u8]) -> Result<&'b [u8], String> {
        if bytes.len() < 16 + self.min_payload() {
            return Err(format!("too short for a {}", self.what));
        }
        if u64_at(bytes, 0) != self.magic {
            return Err(format!("not a {} of this version", self.what));
        }
        let payload = match self.len {
            SlotLen::Fixed(n) => n,
            SlotLen::Stored { at, base } => usize::try_from(u64_at(bytes, 8 + at))
                .ok()
                .and_then(|n| n.checked_add(base))
                .ok_or("length beyond the file (torn or damaged)")?,
        };
        let end = payload
            .checked_add(8)
            .filter(|end| end.checked_add(8).is_some_and(|e| e <= bytes.len()))
            .ok_or("length beyond the file (torn or damaged)")?;
        if Fnv1a64::new().bytes(&bytes[..end]).finish() != u64_at(bytes, end) {
            return Err("checksum mismatch (torn or damaged)".into());
        }
        Ok(&bytes[8..end])
    }
}

/// What a slot file holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SlotRead {
    /// No file.
    Missing,
    /// A complete slot: its payload.
    Usable(Vec<u8>),
    /// A file that holds no complete slot of this layout (empty, torn, damaged, foreign).
    Unusable(String),
}

/// One slot file, opened on the first store; see the [module docs](self).
#[derive(Debug)]
pub struct SlotFile<D: Disk = RealDisk> {
    disk: D,
    path: PathBuf,
    layout: SlotLayout,
    file: Option<D::File>,
    buf: Vec<u8>,
}

impl SlotFile<RealDisk> {
    /// The slot file `path` (nothing is opened yet).
    pub fn new(path: &Path, layout: SlotLayout) -> Self {
        Self::on(RealDisk, path, layout)
    }
}

impl<D: Disk> SlotFile<D> {
    /// The slot file `path` on `disk`.
    pub fn on(disk: D, path: &Path, layout: SlotLayout) -> Self {
        Self {
            disk,
            path: path.to_path_buf(),
            layout,
            file: None,
            buf: Vec::new(),
        }
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Opens the file now (creating it empty), so that a file that cannot be written is
    /// found at start-up rather than at the first store.
    pub fn open(&mut self) -> std::io::Result<&D::File> {
        if self.file.is_none() {
            self.file = Some(self.disk.open_or_create(&self.path)?);
        }
        Ok(self.file.as_ref().expect("opened above"))
    }

    /// Writes a slot whose payload `fill` appends to the buffer it is given, with one
    /// `pwrite` at offset 0. The buffer is reused: a store allocates nothing once it has
    /// grown to the largest slot.
    pub fn store(&mut self, fill: impl FnOnce(&mut Vec<u8>)) -> std::io::Result<()> {
        let mut buf = std::mem::take(&mut self.buf);
        buf.clear();
        buf.extend_from_slice(&self.layout.magic.to_le_bytes());
        fill(&mut buf);
        if let SlotLen::Stored { at, base } = self.layout.len {
            let counted = (buf.len() - 8).saturating_sub(base) as u64;
            buf[8 + at..16 + at].copy_from_slice(&counted.to_le_bytes());
        }
        let sum = Fnv1a64::new().bytes(&buf).finish();
        buf.extend_from_slice(&sum.to_le_bytes());
        let written = self.open().and_then(|f| f.write_at(0, &buf));
        self.buf = buf;
        written
    }

    /// What the file holds now.
    pub fn load(&self) -> std::io::Result<SlotRead> {
        let bytes = match std::fs::read(&self.path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(SlotRead::Missing),
            Err(e) => return Err(e),
        };
        Ok(match self.layout.check(&bytes) {
            Ok(payload) => SlotRead::Usable(payload.to_vec()),
            Err(what) => SlotRead::Unusable(what),
        })
    }
}

/// Two slot files written alternately by a sequence number the payload carries, so that a
/// torn store leaves the other slot, one step older, complete.
#[derive(Debug)]
pub struct SlotPair<D: Disk = RealDisk> {
    slots: [SlotFile<D>; 2],
}

/// The newest slot of a [`SlotPair`] its owner accepted.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Newest<'p> {
    /// Its sequence number.
    pub seq: u64,
    /// Its file.
    pub path: &'p Path,
    /// Its payload.
    pub payload: Vec<u8>,
}

/// Why no slot of a [`SlotPair`] could be used.
#[derive(Debug, thiserror::Error)]
pub enum PairError {
    /// A slot file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// A slot file exists but holds nothing usable (and neither does the other).
    #[error("{}: {what}", path.display())]
    Unusable {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        what: String,
    },
}

impl SlotPair<RealDisk> {
    /// The pair of slot files `paths`.
    pub fn new(paths: [PathBuf; 2], layout: SlotLayout) -> Self {
        Self::on(|| RealDisk, paths, layout)
    }
}

impl<D: Disk> SlotPair<D> {
    /// The pair of slot files `paths` on the disks `disk` makes.
    pub fn on(disk: impl Fn() -> D, paths: [PathBuf; 2], layout: SlotLayout) -> Self {
        Self {
            slots: paths.map(|p| SlotFile::on(disk(), &p, layout)),
        }
    }

    /// The file sequence number `seq` is stored in.
    pub fn path(&self, seq: u64) -> &Path {
        self.slots[(seq % 2) as usize].path()
    }

    /// Stores the slot of sequence number `seq` (which `fill` must write into the payload)
    /// in slot `seq % 2`.
    pub fn store(&mut self, seq: u64, fill: impl FnOnce(&mut Vec<u8>)) -> std::io::Result<()> {
        self.slots[(seq % 2) as usize].store(fill)
    }

    /// The newest slot `accept` takes (it gives the slot's sequence number, or refuses the
    /// payload in words): `Ok(None)` when neither file exists, an error naming the file when
    /// a file exists but no slot is accepted.
    pub fn load(
        &self,
        accept: impl Fn(&[u8]) -> Result<u64, String>,
    ) -> Result<Option<Newest<'_>>, PairError> {
        let mut best: Option<Newest<'_>> = None;
        let mut refused = None;
        for slot in &self.slots {
            let path = slot.path();
            let unusable = |what| PairError::Unusable {
                path: path.to_path_buf(),
                what,
            };
            match slot.load() {
                Err(source) => {
                    return Err(PairError::Io {
                        path: path.to_path_buf(),
                        source,
                    })
                }
                Ok(SlotRead::Missing) => {}
                Ok(SlotRead::Unusable(what)) => refused = Some(unusable(what)),
                Ok(SlotRead::Usable(payload)) => match accept(&payload) {
                    Ok(seq) if best.as_ref().is_none_or(|b| seq > b.seq) => {
                        best = Some(Newest { seq, path, payload });
                    }
                    Ok(_) => {}
                    Err(what) => refused = Some(unusable(what)),
                },
            }
        }
        match (best, refused) {
            (Some(b), _) => Ok(Some(b)),
            (None, Some(e)) => Err(e),
            (None, None) => Ok(None),
        }
    }
}

/// The little-endian `u64` at byte `offset` of `bytes` (`bytes` holds it).
fn u64_at(bytes: &[u8], offset: usize) -> u64 {
    let mut w = [0u8; 8];
    w.copy_from_slice(&bytes[offset..offset + 8]);
    u64::from_le_bytes(w)
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAYOUT: SlotLayout = SlotLayout {
        magic: 0x1234,
        what: "test slot",
        len: SlotLen::Stored { at: 8, base: 16 },
    };

    fn fill(seq: u64, body: &[u8]) -> impl FnOnce(&mut Vec<u8>) + '_ {
        move |b: &mut Vec<u8>| {
            b.extend_from_slice(&seq.to_le_bytes());
            b.extend_from_slice(&[0; 8]);
            b.extend_from_slice(body);
        }
    }

    #[test]
    fn a_shorter_slot_over_a_longer_one_is_bounded_by_its_length() {
        let dir = tempfile::tempdir().unwrap();
        let mut s = SlotFile::new(&dir.path().join("s"), LAYOUT);
        assert_eq!(s.load().unwrap(), SlotRead::Missing);
        s.store(fill(1, &[7; 100])).unwrap();
        s.store(fill(2, &[9; 3])).unwrap();
        let SlotRead::Usable(p) = s.load().unwrap() else {
            panic!()
        };
        assert_eq!(p.len(), 16 + 3);
        assert_eq!(&p[16..], &[9; 3]);
        assert_eq!(u64_at(&p, 8), 3, "the stored length counts the body");
    }

    #[test]
    fn damaged_slots_say_what_is_wrong() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s");
        let mut s = SlotFile::new(&path, LAYOUT);
        s.store(fill(1, b"abc")).unwrap();
        let good = std::fs::read(&path).unwrap();
        let reason = |bytes: &[u8]| match LAYOUT.check(bytes) {
            Err(what) => what,
            Ok(_) => panic!("accepted"),
        };
        assert_eq!(reason(&good[..10]), "too short for a test slot");
        let mut b = good.clone();
        b[0] ^= 1;
        assert_eq!(reason(&b), "not a test slot of this version");
        let mut b = good.clone();
        b[26] ^= 1;
        assert_eq!(reason(&b), "checksum mismatch (torn or damaged)");
        let mut b = good.clone();
        b[16..24].copy_from_slice(&u64::MAX.to_le_bytes());
        assert_eq!(reason(&b), "length beyond the file (torn or damaged)");
    }

    #[test]
    fn a_pair_takes_the_newest_accepted_slot() {
        let dir = tempfile::tempdir().unwrap();
        let paths = ["a", "b"].map(|n| dir.path().join(n));
        let mut pair = SlotPair::new(paths, LAYOUT);
        let seq = |p: &[u8]| Ok(u64_at(p, 0));
        assert_eq!(pair.load(seq).unwrap(), None);
        pair.store(4, fill(4, b"four")).unwrap();
        pair.store(5, fill(5, b"five")).unwrap();
        let newest = pair.load(seq).unwrap().unwrap();
        assert_eq!((newest.seq, newest.path), (5, pair.path(5)));
        let e = pair
            .load(|_| Err("foreign".into()))
            .unwrap_err()
            .to_string();
        assert!(e.ends_with("b: foreign"), "{e}");
        // A torn newest slot: the other one.
        let mut torn = std::fs::read(pair.path(5)).unwrap();
        torn[30] ^= 1;
        std::fs::write(pair.path(5), &torn).unwrap();
        assert_eq!(pair.load(seq).unwrap().unwrap().seq, 4);
    }
}
