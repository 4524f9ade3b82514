//! Replacing a whole log ([`LogWriter::replace`]): how a Raft replica compacts its log
//! behind a snapshot, all or nothing across a crash.
//!
//! The new log is written to [`REPLACE_TMP`] in the log directory and synced, then renamed to
//! [`REPLACE_READY`]: from that rename on, the replacement is decided. The old segments are
//! removed, the last first, and the ready file is renamed to the first segment. A writer
//! opened over a directory holding a ready file finishes those steps before it reads the log
//! (the steps can be repeated), and removes a temporary file, whose replacement was never
//! decided. A reader that looks in between (`hnav log show` during a crash window) sees the
//! old log cut short at a segment end; the writer's next open puts the new one in place.

use std::path::Path;

use super::{create_segment, sync_dir, write_error, LogWriter, MAGIC_LEN};
use crate::consensus_log::error::LogError;
use crate::consensus_log::frame::{encode_frame, MAGIC};
use crate::consensus_log::reader::check_header;
use crate::consensus_log::record::Record;
use crate::consensus_log::segment::{list_segments, segment_path};
use crate::durable::{Appender, Disk, DiskFile};
use crate::scenario::FsyncPolicy;

/// The replacement of a log being written (removed on open: never decided).
pub const REPLACE_TMP: &str = "replace.tmp";

/// The replacement of a log, written whole and decided: the open finishes putting it in place.
pub const REPLACE_READY: &str = "replace.ready";

impl<D: Disk> LogWriter<D> {
    /// Replaces the whole log with `records` (a header first), atomically across a crash:
    /// written to [`REPLACE_TMP`] and synced, renamed to [`REPLACE_READY`] (decided), the old
    /// segments removed (the last first), the ready file made segment 0; an open finishes a
    /// decided replacement and drops an undecided one. They are durable when it returns,
    /// unless the policy is `None`. The writer then appends after them, in segment 0. A failure after the
    /// replacement was decided poisons the writer: the next open finishes it.
    pub fn replace(&mut self, records: &[Record]) -> Result<(), LogError> {
        self.check_usable()?;
        let syncing = self.options.fsync != FsyncPolicy::None;
        let tmp = self.dir.join(REPLACE_TMP);
        let mut buf = MAGIC.to_vec();
        for (i, r) in records.iter().enumerate() {
            if i == 0 {
                check_header(&tmp, MAGIC_LEN, r)?;
            }
            encode_frame(r, &mut buf)?;
        }
        if tmp.exists() {
            self.disk
                .remove_file(&tmp)
                .map_err(|e| LogError::io(&tmp, e))?;
        }
        let file = create_segment(&self.disk, &tmp, &self.dir, false)?;
        let written =
            file.write_at(0, &buf)
                .and_then(|()| if syncing { file.sync_data() } else { Ok(()) });
        if let Err(e) = written {
            let _ = self.disk.remove_file(&tmp);
            return Err(write_error(&self.dir, &tmp, e));
        }
        drop(file);
        let ready = self.dir.join(REPLACE_READY);
        self.disk
            .rename(&tmp, &ready)
            .map_err(|e| write_error(&self.dir, &tmp, e))?;
        // Decided: whatever fails now, the next open finishes it.
        let finished = finish_replace(&self.disk, &self.dir, syncing).and_then(|()| {
            let path = segment_path(&self.dir, 0);
            let file = self
                .disk
                .open_or_create(&path)
                .map_err(|e| LogError::io(&path, e))?;
            let len = file.size().map_err(|e| LogError::io(&path, e))?;
            Ok((path, file, len))
        });
        match finished {
            Ok((path, file, len)) => {
                self.file = Appender::new(file, len);
                self.path = path;
                self.segment = 0;
                self.records = records.len() as u64;
                self.unsynced = 0;
                Ok(())
            }
            Err(e) => {
                self.poisoned = true;
                Err(e)
            }
        }
    }
}

