//! The crash test of `runtime::durable`: every durable write of every file kind cut at every
//! file operation, and the cutting write also torn at byte offsets, through a fault-injecting
//! [`Disk`]. After each cut the files are read back as a restarted process reads them, and
//! the outcome must be the old state, the new state, or a located torn tail ("torn tail cut
//! at offset N") or refused slot; never a record that was acknowledged (its write and its
//! fsync returned Ok) missing, and never corruption.
//!
//! A cut is a crash: the operation it falls on fails (a write leaves only its first `k`
//! bytes, or `k` zero bytes: a file system that extended the file before the data reached
//! the disk) and every later operation fails too. The test prints the cut points it tried
//! per file kind and the acknowledged records lost (0).

use std::cell::Cell;
use std::fmt;
use std::io;
use std::path::Path;
use std::rc::Rc;

use hnav_runtime::consensus_log::{
    read_log, EndReason, EndRecord, LogError, LogWriter, Record, RunHeader, WriterOptions,
    FORMAT_VERSION,
};
use hnav_runtime::durable::framed::seal_checksummed;
use hnav_runtime::durable::{
    replace_file_on, Appender, Checksummed, Disk, DiskFile, Fixed, FrameFormat, FrameProblem,
    FrameReader, RealDisk, SlotFile, SlotLayout, SlotLen, SlotPair, SlotRead, Step,
};
use hnav_runtime::scenario::FsyncPolicy;

/// How the operation a cut falls on fails.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Tear {
    /// A write keeps its first `k` bytes.
    Prefix(usize),
    /// A write leaves `k` zero bytes.
    Zeros(usize),
}

/// Where the crash falls, and what has happened so far.
#[derive(Debug, Default)]
struct Plan {
    ops: Cell<u64>,
    cut_at: Cell<Option<u64>>,
    tear: Cell<Option<Tear>>,
    /// Only the cut operation fails; later ones succeed (an fsync error the process outlives).
    survive: Cell<bool>,
    crashed: Cell<bool>,
    /// The length of the write the cut fell on, if it fell on a write.
    cut_write: Cell<Option<usize>>,
}

enum Gate {
    Go,
    Cut,
    Dead,
}

impl Plan {
    fn cut(at: u64, tear: Option<Tear>) -> Rc<Plan> {
        let p = Plan::default();
        p.cut_at.set(Some(at));
        p.tear.set(tear);
        Rc::new(p)
    }

    fn gate(&self) -> Gate {
        if self.crashed.get() {
            return Gate::Dead;
        }
        let n = self.ops.get();
        self.ops.set(n + 1);
        if self.cut_at.get() == Some(n) {
            self.crashed.set(!self.survive.get());
            return Gate::Cut;
        }
        Gate::Go
    }
}

fn crash() -> io::Error {
    io::Error::other("cut by the crash test")
}

#[derive(Clone, Debug)]
struct FaultDisk(Rc<Plan>);

#[derive(Debug)]
struct FaultFile {
    file: std::fs::File,
    plan: Rc<Plan>,
}

impl FaultDisk {
    fn pass(&self) -> io::Result<()> {
        match self.0.gate() {
            Gate::Go => Ok(()),
            Gate::Cut | Gate::Dead => Err(crash()),
        }
    }

    fn file(&self, file: std::fs::File) -> FaultFile {
        FaultFile {
            file,
            plan: self.0.clone(),
        }
    }
}

impl Disk for FaultDisk {
    type File = FaultFile;

    fn create_new(&self, path: &Path) -> io::Result<FaultFile> {
        self.pass()?;
        Ok(self.file(RealDisk.create_new(path)?))
    }

    fn open_or_create(&self, path: &Path) -> io::Result<FaultFile> {
        self.pass()?;
        Ok(self.file(RealDisk.open_or_create(path)?))
    }

    fn rename(&self, from: &Path, to: &Path) -> io::Result<()> {
        self.pass()?;
        RealDisk.rename(from, to)
    }

