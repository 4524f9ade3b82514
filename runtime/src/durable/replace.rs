//! [`replace_file`]: a whole file replaced, so that after a crash it is the old file or the
//! new one, never half of either.

use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use super::disk::{parent_dir, Disk, DiskFile, RealDisk};
use super::sync_failed;

/// Replaces `path` by a file holding `bytes`, whole or not at all.
///
/// The bytes go to a temporary file beside `path` whose name no other writer uses (process id
/// and a counter), which is fsynced, renamed over `path`, and the directory fsynced so that the
/// rename itself survives a crash. On any failure the temporary file is removed and the old
/// `path` is left as it was; a failed fsync is an error too (the new file may not survive a
/// crash), reported and not retried.
pub fn replace_file(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    replace_file_on(&RealDisk, path, bytes)
}

/// [`replace_file`] on `disk`.
pub fn replace_file_on<D: Disk>(disk: &D, path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let dir = parent_dir(path);
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    let tmp = dir.join(format!(
        ".{name}.tmp-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    let written = (|| {
        let f = disk.create_new(&tmp)?;
        f.write_at(0, bytes)?;
        f.sync_data().map_err(sync_failed)?;
        drop(f);
        disk.rename(&tmp, path)
    })();
    if let Err(e) = written {
        let _ = disk.remove_file(&tmp);
        return Err(e);
    }
    disk.sync_dir(dir).map_err(sync_failed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_replaced_file_holds_the_new_bytes_and_no_temporary_is_left() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("summary.json");
        replace_file(&path, b"old").unwrap();
        replace_file(&path, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "{names:?}");
    }

    #[test]
    fn a_failed_replace_leaves_the_old_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f");
        replace_file(&path, b"old").unwrap();
        // A directory where the temporary would be renamed to: the rename fails.
        let blocked = dir.path().join("sub");
        std::fs::create_dir(&blocked).unwrap();
        std::fs::write(blocked.join("x"), b"").unwrap();
        assert!(replace_file(&blocked, b"new").is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        let left: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains(".tmp-"))
            .collect();
        assert!(left.is_empty(), "{left:?}");
    }
}
