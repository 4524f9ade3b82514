//! Segment files: `seg-00000000.hlog`, `seg-00000001.hlog`, ... in the log directory.

use std::path::{Path, PathBuf};

use super::error::LogError;

/// Size above which the writer starts a new segment (64 MiB), unless configured otherwise.
pub const DEFAULT_SEGMENT_BYTES: u64 = 64 << 20;

/// The file name of segment `n`.
pub fn segment_name(n: u32) -> String {
    format!("seg-{n:08}.hlog")
}

/// The path of segment `n` in `dir`.
pub fn segment_path(dir: &Path, n: u32) -> PathBuf {
    dir.join(segment_name(n))
}

/// The segment number of a file name, if it is one (`seg-` + 8 decimal digits + `.hlog`).
pub fn parse_segment_name(name: &str) -> Option<u32> {
    let digits = name.strip_prefix("seg-")?.strip_suffix(".hlog")?;
    if digits.len() != 8 || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

/// The segments in `dir`, in order (possibly none). Other files are ignored.
///
/// Errors: the directory cannot be read ([`LogError::Io`]), or the numbers are not
/// 0, 1, 2, ... ([`LogError::SegmentGap`]).
pub fn list_segments(dir: &Path) -> Result<Vec<PathBuf>, LogError> {
    let entries = std::fs::read_dir(dir).map_err(|e| LogError::io(dir, e))?;
    let mut numbers = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| LogError::io(dir, e))?;
        if let Some(n) = entry.file_name().to_str().and_then(parse_segment_name) {
            numbers.push(n);
        }
    }
    numbers.sort_unstable();
    for (expected, &found) in numbers.iter().enumerate() {
        let expected = expected as u32;
        if found != expected {
            return Err(LogError::SegmentGap {
                dir: dir.to_path_buf(),
                expected,
                found,
            });
        }
    }
    Ok(numbers.into_iter().map(|n| segment_path(dir, n)).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        assert_eq!(segment_name(0), "seg-00000000.hlog");
        assert_eq!(segment_name(123), "seg-00000123.hlog");
        assert_eq!(parse_segment_name("seg-00000123.hlog"), Some(123));
        for bad in [
            "seg-123.hlog",
            "seg-0000012x.hlog",
            "seg-00000001.log",
            "x.hlog",
        ] {
            assert_eq!(parse_segment_name(bad), None, "{bad}");
        }
    }
}