    fn remove_file(&self, path: &Path) -> io::Result<()> {
        self.pass()?;
        RealDisk.remove_file(path)
    }

    /// Counted and cut, but not made: a cut is a crash of the process, whose page cache the
    /// reader sees, so the real fsyncs would only make the test slow.
    fn sync_dir(&self, _: &Path) -> io::Result<()> {
        self.pass()
    }
}

impl DiskFile for FaultFile {
    fn write_at(&self, offset: u64, bytes: &[u8]) -> io::Result<()> {
        match self.plan.gate() {
            Gate::Go => self.file.write_at(offset, bytes),
            Gate::Dead => Err(crash()),
            Gate::Cut => {
                self.plan.cut_write.set(Some(bytes.len()));
                match self.plan.tear.get() {
                    Some(Tear::Prefix(k)) => {
                        self.file.write_at(offset, &bytes[..k.min(bytes.len())])?
                    }
                    Some(Tear::Zeros(k)) => {
                        self.file.write_at(offset, &vec![0; k.min(bytes.len())])?
                    }
                    None => {}
                }
                Err(crash())
            }
        }
    }

    fn set_len(&self, len: u64) -> io::Result<()> {
        match self.plan.gate() {
            Gate::Go => DiskFile::set_len(&self.file, len),
            Gate::Cut | Gate::Dead => Err(crash()),
        }
    }

    /// Counted and cut, but not made (see [`FaultDisk::sync_dir`]).
    fn sync_data(&self) -> io::Result<()> {
        match self.plan.gate() {
            Gate::Go => Ok(()),
            Gate::Cut | Gate::Dead => Err(crash()),
        }
    }

    fn size(&self) -> io::Result<u64> {
        self.file.size()
    }
}

/// The tears tried at a cut that falls on a write of up to `len` bytes: none, and the write
/// cut after every byte offset, as a prefix or as zeros.
fn tears(len: usize) -> Vec<Option<Tear>> {
    let mut out = vec![None];
    for k in 1..len {
        out.push(Some(Tear::Prefix(k)));
        out.push(Some(Tear::Zeros(k)));
    }
    out
}

/// A fresh directory, in memory where the machine has `/dev/shm`: the test makes thousands
/// of files, and the disk's speed is not what it measures.
fn scratch() -> tempfile::TempDir {
    tempfile::tempdir_in("/dev/shm")
        .or_else(|_| tempfile::tempdir())
        .unwrap()
}

/// Cut points tried and records lost, per file kind.
#[derive(Default)]
struct Tally {
    cuts: u64,
    torn_reported: u64,
    lost: u64,
}

impl Tally {
    fn count(&mut self, lost: u64, torn: bool) {
        self.cuts += 1;
        self.lost += lost;
        self.torn_reported += u64::from(torn);
    }
}

impl fmt::Display for Tally {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} cut points, {} torn tails or torn slots reported, {} acknowledged records lost",
            self.cuts, self.torn_reported, self.lost
        )
    }
}

/// Runs `attempt` at every cut point of a write sequence: first uncut, to count its
/// operations, then cut at each one (with every tear for a write). `attempt` gets a fresh
/// directory and the disk, and returns the records it lost and whether a torn state was
/// reported.
fn every_cut(
    tally: &mut Tally,
    write_len: usize,
    mut attempt: impl FnMut(&Path, FaultDisk) -> (u64, bool),
) {
    let dir = scratch();
    let plan = Rc::new(Plan::default());
    let (lost, _) = attempt(dir.path(), FaultDisk(plan.clone()));
    assert_eq!(lost, 0, "a run without a crash lost records");
    let ops = plan.ops.get();
    for at in 0..ops {
        for tear in tears(write_len) {
            let dir = scratch();
            let plan = Plan::cut(at, tear);
            let (lost, torn) = attempt(dir.path(), FaultDisk(plan.clone()));
            let (Some(Tear::Prefix(k) | Tear::Zeros(k)), written) = (tear, plan.cut_write.get())
            else {
                tally.count(lost, torn);
                continue;
            };
            if written.is_none_or(|len| k >= len) {
                continue; // no write torn at k: another try covered this cut
            }
            tally.count(lost, torn);
        }
    }
}

