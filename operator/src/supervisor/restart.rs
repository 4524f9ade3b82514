//! Whether, and when, to restart a child that exited.
//!
//! The scenario's `[restart]` table gives each role a [`RestartRule`]: a policy (`never`,
//! `on-failure`, `always`), a cap on restarts over the whole run, and a base backoff. The
//! delay doubles with every restart of the same child, so a process that crashes as it starts
//! (a bad argument, a missing file) does not spin, while a one-off crash is retried quickly.
//! The doubling is capped (by default at [`DEFAULT_BACKOFF_CAP`]) so a late restart is not
//! delayed for minutes.
//!
//! The tracker only decides; the supervisor waits (a `Waiter` deadline, not a sleep) and
//! respawns.

use std::time::Duration;

use super::child::ExitInfo;
use hnav_runtime::launch::EXIT_NO_SPACE;
use hnav_runtime::scenario::{RestartPolicy, RestartRule};

/// The longest backoff [`RestartTracker`] uses unless told otherwise (or unless the rule's
/// own base backoff is longer, which is then used unchanged).
pub const DEFAULT_BACKOFF_CAP: Duration = Duration::from_secs(5);

/// What to do after a child exited.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RestartDecision {
    /// Start it again after this delay.
    Restart {
        /// The backoff before respawning.
        after: Duration,
    },
    /// Leave it down.
    GiveUp(GiveUpReason),
}

/// Why a child is not restarted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GiveUpReason {
    /// The policy is `never`.
    Never,
    /// The policy is `on-failure` and the child exited with code 0.
    CleanExit,
    /// The policy would restart, but `max_restarts` restarts were already made.
    LimitReached {
        /// The cap that was reached.
        max_restarts: u32,
    },
    /// The child exited with [`EXIT_NO_SPACE`]: the run directory's disk is full, and a
    /// restart would meet the same full disk. The run cannot go on.
    NoSpace,
}

impl core::fmt::Display for GiveUpReason {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            GiveUpReason::Never => f.write_str("restart policy is never"),
            GiveUpReason::CleanExit => f.write_str("exited cleanly under on-failure"),
            GiveUpReason::LimitReached { max_restarts } => {
                write!(f, "restart limit of {max_restarts} reached")
            }
            GiveUpReason::NoSpace => f.write_str("no space left on device"),
        }
    }
}

/// The restart state of one child slot (one role and index) across its incarnations.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RestartTracker {
    rule: RestartRule,
    cap: Duration,
    restarts: u32,
}

impl RestartTracker {
    /// A tracker for `rule` with no restarts yet and the [`DEFAULT_BACKOFF_CAP`].
    pub fn new(rule: RestartRule) -> Self {
        Self {
            rule,
            cap: DEFAULT_BACKOFF_CAP,
            restarts: 0,
        }
    }

    /// Replaces the backoff cap.
    pub fn with_backoff_cap(mut self, cap: Duration) -> Self {
        self.cap = cap;
        self
    }

    /// The rule in force.
    pub fn rule(&self) -> RestartRule {
        self.rule
    }

    /// Restarts decided so far.
    pub fn restarts(&self) -> u32 {
        self.restarts
    }

    /// Decides what to do about `exit`; a [`RestartDecision::Restart`] counts as one restart.
    pub fn on_exit(&mut self, exit: &ExitInfo) -> RestartDecision {
        if exit.code() == Some(i32::from(EXIT_NO_SPACE)) {
            return RestartDecision::GiveUp(GiveUpReason::NoSpace);
        }
        let wanted = match self.rule.policy {
            RestartPolicy::Never => return RestartDecision::GiveUp(GiveUpReason::Never),
            RestartPolicy::OnFailure => exit.is_failure(),
            RestartPolicy::Always => true,
        };
        if !wanted {
            return RestartDecision::GiveUp(GiveUpReason::CleanExit);
        }
        if self.restarts >= self.rule.max_restarts {
            return RestartDecision::GiveUp(GiveUpReason::LimitReached {
                max_restarts: self.rule.max_restarts,
            });
        }
        let after = self.backoff(self.restarts);
        self.restarts += 1;
        RestartDecision::Restart { after }
    }

    /// The delay before restart number `n + 1`: `backoff_ms · 2ⁿ`, capped.
    pub fn backoff(&self, n: u32) -> Duration {
        let base = Duration::from_millis(self.rule.backoff_ms);
        let factor = 1u32.checked_shl(n).unwrap_or(u32::MAX);
        base.saturating_mul(factor).min(self.cap.max(base))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_disk_is_never_restarted_whatever_the_policy() {
        for policy in [RestartPolicy::Always, RestartPolicy::OnFailure] {
            let rule = RestartRule {
                policy,
                max_restarts: 3,
                backoff_ms: 10,
            };
            let mut t = RestartTracker::new(rule);
            let full = ExitInfo::Exited(i32::from(EXIT_NO_SPACE));
            assert_eq!(
                t.on_exit(&full),
                RestartDecision::GiveUp(GiveUpReason::NoSpace)
            );
            assert_eq!(t.restarts(), 0);
            assert!(matches!(
                t.on_exit(&ExitInfo::Exited(1)),
                RestartDecision::Restart { .. }
            ));
        }
    }
}
