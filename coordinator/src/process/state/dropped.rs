//! Candidates the coordinator dropped as malformed or hostile ([`Dropped`]), counted per class
//! and kept in `DIR/rejected.json` across restarts.

use std::path::{Path, PathBuf};

use hnav_runtime::msg::Candidate;
use hnav_runtime::rejected::{Rejected, Rejections, FILE};

/// The run's counts of dropped candidates, and where they are kept.
pub(super) struct Dropped {
    counts: Rejections,
    run_dir: PathBuf,
}

impl Dropped {
    /// The counts an earlier coordinator of the run left in `run_dir`, or none; a file that
    /// cannot be read is reported and counting starts again from zero, since the counts
    /// never decide anything.
    pub(super) fn load(run_dir: &Path) -> Self {
        let counts = Rejections::load(run_dir).unwrap_or_else(|e| {
            tracing::warn!("{e}; counting dropped candidates from zero");
            Rejections::default()
        });
        Dropped {
            counts,
            run_dir: run_dir.to_path_buf(),
        }
    }

    /// Counts a dropped candidate; only the first of its class is logged, so that a flood
    /// costs no log line and no allocation per message.
    pub(super) fn note(&mut self, class: Rejected, c: &Candidate) {
        if self.counts.note(class) {
            tracing::warn!(
                class = class.name(),
                agent = c.agent,
                round = c.round,
                "candidate dropped; further ones of this class are only counted"
            );
        }
    }

    /// Candidates dropped so far, every class together.
    pub(super) fn total(&self) -> u64 {
        self.counts.total()
    }

    /// Logs the totals (if any) and keeps them in `DIR/rejected.json` for the run summary and
    /// for a coordinator restarted after this one.
    pub(super) fn report(&self) {
        if self.counts.total() > 0 {
            tracing::warn!(counts = %self.counts, "candidates dropped in this run");
        }
        if let Err(e) = self.counts.store(&self.run_dir) {
            tracing::warn!("cannot write {}: {e}", self.run_dir.join(FILE).display());
        }
    }
}
