//! What the parts of the watch want done to the run. The fault schedule, the hang watch and
//! the slots (reaping, restarts, `Up`s) only read the run's state and return [`Action`]s; the
//! watch (`Watch::apply`) is the one place that carries them out, at once and in the order
//! given: so every signal, respawn, journal line and lifecycle message of a run is sent from
//! one `match`.

use crate::supervisor::child::Signal;
use crate::supervisor::events::RunEvent;
use hnav_runtime::msg::{Lifecycle, Role};

/// One thing to do to the run.
#[derive(Debug)]
pub(super) enum Action {
    /// Signal one incarnation of a process and journal it (`Signalled`).
    Signal(Shot),
    /// A line in the run's journal `DIR/events.jsonl`.
    Journal(RunEvent),
    /// Tell the run's processes on the lifecycle topic.
    Publish(Lifecycle),
    /// Remove the iceoryx2 resources of the processes just reaped, which wakes their peers
    /// with "peer dead".
    CleanUpDead,
    /// Start `role`/`index` again, with `--resume`.
    Respawn {
        /// The role of the process.
        role: Role,
        /// Its index.
        index: u32,
    },
}

/// One incarnation of one of the run's processes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Incarnation {
    pub(super) role: Role,
    pub(super) index: u32,
    pub(super) pid: u32,
}

/// A signal to send. It goes only to `target`'s incarnation: one that was reaped or replaced
/// meanwhile gets nothing.
#[derive(Debug)]
pub(super) struct Shot {
    pub(super) target: Incarnation,
    pub(super) signal: Signal,
    /// Who sends it; a fault learns where its shot landed.
    pub(super) why: Why,
    /// The last committed round the supervisor knew of, for the journal.
    pub(super) round: u64,
    /// Block until the target has stopped (or died instead): a lockstep freeze, so that the
    /// run resumes only once the frozen process cannot step.
    pub(super) wait_stop: bool,
}

/// Who a [`Shot`] is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Why {
    /// Fault `n` of the plan fires.
    Fault(usize),
    /// The freeze of fault `n` ends (SIGCONT).
    Thaw(usize),
    /// The hang watch kills a silent process.
    Hung,
}

impl Why {
    /// The fault plan's entry, for the journal.
    pub(super) fn fault(self) -> Option<usize> {
        match self {
            Why::Fault(n) | Why::Thaw(n) => Some(n),
            Why::Hung => None,
        }
    }
}

/// Where a [`Shot`] landed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Landed {
    /// Not sent: the incarnation is gone, or the signal could not be sent.
    Missed,
    /// Sent (and, waited for, the target stopped).
    Sent,
    /// Sent, waited for, and the target died instead of stopping.
    DiedInstead,
}
