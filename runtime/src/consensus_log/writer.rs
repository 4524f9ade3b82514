//! The consensus-log writer: [`LogWriter`] appends [`Record`]s to a log directory in the
//! format of the [module docs](super) and makes them durable as the run's [`FsyncPolicy`]
//! asks.
//!
//! The coordinator appends one [`Record::Round`] per decision round and publishes the round's
//! Commit only after [`LogWriter::append`] returned. Durability by policy:
//!
//! | policy | `append` returns after | after a crash |
//! |---|---|---|
//! | [`FsyncPolicy::EveryRecord`] | `fdatasync` of the record | every published commit is in the log |
//! | [`FsyncPolicy::Batched`] | the write; `fdatasync` every [`BATCH_RECORDS`] records or when [`BATCH_INTERVAL`] has passed since the last one (checked on append) | the unsynced tail may be lost, although its commits may already have been published |
//! | [`FsyncPolicy::None`] | the write; never syncs (benchmarks only) | anything not yet written back by the OS may be lost |
//!
//! A writer holds an exclusive lock on [`WRITER_LOCK`] in the log directory from
//! [`LogWriter::open`] until it is dropped, so two processes can never append to one log (a
//! second `open` fails with [`LogError::Locked`]). The kernel drops the lock of a killed
//! writer, so a coordinator restarted with `--resume` after a SIGKILL opens the log again.
//!
//! Under `Batched` and `None` a crash can also damage several unsynced records in an order
//! the reader cannot tell from corruption; under `EveryRecord` only the record in flight can
//! be torn, and reopening cuts exactly that.
//!
//! A Raft replica compacting its log replaces it whole ([`LogWriter::replace`], in
//! `replace`).
//!
//! ```no_run
//! use hnav_runtime::consensus_log::{LogWriter, Record, RunHeader, FORMAT_VERSION};
//! use hnav_runtime::scenario::FsyncPolicy;
//! # fn main() -> Result<(), hnav_runtime::consensus_log::LogError> {
//! let (mut log, recovered) = LogWriter::open("target/run/log", FsyncPolicy::EveryRecord)?;
//! if recovered.records.is_empty() {
//!     log.append(&Record::Header(RunHeader {
//!         version: FORMAT_VERSION,
//!         scenario_hash: 0,
//!         seed: 1,
//!         clock: "lockstep".into(),
//!         width: 8,
//!         height: 8,
//!         agents: Vec::new(),
//!     }))?;
//! }
//! # Ok(())
//! # }
//! ```

mod replace;

pub use replace::{REPLACE_READY, REPLACE_TMP};

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::error::LogError;
use super::frame::{encode_frame, MAGIC};
use super::reader::{check_header, read_log, LogContents, RecordPos, TornTail};
use super::record::Record;
use super::segment::{list_segments, segment_path, DEFAULT_SEGMENT_BYTES};
use crate::durable::{Appender, Disk, DiskFile, RealDisk};
use crate::file_lock::{try_lock, FileLock, TryLock};
use crate::scenario::FsyncPolicy;

/// The writer's lock file in the log directory (ignored by the reader, which reads only
/// segment files).
pub const WRITER_LOCK: &str = ".writer.lock";

/// Under [`FsyncPolicy::Batched`], sync at the latest after this many records.
pub const BATCH_RECORDS: u32 = 32;

/// Under [`FsyncPolicy::Batched`], sync on the first append this long after the last sync.
pub const BATCH_INTERVAL: Duration = Duration::from_millis(20);

const MAGIC_LEN: u64 = MAGIC.len() as u64;

/// How a [`LogWriter`] writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WriterOptions {
    /// When records are made durable.
    pub fsync: FsyncPolicy,
    /// Start a new segment before a record that would take the current one past this size
    /// (a segment always takes at least one record).
    pub segment_bytes: u64,
}

impl WriterOptions {
    /// `fsync` with the default segment size [`DEFAULT_SEGMENT_BYTES`].
    pub fn new(fsync: FsyncPolicy) -> Self {
        Self {
            fsync,
            segment_bytes: DEFAULT_SEGMENT_BYTES,
        }
    }
}