/// Finishes a decided replacement in `dir` if there is one (old segments removed, the last
/// first; the ready file made segment 0), and removes an undecided one.
pub(super) fn finish_replace(disk: &impl Disk, dir: &Path, syncing: bool) -> Result<(), LogError> {
    let tmp = dir.join(REPLACE_TMP);
    if tmp.exists() {
        disk.remove_file(&tmp).map_err(|e| LogError::io(&tmp, e))?;
    }
    let ready = dir.join(REPLACE_READY);
    if !ready.exists() {
        return Ok(());
    }
    for seg in list_segments(dir)?.iter().rev() {
        disk.remove_file(seg).map_err(|e| LogError::io(seg, e))?;
    }
    let first = segment_path(dir, 0);
    disk.rename(&ready, &first)
        .map_err(|e| write_error(dir, &ready, e))?;
    if syncing {
        sync_dir(disk, dir)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::consensus_log::reader::read_log;
    use crate::consensus_log::record::{EndReason, EndRecord, RunHeader};
    use crate::consensus_log::writer::WriterOptions;
    use crate::consensus_log::FORMAT_VERSION;

    fn header() -> Record {
        Record::Header(RunHeader::tiny(FORMAT_VERSION))
    }

    fn end(round: u64) -> Record {
        Record::End(EndRecord {
            round,
            at_goal: 0,
            reason: EndReason::Stopped,
        })
    }

    /// A log of many small segments: header and `n` records.
    fn log(dir: &Path, n: u64) -> LogWriter {
        let options = WriterOptions {
            segment_bytes: 64,
            ..WriterOptions::new(FsyncPolicy::EveryRecord)
        };
        let (mut w, _) = LogWriter::open_with(dir, options).unwrap();
        w.append(&header()).unwrap();
        (1..=n).for_each(|r| _ = w.append(&end(r)).unwrap());
        w
    }

    #[test]
    fn a_replaced_log_is_the_new_records_in_one_segment_and_appends_go_on_after_them() {
        let dir = tempfile::tempdir().unwrap();
        let mut w = log(dir.path(), 40);
        assert!(list_segments(dir.path()).unwrap().len() > 3);
        w.replace(&[header(), end(39), end(40)]).unwrap();
        assert_eq!(list_segments(dir.path()).unwrap().len(), 1);
        // Appends go on as before: a new segment once the 64-byte limit is passed.
        w.append(&end(41)).unwrap();
        drop(w);
        let records = read_log(dir.path()).unwrap().records;
        assert_eq!(records, vec![header(), end(39), end(40), end(41)]);
    }

    #[test]
    fn a_replacement_cut_short_by_a_crash_is_finished_if_decided_and_dropped_if_not() {
        let dir = tempfile::tempdir().unwrap();
        drop(log(dir.path(), 40));
        let mut new = MAGIC.to_vec();
        for r in [header(), end(40)] {
            encode_frame(&r, &mut new).unwrap();
        }
        // Written but not decided: the old log stays.
        std::fs::write(dir.path().join(REPLACE_TMP), &new).unwrap();
        let (_, recovered) = LogWriter::open(dir.path(), FsyncPolicy::EveryRecord).unwrap();
        assert_eq!(recovered.records.len(), 41);
        assert!(!dir.path().join(REPLACE_TMP).exists());
        // Decided, the crash after two old segments were removed: the open finishes it.
        std::fs::write(dir.path().join(REPLACE_READY), &new).unwrap();
        let segments = list_segments(dir.path()).unwrap();
        for seg in segments.iter().rev().take(2) {
            std::fs::remove_file(seg).unwrap();
        }
        let (_, recovered) = LogWriter::open(dir.path(), FsyncPolicy::EveryRecord).unwrap();
        assert_eq!(recovered.records, vec![header(), end(40)]);
        assert_eq!(list_segments(dir.path()).unwrap().len(), 1);
        assert!(!dir.path().join(REPLACE_READY).exists());
    }
}