#[test]
fn replaced_files_are_old_or_new_after_any_cut() {
    let mut tally = Tally::default();
    let (old, new) = (
        b"old contents\n".as_slice(),
        b"new contents, longer\n".as_slice(),
    );
    every_cut(&mut tally, new.len(), |dir, disk| {
        let path = dir.join("summary.json");
        std::fs::write(&path, old).unwrap();
        let result = replace_file_on(&disk, &path, new);
        let now = std::fs::read(&path).unwrap();
        assert!(now == old || now == new, "{now:?}");
        (u64::from(result.is_ok() && now != new), false)
    });
    println!("replaced file: {tally}");
    assert!(tally.cuts >= 10, "{}", tally.cuts);
    assert_eq!(tally.lost, 0);
}

const SLOT: SlotLayout = SlotLayout {
    magic: 0x5445_5354_534c_4f54,
    what: "test slot",
    len: SlotLen::Stored { at: 8, base: 16 },
};

/// A slot payload: sequence number, length word, `seq` repeated over 150 bytes.
fn slot_fill(seq: u64) -> impl FnOnce(&mut Vec<u8>) {
    move |b: &mut Vec<u8>| {
        b.extend_from_slice(&seq.to_le_bytes());
        b.extend_from_slice(&[0; 8]);
        b.extend(std::iter::repeat_n(seq as u8, 150));
    }
}

fn slot_seq(payload: &[u8]) -> u64 {
    u64::from_le_bytes(payload[..8].try_into().unwrap())
}

#[test]
fn a_slot_is_old_new_or_refused_and_a_pair_old_or_new_after_any_cut() {
    let slot_len = 8 + 16 + 150 + 8;
    let mut single = Tally::default();
    every_cut(&mut single, slot_len, |dir, disk| {
        let path = dir.join("agent.ckpt");
        SlotFile::new(&path, SLOT).store(slot_fill(1)).unwrap();
        let stored = SlotFile::on(disk, &path, SLOT).store(slot_fill(2));
        match SlotFile::new(&path, SLOT).load().unwrap() {
            SlotRead::Usable(p) => {
                let seq = slot_seq(&p);
                assert!(seq == 1 || seq == 2, "{seq}");
                (u64::from(stored.is_ok() && seq != 2), false)
            }
            // Refused by its checksum: the torn slot is reported, not taken for a state.
            SlotRead::Unusable(what) => {
                assert!(stored.is_err(), "{what}");
                (0, true)
            }
            SlotRead::Missing => (1, false),
        }
    });
    println!("checkpoint slot (one file, agent): {single}");
    let mut pair = Tally::default();
    every_cut(&mut pair, slot_len, |dir, disk| {
        let paths = ["sim.ckpt.0", "sim.ckpt.1"].map(|n| dir.join(n));
        let mut real = SlotPair::new(paths.clone(), SLOT);
        for seq in [1, 2] {
            real.store(seq, slot_fill(seq)).unwrap();
        }
        let stored = SlotPair::on(|| disk.clone(), paths.clone(), SLOT).store(3, slot_fill(3));
        let torn = matches!(
            SlotFile::new(&paths[1], SLOT).load().unwrap(),
            SlotRead::Unusable(_)
        );
        let reread = SlotPair::new(paths, SLOT);
        let newest = reread.load(|p| Ok(slot_seq(p))).unwrap().expect("a slot");
        assert!(newest.seq == 2 || newest.seq == 3, "{}", newest.seq);
        (u64::from(stored.is_ok() && newest.seq != 3), torn)
    });
    println!("checkpoint slot pair (sim): {pair}");
    assert!(single.cuts >= 7 && pair.cuts >= 7);
    assert_eq!(single.lost + pair.lost, 0);
}