/// What an existing log held when it was opened for writing.
#[derive(Clone, Debug, PartialEq)]
pub struct Recovered {
    /// Every complete record, in order (empty for a new log: append a header first).
    pub records: Vec<Record>,
    /// Where each of `records` is.
    pub positions: Vec<RecordPos>,
    /// Bytes of a torn tail cut off the last segment (0 if there was none).
    pub truncated_bytes: u64,
    /// The torn tail that was cut off, if any.
    pub torn: Option<TornTail>,
}

/// Appends records to a consensus log; see the [module docs](self). Its files are written
/// on a [`Disk`]: the machine's, or a crash test's.
#[derive(Debug)]
pub struct LogWriter<D: Disk = RealDisk> {
    disk: D,
    dir: PathBuf,
    options: WriterOptions,
    file: Appender<D::File>,
    path: PathBuf,
    segment: u32,
    records: u64,
    buf: Vec<u8>,
    unsynced: u32,
    last_sync: Instant,
    poisoned: bool,
    /// Held, never read: the lock lasts as long as the writer.
    _lock: FileLock,
}

impl LogWriter<RealDisk> {
    /// Opens (or creates) the log in `dir` with the default segment size.
    pub fn open(dir: impl AsRef<Path>, policy: FsyncPolicy) -> Result<(Self, Recovered), LogError> {
        Self::open_with(dir, WriterOptions::new(policy))
    }

    /// Opens the log in `dir`, creating the directory and a first segment if needed.
    ///
    /// An existing log is read whole: its complete records come back in [`Recovered`], a torn
    /// tail of the last segment is truncated (and the truncation fsynced), and corruption,
    /// a missing header or a version mismatch is an error with nothing changed.
    pub fn open_with(
        dir: impl AsRef<Path>,
        options: WriterOptions,
    ) -> Result<(Self, Recovered), LogError> {
        Self::open_on(RealDisk, dir, options)
    }
}

impl<D: Disk> LogWriter<D> {
    /// [`LogWriter::open_with`] writing on `disk`.
    pub fn open_on(
        disk: D,
        dir: impl AsRef<Path>,
        options: WriterOptions,
    ) -> Result<(Self, Recovered), LogError> {
        let dir = dir.as_ref().to_path_buf();
        let syncing = options.fsync != FsyncPolicy::None;
        if !dir.is_dir() {
            std::fs::create_dir_all(&dir).map_err(|e| write_error(&dir, &dir, e))?;
            if syncing {
                let parent = dir.parent().filter(|p| !p.as_os_str().is_empty());
                sync_dir(&disk, parent.unwrap_or(Path::new(".")))?;
            }
        }
        let lock = lock_log(&dir)?;
        replace::finish_replace(&disk, &dir, syncing)?;
        let segments = list_segments(&dir)?;
        if segments.is_empty() {
            let path = segment_path(&dir, 0);
            let file = create_segment(&disk, &path, &dir, syncing)?;
            let file = Appender::new(file, MAGIC_LEN);
            let writer = Self::new((disk, dir), options, (file, lock), path, 0, 0);
            let recovered = Recovered {
                records: Vec::new(),
                positions: Vec::new(),
                truncated_bytes: 0,
                torn: None,
            };
            return Ok((writer, recovered));
        }
        let contents = read_log(&dir)?;
        let last = drop_empty_last_segment(&disk, &dir, &segments, &contents, syncing)?;
        let path = segments[last].clone();
        let file = disk
            .open_or_create(&path)
            .map_err(|e| LogError::io(&path, e))?;
        // A torn tail of a dropped segment went with its file.
        let truncated_bytes = contents.torn.as_ref().map_or(0, |t| t.bytes);
        if let Some(torn) = contents
            .torn
            .as_ref()
            .filter(|t| t.segment as usize == last)
        {
            let io = |e| write_error(&dir, &path, e);
            file.set_len(torn.offset).map_err(io)?;
            if torn.offset < MAGIC_LEN {
                file.write_at(0, &MAGIC).map_err(io)?;
            }
            file.sync_data().map_err(io)?;
        }
        let len = file.size().map_err(|e| LogError::io(&path, e))?;
        let records = contents.records.len() as u64;
        let file = Appender::new(file, len);
        let writer = Self::new(
            (disk, dir),
            options,
            (file, lock),
            path,
            last as u32,
            records,
        );
        let recovered = Recovered {
            records: contents.records,
            positions: contents.positions,
            truncated_bytes,
            torn: contents.torn,
        };
        Ok((writer, recovered))
    }

