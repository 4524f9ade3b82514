//! What a coordinator reports when its run is over.

/// How the coordinator's run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CoordinatorOutcome {
    /// Last committed round.
    pub round: u64,
    /// Whether every agent reached its goal.
    pub all_at_goal: bool,
    /// Candidates dropped as malformed or hostile (every class of
    /// [`Rejected`](hnav_runtime::rejected::Rejected) together).
    pub dropped: u64,
}