fn header() -> Record {
    Record::Header(RunHeader {
        version: FORMAT_VERSION,
        scenario_hash: 7,
        seed: 1,
        clock: "lockstep".into(),
        width: 4,
        height: 4,
        agents: Vec::new(),
    })
}

fn end(round: u64) -> Record {
    Record::End(EndRecord {
        round,
        at_goal: round as u32,
        reason: EndReason::Stopped,
    })
}

/// Appends a header and ten records under `EveryRecord` with segments of 100 bytes (so that
/// the log rolls over), cut as `disk` says; then reads the log back.
fn cut_log(dir: &Path, disk: FaultDisk, example: &mut Option<String>) -> (u64, bool) {
    let log = dir.join("log");
    let options = WriterOptions {
        fsync: FsyncPolicy::EveryRecord,
        segment_bytes: 100,
    };
    let records: Vec<Record> = std::iter::once(header()).chain((1..=10).map(end)).collect();
    let mut acknowledged = 0;
    if let Ok((mut w, _)) = LogWriter::open_on(disk, &log, options) {
        for r in &records {
            if w.append(r).is_err() {
                break;
            }
            acknowledged += 1;
        }
    }
    let contents = match read_log(&log) {
        Ok(c) => c,
        // The crash came before the first segment's magic was whole on disk.
        Err(LogError::NoSegments { .. }) => return (acknowledged, false),
        Err(e) => panic!("after a cut: {e}"),
    };
    let n = contents.records.len();
    assert!(
        n <= acknowledged as usize + 1,
        "{n} records, {acknowledged} acknowledged"
    );
    assert_eq!(
        contents.records[..],
        records[..n],
        "the log is a prefix of what was written"
    );
    if let Some(t) = &contents.torn {
        example.get_or_insert_with(|| t.to_string());
        assert!(t.to_string().contains("torn tail cut at offset"));
    }
    // A restarted writer cuts the torn tail and goes on.
    let quick = WriterOptions {
        fsync: FsyncPolicy::None,
        ..options
    };
    let (mut w, recovered) = LogWriter::open_with(&log, quick).unwrap();
    assert_eq!(recovered.records.len(), n);
    if n == 0 {
        w.append(&header()).unwrap();
    }
    w.append(&end(99)).unwrap();
    drop(w);
    let after = read_log(&log).unwrap();
    assert!(after.torn.is_none());
    assert_eq!(after.records.last(), Some(&end(99)));
    let lost = (acknowledged as usize).saturating_sub(n) as u64;
    (lost, contents.torn.is_some())
}

#[test]
fn a_consensus_log_loses_no_acknowledged_record_at_any_cut() {
    let mut tally = Tally::default();
    let mut example = None;
    // The longest write: the header's frame.
    let mut frame = Vec::new();
    hnav_runtime::consensus_log::encode_frame(&header(), &mut frame).unwrap();
    every_cut(&mut tally, frame.len(), |dir, disk| {
        cut_log(dir, disk, &mut example)
    });
    println!("consensus-log segments: {tally}");
    println!("  e.g. {}", example.unwrap_or_default());
    assert!(tally.cuts >= 100, "{}", tally.cuts);
    assert!(tally.torn_reported > 0);
    assert_eq!(tally.lost, 0);
}

/// A failed fsync is never retried: the writer names the file and refuses every later
/// append until the log is reopened; the reopened log holds every record acknowledged before.
#[test]
fn a_failed_fsync_poisons_the_log_writer() {
    let dir = scratch();
    let log = dir.path().join("log");
    let plan = Rc::new(Plan::default());
    let options = WriterOptions::new(FsyncPolicy::EveryRecord);
    let (mut w, _) = LogWriter::open_on(FaultDisk(plan.clone()), &log, options).unwrap();
    w.append(&header()).unwrap();
    // The next operations: the frame's write, then its fsync, which fails.
    plan.cut_at.set(Some(plan.ops.get() + 1));
    plan.survive.set(true);
    let e = w.append(&end(1)).unwrap_err().to_string();
    assert!(
        e.contains("seg-00000000.hlog") && e.contains("fsync failed"),
        "{e}"
    );
    let e = w.append(&end(2)).unwrap_err().to_string();
    assert!(e.contains("poisoned") || e.contains("reopen"), "{e}");
    drop(w);
    let records = read_log(&log).unwrap().records;
    assert_eq!(records[0], header());
}