    fn new(
        (disk, dir): (D, PathBuf),
        options: WriterOptions,
        (file, lock): (Appender<D::File>, FileLock),
        path: PathBuf,
        segment: u32,
        records: u64,
    ) -> Self {
        Self {
            _lock: lock,
            disk,
            dir,
            options,
            file,
            path,
            segment,
            records,
            buf: Vec::with_capacity(4096),
            unsynced: 0,
            last_sync: Instant::now(),
            poisoned: false,
        }
    }

    /// Appends `record` with one write call and syncs as the policy asks; returns the
    /// record's byte offset in its segment file ([`segment`](Self::segment) tells which).
    ///
    /// The first record of a log must be a header of
    /// [`FORMAT_VERSION`](super::FORMAT_VERSION). After a failed fsync (or a failed write
    /// that could not be undone) the writer is poisoned: every further call fails with
    /// [`LogError::Poisoned`] and the log must be reopened.
    pub fn append(&mut self, record: &Record) -> Result<u64, LogError> {
        self.check_usable()?;
        let offset = self.write(record)?;
        self.sync_by_policy()?;
        Ok(offset)
    }

    /// Appends `records` in order and then syncs once as the policy asks: under
    /// [`FsyncPolicy::EveryRecord`] all of them are durable when it returns, for the price of
    /// one `fdatasync` (a Raft replica's entries and hard state of one `Ready`).
    pub fn append_all<'r>(
        &mut self,
        records: impl IntoIterator<Item = &'r Record>,
    ) -> Result<(), LogError> {
        self.check_usable()?;
        for record in records {
            self.write(record)?;
        }
        self.sync_by_policy()
    }

    /// Writes one record's frame (rolling to a new segment first if it would not fit).
    fn write(&mut self, record: &Record) -> Result<u64, LogError> {
        if self.records == 0 {
            check_header(&self.path, self.file.len(), record)?;
        }
        self.buf.clear();
        encode_frame(record, &mut self.buf)?;
        let frame = self.buf.len() as u64;
        let len = self.file.len();
        if len > MAGIC_LEN && len + frame > self.options.segment_bytes {
            self.roll()?;
        }
        // A failed write is cut off again (or the appender is poisoned).
        let offset = self.file.append(&self.buf).map_err(|e| {
            self.poisoned |= self.file.is_poisoned();
            write_error(&self.dir, &self.path, e)
        })?;
        self.records += 1;
        self.unsynced += 1;
        Ok(offset)
    }

    /// Syncs if the policy says it is due.
    fn sync_by_policy(&mut self) -> Result<(), LogError> {
        let due = match self.options.fsync {
            FsyncPolicy::EveryRecord => true,
            FsyncPolicy::Batched => {
                self.unsynced >= BATCH_RECORDS || self.last_sync.elapsed() >= BATCH_INTERVAL
            }
            FsyncPolicy::None => false,
        };
        if due {
            self.sync_file()?;
        }
        Ok(())
    }

    /// Makes every appended record durable now, whatever the policy.
    pub fn sync(&mut self) -> Result<(), LogError> {
        self.check_usable()?;
        self.sync_file()
    }

    /// The log directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Number of the segment being written.
    pub fn segment(&self) -> u32 {
        self.segment
    }

    /// Bytes in the segment being written.
    pub fn segment_len(&self) -> u64 {
        self.file.len()
    }

    /// Records in the log (recovered and appended).
    pub fn records(&self) -> u64 {
        self.records
    }

    /// Records appended but not yet synced.
    pub fn unsynced(&self) -> u32 {
        self.unsynced
    }

    /// The options the writer was opened with.
    pub fn options(&self) -> WriterOptions {
        self.options
    }

    fn check_usable(&self) -> Result<(), LogError> {
        if self.poisoned {
            return Err(LogError::Poisoned {
                path: self.path.clone(),
            });
        }
        Ok(())
    }

    fn sync_file(&mut self) -> Result<(), LogError> {
        if self.unsynced > 0 {
            if let Err(e) = self.file.sync() {
                // After a failed fsync the kernel may have dropped the dirty pages: the
                // durable state of the file is unknown (the appender is poisoned too).
                self.poisoned = true;
                return Err(write_error(&self.dir, &self.path, e));
            }
            self.unsynced = 0;
        }
        self.last_sync = Instant::now();
        Ok(())
    }

    /// Closes the current segment (synced, unless the policy is `None`) and starts the next.
    fn roll(&mut self) -> Result<(), LogError> {
        let syncing = self.options.fsync != FsyncPolicy::None;
        if syncing {
            self.sync_file()?;
        }
        let next = self.segment + 1;
        let path = segment_path(&self.dir, next);
        let file = create_segment(&self.disk, &path, &self.dir, syncing).inspect_err(|_| {
            self.poisoned = true;
        })?;
        self.file = Appender::new(file, MAGIC_LEN);
        self.path = path;
        self.segment = next;
        Ok(())
    }
}

