//! The run's start, kept in the run directory so that a restarted `hnav-ros2 --robots` goes
//! on counting control periods where its predecessor was: an agent ignores odometry of a
//! period it has already seen, so a count that started again at 1 would hold every robot.
//! Wall-clock nanoseconds since the Unix epoch, because an `Instant` does not outlive its
//! process.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// The file in the run directory that holds the run's start, ns since the Unix epoch.
pub const ORIGIN_FILE: &str = "outside.origin";

/// The start could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {source}")]
pub struct OriginError {
    /// The file.
    pub path: PathBuf,
    /// What failed.
    pub source: std::io::Error,
}

/// The run's start: now, kept in `dir/outside.origin`; or, resuming, the one kept there.
pub fn origin(dir: Option<&Path>, resume: bool) -> Result<Instant, OriginError> {
    let now = Instant::now();
    let wall = SystemTime::now();
    let Some(dir) = dir else { return Ok(now) };
    let path = dir.join(ORIGIN_FILE);
    let err = |source| OriginError {
        path: path.clone(),
        source,
    };
    if resume {
        if let Ok(text) = std::fs::read_to_string(&path) {
            if let Ok(ns) = text.trim().parse::<u64>() {
                let then = UNIX_EPOCH + Duration::from_nanos(ns);
                let ago = wall.duration_since(then).unwrap_or_default();
                return Ok(now.checked_sub(ago).unwrap_or(now));
            }
        }
        tracing::warn!(
            "{}: no usable start kept; counting from now",
            path.display()
        );
    }
    let ns = wall
        .duration_since(UNIX_EPOCH)
        .unwrap_or_default()
        .as_nanos();
    let tmp = dir.join(format!("{ORIGIN_FILE}.tmp"));
    std::fs::write(&tmp, format!("{ns}\n")).map_err(err)?;
    std::fs::rename(&tmp, &path).map_err(err)?;
    Ok(now)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_resumed_count_goes_on_from_the_kept_start() {
        let dir = tempfile::tempdir().unwrap();
        let first = origin(Some(dir.path()), false).unwrap();
        std::thread::sleep(Duration::from_millis(30));
        let again = origin(Some(dir.path()), true).unwrap();
        // The same instant, as far as the wall clock's and the monotonic clock's readings
        // agree.
        let apart = if again > first {
            again - first
        } else {
            first - again
        };
        assert!(apart < Duration::from_millis(20), "{apart:?}");
        // Nothing kept: now.
        let other = tempfile::tempdir().unwrap();
        let fresh = origin(Some(other.path()), true).unwrap();
        assert!(fresh.elapsed() < Duration::from_secs(1));
    }
}
