//! When a replica may decide, and when what it decided is final ([`Lead`]): the rules the
//! coordinator's decision loop follows over its [`Replica`], kept apart from the link and
//! the clock so that the simulation ([`sim`](super::sim)) follows the same ones.
//!
//! A replica decides only once it leads and has committed an entry of its own term (then
//! every entry of earlier leaders that will ever commit is committed, and applied). From
//! then on it decides in that term only: once it no longer leads in it, it is deposed, and
//! its owner must start again from the journal, because its state may hold decisions the
//! cluster never committed. A decision is final once the replica's commit index reaches its
//! last proposal while it is not deposed.

use hnav_runtime::durable::Disk;

use super::peer::{Committed, Replica, Role};

/// One process's lead: the term it decides in, once it has started to, and its last
/// proposal.
#[derive(Debug, Clone, Default)]
pub struct Lead {
    /// The term this replica leads in, once it has started to decide.
    led: Option<u64>,
    /// The index of its last proposal.
    proposed: u64,
}

impl Lead {
    /// A process that has not decided yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Whether it may decide now ([`Replica::can_decide`] the first time, its term kept
    /// after that).
    pub fn take<D: Disk>(&mut self, replica: &Replica<D>) -> bool {
        if self.led.is_none() && replica.can_decide() {
            self.led = Some(replica.term());
        }
        self.led.is_some()
    }

    /// Whether it has started to decide.
    pub fn leading(&self) -> bool {
        self.led.is_some()
    }

    /// The term it decided in, if it no longer leads in that term.
    pub fn deposed<D: Disk>(&self, replica: &Replica<D>) -> Option<u64> {
        let led = self.led?;
        (replica.role() != Role::Leader || replica.term() != led).then_some(led)
    }

    /// Notes a proposal the replica just took (its last entry).
    pub fn proposed<D: Disk>(&mut self, replica: &Replica<D>) {
        self.proposed = replica.last_index();
    }

    /// The index of its last proposal (0 before the first).
    pub fn last_proposal(&self) -> u64 {
        self.proposed
    }

    /// Whether every proposal is committed: a majority holds it durably. Final only while
    /// the replica is not [`deposed`](Self::deposed).
    pub fn settled<D: Disk>(&self, replica: &Replica<D>) -> bool {
        replica.committed_index() >= self.proposed
    }

    /// Whether `entry` is one this process decided itself (and applied when it decided),
    /// rather than another leader's to apply now.
    pub fn decided_here(&self, entry: &Committed) -> bool {
        Some(entry.term) == self.led
    }
}