impl<D: Disk> Drop for LogWriter<D> {
    /// Syncs the unsynced records (unless the policy is `None` or the writer is poisoned).
    fn drop(&mut self) {
        if self.options.fsync != FsyncPolicy::None && !self.poisoned {
            let _ = self.sync_file();
        }
    }
}

/// Removes the last segment if it holds no complete record and is not the first one (a crash
/// between creating it and writing the record it was made for); returns the index of the
/// segment to append to.
///
/// Appending goes on in the segment before it, so the next append decides again whether to
/// roll over. That keeps the writer's rule that a segment ends only when the next segment's
/// first record would not have fitted, which is what [`verify`](super::verify()) checks to
/// find records missing at the end of a segment: after a restart the first record appended
/// is often not the one the segment was created for.
fn drop_empty_last_segment(
    disk: &impl Disk,
    dir: &Path,
    segments: &[PathBuf],
    contents: &LogContents,
    syncing: bool,
) -> Result<usize, LogError> {
    let last = segments.len() - 1;
    let holds_records = contents
        .positions
        .last()
        .is_some_and(|p| p.segment as usize == last);
    if last == 0 || holds_records {
        return Ok(last);
    }
    disk.remove_file(&segments[last])
        .map_err(|e| LogError::io(&segments[last], e))?;
    if syncing {
        sync_dir(disk, dir)?;
    }
    Ok(last - 1)
}

/// Takes the log's writer lock, or says which process holds it.
fn lock_log(dir: &Path) -> Result<FileLock, LogError> {
    let path = dir.join(WRITER_LOCK);
    match try_lock(&path, &[("pid", std::process::id().to_string())]) {
        Ok(TryLock::Acquired(lock)) => Ok(lock),
        Ok(TryLock::Held(holder)) => Err(LogError::Locked {
            dir: dir.to_path_buf(),
            holder: holder.get("pid").map(str::to_string),
        }),
        Err(e) => Err(LogError::io(&path, e)),
    }
}

/// Creates a segment holding only the magic; with `syncing`, syncs it and the directory.
fn create_segment<D: Disk>(
    disk: &D,
    path: &Path,
    dir: &Path,
    syncing: bool,
) -> Result<D::File, LogError> {
    let file = disk
        .create_new(path)
        .map_err(|e| write_error(dir, path, e))?;
    let written =
        file.write_at(0, &MAGIC)
            .and_then(|()| if syncing { file.sync_data() } else { Ok(()) });
    if let Err(e) = written {
        // A segment without its whole magic would read as damage; remove it (a full disk
        // still allows that), so the log ends on the previous, complete segment.
        let _ = disk.remove_file(path);
        return Err(write_error(dir, path, e));
    }
    if syncing {
        sync_dir(disk, dir)?;
    }
    Ok(file)
}

/// The error of a failed write to `path` in the log `dir`: [`LogError::NoSpace`] for a full
/// disk, which the coordinator reports as fatal, else [`LogError::Io`].
fn write_error(dir: &Path, path: &Path, e: std::io::Error) -> LogError {
    if crate::diag::is_no_space_io(&e) {
        LogError::NoSpace {
            dir: dir.to_path_buf(),
            source: e,
        }
    } else {
        LogError::io(path, e)
    }
}

fn sync_dir(disk: &impl Disk, dir: &Path) -> Result<(), LogError> {
    disk.sync_dir(dir).map_err(|e| LogError::io(dir, e))
}
