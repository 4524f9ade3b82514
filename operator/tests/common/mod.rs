//! What several of the operator's test binaries share.

use std::path::Path;
use std::time::{Duration, Instant};

/// Test-only readiness wait: a child writes `needle` into the file at `path` once it is
/// ready (its signal set-up done); bounded, it panics after 10 s.
pub fn wait_for_line(path: &Path, needle: &str) {
    let deadline = Instant::now() + Duration::from_secs(10);
    while Instant::now() < deadline {
        if std::fs::read_to_string(path).is_ok_and(|s| s.contains(needle)) {
            return;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    panic!("{} never printed {needle:?}", path.display());
}