/// A recording-like framed file: `magic`, then frames appended in chunks of three through an
/// [`Appender`], synced once at the end (what `maps.bin` and `trajectories.bin` do).
fn cut_recording<F: FrameFormat>(
    dir: &Path,
    disk: FaultDisk,
    format: F,
    frames: &[Vec<u8>],
    example: &mut Option<String>,
) -> (u64, bool) {
    let path = dir.join("recording.bin");
    let magic = b"HNAVTST\x01";
    let finished = (|| {
        let f = disk.create_new(&path)?;
        let mut out = Appender::new(f, 0);
        out.append(magic)?;
        for chunk in frames.chunks(3) {
            out.append(&chunk.concat())?;
        }
        out.sync()
    })();
    let Ok(bytes) = std::fs::read(&path) else {
        return (u64::from(finished.is_ok()), false);
    };
    if bytes.len() < magic.len() {
        assert!(finished.is_err());
        return (0, false);
    }
    let file = std::fs::File::open(&path).unwrap();
    let mut reader = FrameReader::open(format, file, magic.len() as u64, true).unwrap();
    let mut read = 0;
    let torn = loop {
        match reader.step() {
            Ok(Step::Frame { offset, len, .. }) => {
                let at = offset as usize;
                assert_eq!(&bytes[at..at + len as usize], &frames[read][..]);
                read += 1;
            }
            Ok(Step::End) => break None,
            Ok(Step::Torn(t)) => break Some(t),
            Err(e) => panic!("after a cut: {e:?}"),
        }
    };
    if let Some(t) = &torn {
        example.get_or_insert_with(|| t.to_string());
    }
    let lost = if finished.is_ok() {
        (frames.len() - read) as u64
    } else {
        0
    };
    (lost, torn.is_some())
}

#[test]
fn recordings_read_back_whole_or_with_a_located_torn_tail_at_any_cut() {
    // maps.bin's frames: len | crc32c | body of 40 + 4 cells bytes.
    let maps = Checksummed {
        min_len: 40,
        max_len: 40 + 4 * 64,
        decode: |_: &[u8]| Ok::<(), FrameProblem>(()),
    };
    let map_frames: Vec<Vec<u8>> = (0..7u8)
        .map(|i| {
            let mut f = vec![0; 8];
            f.extend((0..40 + 4 * 6).map(|j| i.wrapping_mul(31).wrapping_add(j as u8)));
            seal_checksummed(&mut f, 0);
            f
        })
        .collect();
    let mut tally = Tally::default();
    let mut example = None;
    let chunk = 3 * map_frames[0].len();
    every_cut(&mut tally, chunk, |dir, disk| {
        cut_recording(dir, disk, maps, &map_frames, &mut example)
    });
    println!("recording maps.bin frames: {tally}");
    println!("  e.g. {}", example.take().unwrap_or_default());
    assert_eq!(tally.lost, 0);
    // trajectories.bin's samples: 24 bytes each, no checksum.
    let samples: Vec<Vec<u8>> = (0..7u8).map(|i| vec![i + 1; 24]).collect();
    let mut fixed = Tally::default();
    every_cut(&mut fixed, 3 * 24, |dir, disk| {
        cut_recording(dir, disk, Fixed { len: 24 }, &samples, &mut example)
    });
    println!("recording trajectories.bin samples: {fixed}");
    println!("  e.g. {}", example.unwrap_or_default());
    assert!(tally.cuts >= 10 && fixed.cuts >= 10);
    assert_eq!(fixed.lost, 0);
}
