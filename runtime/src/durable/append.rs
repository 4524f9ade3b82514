//! [`Appender`]: writes frames at the end of a file, each with one write call, and makes them
//! durable on [`sync`](Appender::sync).
//!
//! A write that fails is cut off again (so that later frames do not follow garbage); if even
//! that fails, or an fsync fails, the appender is poisoned: every later call fails, and the
//! file must be reopened (and its tail read back) before anything else is appended. After a
//! failed fsync the kernel may have dropped the dirty pages and marked them clean, so a
//! second fsync would report success for data that is gone: it is never retried.

use std::io;

use super::disk::DiskFile;
use super::sync_failed;

/// Appends to one open file; see the [module docs](self).
#[derive(Debug)]
pub struct Appender<F> {
    file: F,
    len: u64,
    unsynced: bool,
    poisoned: bool,
}

impl<F: DiskFile> Appender<F> {
    /// Appends to `file` from `len` (its length: the end of its last complete frame).
    pub fn new(file: F, len: u64) -> Self {
        Self {
            file,
            len,
            unsynced: false,
            poisoned: false,
        }
    }

    /// Writes `bytes` (whole frames) at the end with one write call; returns their offset.
    pub fn append(&mut self, bytes: &[u8]) -> io::Result<u64> {
        self.check()?;
        let offset = self.len;
        if let Err(e) = self.file.write_at(offset, bytes) {
            if self.file.set_len(offset).is_err() {
                self.poisoned = true;
            }
            return Err(e);
        }
        self.len += bytes.len() as u64;
        self.unsynced = true;
        Ok(offset)
    }

    /// Makes everything appended durable (`fdatasync`, only if something was appended since
    /// the last sync). A failure poisons the appender.
    pub fn sync(&mut self) -> io::Result<()> {
        self.check()?;
        if self.unsynced {
            if let Err(e) = self.file.sync_data() {
                self.poisoned = true;
                return Err(sync_failed(e));
            }
            self.unsynced = false;
        }
        Ok(())
    }

    /// Bytes in the file.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// Whether the file holds nothing.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether an fsync or an undo failed: the file's durable state is unknown.
    pub fn is_poisoned(&self) -> bool {
        self.poisoned
    }

    /// The open file (to rewrite a header in place).
    pub fn file(&self) -> &F {
        &self.file
    }

    fn check(&self) -> io::Result<()> {
        if self.poisoned {
            return Err(io::Error::other(
                "an earlier write or fsync failed; the file must be reopened",
            ));
        }
        Ok(())
    }
}
