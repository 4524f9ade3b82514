//! The round's candidate-to-commit latencies ([`Latency`]), for the summary's speed of
//! reaching consensus, kept in `DIR/consensus-latency.json` across restarts.
//!
//! Measured on this host's monotonic clock, in the coordinator: from the instant its loop
//! took in the round's first candidate (and, separately, its last one) to the instant the
//! commit was published. The lockstep log holds no wall times, so this is the one place
//! where both ends are seen; counting allocates nothing.

use std::path::{Path, PathBuf};
use std::time::Instant;

use hnav_runtime::criteria::files::LATENCY_FILE;
use hnav_runtime::criteria::ConsensusLatency;

/// The run's latencies so far, and where they are kept.
pub(super) struct Latency {
    counts: ConsensusLatency,
    run_dir: PathBuf,
    /// Whether this coordinator committed a round: a replica that only followed leaves the
    /// file to the one that led.
    counted: bool,
}

impl Latency {
    /// The latencies an earlier coordinator of the run left in `run_dir`, or none; a file
    /// that cannot be read is reported and counting starts again (they decide nothing).
    pub(super) fn load(run_dir: &Path) -> Self {
        let counts = ConsensusLatency::load(run_dir)
            .unwrap_or_else(|e| {
                tracing::warn!("{e}; counting candidate-to-commit latencies from zero");
                None
            })
            .unwrap_or_default();
        Latency {
            counts,
            run_dir: run_dir.to_path_buf(),
            counted: false,
        }
    }

    /// Counts a round whose first and last candidates came at `first` and `last`, committed
    /// now. A round with no candidate (closed by its deadline with none in) counts nothing.
    pub(super) fn note(&mut self, (first, last): (Option<Instant>, Option<Instant>)) {
        let now = Instant::now();
        let us = |t: Instant| now.saturating_duration_since(t).as_micros() as u64;
        if let (Some(f), Some(l)) = (first, last) {
            self.counts.from_first.record(us(f));
            self.counts.from_last.record(us(l));
            self.counted = true;
        }
    }

    /// Keeps the latencies in `DIR/consensus-latency.json` for the run summary and for a
    /// coordinator restarted after this one, if this one committed any round.
    pub(super) fn report(&self) {
        if !self.counted {
            return;
        }
        if let Err(e) = self.counts.store(&self.run_dir) {
            let path = self.run_dir.join(LATENCY_FILE);
            tracing::warn!("cannot write {}: {e}", path.display());
        }
    }
}
