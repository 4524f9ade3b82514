//! One voter of the cluster ([`Replica`]): the `raft` crate's `RawNode` and its `Ready` cycle,
//! driven by its owner's loop, with the order Raft's safety needs between the storage and
//! the messages that acknowledge it.

use std::collections::VecDeque;

use raft::eraftpb::{Entry, EntryType, Message, MessageType};
use raft::{Config, RawNode, SnapshotStatus, StateRole};

use hnav_runtime::consensus_log::{AppliedState, WriterOptions};
use hnav_runtime::durable::{Disk, RealDisk};

use super::error::ReplicaError;
use super::journal::Journal;
use super::link::{RaftLink, MAX_ENTRIES_BYTES};
use super::log_bridge;
use super::store::Store;
use snapshot::decode_state;

mod snapshot;

/// A replica's timing and identity.
#[derive(Debug, Clone)]
pub struct ReplicaConfig {
    /// This replica's id, 1-based.
    pub id: u64,
    /// Every voter of the cluster, this one included.
    pub voters: Vec<u64>,
    /// Ticks without a leader's heartbeat before a follower stands for election; Raft
    /// randomises each timeout in `[election_ticks, 2 * election_ticks)`.
    pub election_ticks: usize,
    /// Ticks between the leader's heartbeats; well below `election_ticks`.
    pub heartbeat_ticks: usize,
    /// Committed entries after which a durable replica takes a snapshot and compacts its
    /// journal; 0 never.
    pub snapshot_entries: u64,
}

impl ReplicaConfig {
    /// A replica of a cluster of `n` voters (ids 1..=n) with etcd's default timing, 10 ticks
    /// to an election and 1 between heartbeats.
    pub fn cluster(id: u64, n: u64) -> Self {
        ReplicaConfig {
            id,
            voters: (1..=n).collect(),
            election_ticks: 10,
            heartbeat_ticks: 1,
            snapshot_entries: 0,
        }
    }
}

/// A replica's part in the cluster, as Raft names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// Decides the rounds and replicates them.
    Leader,
    /// Follows the leader of its term.
    Follower,
    /// Stands for election.
    Candidate,
    /// Asks whether it could win before raising the term (pre-vote).
    PreCandidate,
}

impl Role {
    /// Lower-case name, as `hnav ps` would show it.
    pub fn name(self) -> &'static str {
        match self {
            Role::Leader => "leader",
            Role::Follower => "follower",
            Role::Candidate => "candidate",
            Role::PreCandidate => "pre-candidate",
        }
    }
}

/// An entry the cluster has committed: a majority holds it durably, it is final.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Committed {
    /// Raft's log index (1-based, gapless over every entry, empty ones included).
    pub index: u64,
    /// The term of the leader that proposed it.
    pub term: u64,
    /// What was proposed.
    pub data: Vec<u8>,
}

/// Where the messages that may leave before the storage go the moment they exist.
type EarlyOut = Box<dyn FnMut(&Message)>;

/// One voter of a Raft cluster, driven by its owner's loop; its journal is written on the
/// disk `D`.
pub struct Replica<D: Disk = RealDisk> {
    node: RawNode<Store>,
    /// Where entries and hard states are made durable; `None` keeps them in memory only (the
    /// in-process tests).
    journal: Option<Journal<D>>,
    /// Where the messages that may leave before the storage go at once ([`Replica::send_early`]);
    /// without it they wait in the outbox with the rest.
    early: Option<EarlyOut>,
    outbox: Vec<Message>,
    committed: VecDeque<Committed>,
    /// A snapshot's index and state the owner has not taken yet: the journal's on a
    /// restart, or one the leader sent ([`take_installed`](Replica::take_installed)). The
    /// index is kept beside the state because the replica may compact again before the owner
    /// takes it (a restart applies the journal's committed entries and can reach the next
    /// snapshot at once): its current snapshot index is then a later one.
    installed: Option<(u64, AppliedState)>,
    snapshot_entries: u64,
    /// Snapshots installed from a leader since the start.
    installs: u64,
}

impl Replica {
    /// A replica of a new cluster: empty storage that knows the voters.
    pub fn new(config: &ReplicaConfig) -> Result<Self, ReplicaError> {
        Self::restart(config, Store::new(&config.voters))
    }

    /// A replica whose Raft log is the journal in `dir` (created with `header` if new,
    /// replayed if not): a restarted process comes back with its term, vote and entries, and
    /// its committed entries come out of [`take_committed`](Self::take_committed) again.
    pub fn durable(
        config: &ReplicaConfig,
        dir: &std::path::Path,
        header: hnav_runtime::consensus_log::RunHeader,
        fsync: hnav_runtime::scenario::FsyncPolicy,
    ) -> Result<Self, ReplicaError> {
        Self::durable_on(RealDisk, config, dir, header, WriterOptions::new(fsync))
    }

    /// A replica over storage that survived it: its term, vote and entries come back; what it
    /// had applied is applied again from the start (its owner's state machine starts empty),
    /// or from its last snapshot ([`take_installed`](Replica::take_installed)).
    pub fn restart(config: &ReplicaConfig, storage: Store) -> Result<Self, ReplicaError> {
        let snapshot = storage.last_snapshot();
        let mut replica = Self::over(config, storage)?;
        let index = snapshot.get_metadata().index;
        if index > 0 {
            replica.installed = Some((index, decode_state(&snapshot)?));
        }
        Ok(replica)
    }

    /// Sends the messages Raft lets leave before the storage (a leader's appends and
    /// heartbeats) on `link` the moment they exist, instead of queueing them for
    /// [`take_messages`](Self::take_messages): a leader's own `fdatasync` then runs while its
    /// followers write theirs, and a round costs one sync on its path instead of two. A
    /// message that does not go out is Raft's to resend.
    pub fn send_early(&mut self, link: std::rc::Rc<RaftLink>) {
        self.send_early_to(move |m| {
            if let Err(e) = link.send(m) {
                tracing::debug!(to = m.to, "raft message not sent: {e}");
            }
        });
    }
}

impl<D: Disk> Replica<D> {
    /// [`Replica::durable`] with its journal on `disk`, written as `options` say.
    pub fn durable_on(
        disk: D,
        config: &ReplicaConfig,
        dir: &std::path::Path,
        header: hnav_runtime::consensus_log::RunHeader,
        options: WriterOptions,
    ) -> Result<Self, ReplicaError> {
        let (journal, storage, compacted) =
            Journal::open_on(disk, dir, header, options, &config.voters)?;
        let index = storage.snapshot_index();
        let mut replica = Self::over(config, storage)?;
        replica.journal = Some(journal);
        replica.installed = compacted.map(|state| (index, state));
        // The committed entries of the journal are ready at once.
        replica.process()?;
        Ok(replica)
    }

    /// Makes everything the journal holds durable (the end of a run); nothing for a replica
    /// in memory.
    pub fn sync(&mut self) -> Result<(), ReplicaError> {
        match &mut self.journal {
            Some(j) => j.sync(),
            None => Ok(()),
        }
    }

    fn over(config: &ReplicaConfig, storage: Store) -> Result<Self, ReplicaError> {
        if config.id == 0 || !config.voters.contains(&config.id) {
            return Err(ReplicaError::NotAVoter {
                id: config.id,
                voters: config.voters.clone(),
            });
        }
        let raft_config = Config {
            id: config.id,
            election_tick: config.election_ticks,
            heartbeat_tick: config.heartbeat_ticks,
            // A replica that was cut off and comes back must not depose a working leader by
            // its higher term alone (pre-vote), and a leader cut off from the majority steps
            // down instead of believing it still leads (check-quorum): its stale decisions
            // can then never be taken for the cluster's.
            pre_vote: true,
            check_quorum: true,
            // Appends fit the `raft/<i>` topics (`link`).
            max_size_per_msg: MAX_ENTRIES_BYTES,
            ..Config::default()
        };
        raft_config.validate()?;
        let node = RawNode::new(&raft_config, storage, &log_bridge::logger(config.id))?;
        Ok(Replica {
            node,
            journal: None,
            early: None,
            outbox: Vec::new(),
            committed: VecDeque::new(),
            installed: None,
            snapshot_entries: config.snapshot_entries,
            installs: 0,
        })
    }

    /// This replica's id.
    pub fn id(&self) -> u64 {
        self.node.raft.id
    }

    /// Its role now.
    pub fn role(&self) -> Role {
        match self.node.raft.state {
            StateRole::Leader => Role::Leader,
            StateRole::Follower => Role::Follower,
            StateRole::Candidate => Role::Candidate,
            StateRole::PreCandidate => Role::PreCandidate,
        }
    }

    /// The term it is in.
    pub fn term(&self) -> u64 {
        self.node.raft.term
    }

    /// The leader it knows of, if any.
    pub fn leader(&self) -> Option<u64> {
        Some(self.node.raft.leader_id).filter(|&l| l != 0)
    }

    /// The index of the last entry in its log, committed or not: after a
    /// [`propose`](Self::propose), the proposal's.
    pub fn last_index(&self) -> u64 {
        self.node.raft.raft_log.last_index()
    }

    /// The highest index it knows committed.
    pub fn committed_index(&self) -> u64 {
        self.node.raft.raft_log.committed
    }

    /// Whether it leads and has committed an entry of its own term: only then is every entry
    /// of earlier leaders that will ever commit committed (and handed out), so the state it
    /// applied is the cluster's and it may decide.
    pub fn can_decide(&self) -> bool {
        self.role() == Role::Leader && self.node.raft.commit_to_current_term()
    }

    /// The storage, to keep for a restart ([`Replica::restart`]).
    pub fn storage(&self) -> &Store {
        self.node.store()
    }

    /// The index of its last snapshot (0 before the first): every entry up to it is
    /// compacted away.
    pub fn snapshot_index(&self) -> u64 {
        self.node.store().snapshot_index()
    }

    /// Snapshots it installed from a leader (this process).
    pub fn installs(&self) -> u64 {
        self.installs
    }

    /// Records in its journal now (0 for a replica in memory).
    pub fn journal_records(&self) -> u64 {
        self.journal.as_ref().map_or(0, Journal::records)
    }

    /// The state its owner must start from before the next committed entries, if it is not
    /// the state it has applied so far, with the index it stands for: that of the snapshot
    /// its journal starts with (after a restart) or of one its leader sent (it was too far
    /// behind). Take it before [`take_committed`](Self::take_committed).
    pub fn take_installed(&mut self) -> Option<(u64, AppliedState)> {
        self.installed.take()
    }

    /// Advances its logical clock by one tick (elections, heartbeats).
    pub fn tick(&mut self) -> Result<(), ReplicaError> {
        self.node.tick();
        self.process()
    }

    /// Sends a heartbeat to every follower now (a leader only; nothing otherwise): it carries
    /// the commit index, so the followers know the last entries committed without waiting
    /// for the next heartbeat (the end of a run).
    pub fn ping(&mut self) -> Result<(), ReplicaError> {
        self.node.ping();
        self.process()
    }

    /// Takes a message another replica sent.
    pub fn step(&mut self, message: Message) -> Result<(), ReplicaError> {
        self.node.step(message)?;
        self.process()
    }

    /// The leader this replica follows, replica `dead`, is known to have died (its
    /// supervisor saw the process exit): it stands for election now, as Raft's leadership
    /// transfer does (no pre-vote; the other followers grant their vote within the leader's
    /// lease), instead of after a whole election timeout of silence. `false`, and nothing
    /// done, if it does not follow `dead`. Safety does not rest on the news being right:
    /// any election is safe in Raft; a wrong one costs a term.
    pub fn leader_died(&mut self, dead: u64) -> Result<bool, ReplicaError> {
        if self.role() != Role::Follower || self.leader().is_some_and(|l| l != dead) {
            return Ok(false);
        }
        // What Raft's leader sends the transferee; `from` only names it in Raft's log.
        let mut m = Message::default();
        m.set_msg_type(MessageType::MsgTimeoutNow);
        m.from = dead;
        m.to = self.id();
        m.term = self.term();
        self.node.step(m)?;
        self.process()?;
        Ok(true)
    }

    /// Proposes `data` (a round record) for the cluster to commit; only the leader may.
    pub fn propose(&mut self, data: &[u8]) -> Result<(), ReplicaError> {
        if self.role() != Role::Leader {
            return Err(ReplicaError::NotLeader {
                id: self.id(),
                leader: self.node.raft.leader_id,
            });
        }
        self.node.propose(Vec::new(), data.to_vec())?;
        self.process()
    }

    /// Hands the messages Raft lets leave before the storage to `out` the moment they exist
    /// ([`send_early`](Replica::send_early) with `out` as the link): the simulation carries
    /// them on its network, ahead of a write that may fail.
    pub fn send_early_to(&mut self, out: impl FnMut(&Message) + 'static) {
        self.early = Some(Box::new(out));
    }

    /// The election timeout Raft drew for this term, in ticks.
    pub fn election_timeout(&self) -> usize {
        self.node.raft.randomized_election_timeout()
    }

    /// The range Raft draws election timeouts from, in ticks: `[min, max)`, the
    /// configuration's `[election_ticks, 2 * election_ticks)`.
    pub fn election_timeout_range(&self) -> (usize, usize) {
        let e = self.node.raft.election_timeout();
        (e, 2 * e)
    }

    /// Sets the election timeout Raft drew; it must lie in
    /// [`election_timeout_range`](Self::election_timeout_range) (Raft asserts it). Raft draws it from the
    /// thread's random numbers at every change of role or term and reads it only when a tick
    /// asks whether the election is due, so an owner that sets it after every call replaces
    /// the draw with its own: the deterministic simulation draws from its seed.
    pub fn set_election_timeout(&mut self, ticks: usize) {
        self.node.raft.set_randomized_election_timeout(ticks);
    }

    /// The messages to send to the other replicas, each addressed (`Message::to`). Every one
    /// may be sent at once: what they acknowledge is already in the storage.
    pub fn take_messages(&mut self) -> std::vec::Drain<'_, Message> {
        self.outbox.drain(..)
    }

    /// The entries committed since the last call, in log order. Entries without data (the
    /// empty entry each new leader appends) are left out; their indices are skipped.
    pub fn take_committed(&mut self) -> std::collections::vec_deque::Drain<'_, Committed> {
        self.committed.drain(..)
    }

    /// The `Ready` cycle: persist, release messages, apply, until Raft has nothing left.
    fn process(&mut self) -> Result<(), ReplicaError> {
        while self.node.has_ready() {
            let mut ready = self.node.ready();
            // Messages of a leader may leave before its own append (Raft's leader writes in
            // parallel with its followers); the rest wait for the storage below.
            let early = ready.take_messages();
            let snapshots: Vec<u64> = early
                .iter()
                .filter(|m| m.get_msg_type() == MessageType::MsgSnapshot)
                .map(|m| m.to)
                .collect();
            match &mut self.early {
                Some(out) => early.iter().for_each(out),
                None => self.outbox.extend(early),
            }
            let store = self.node.store().clone();
            if !ready.snapshot().is_empty() {
                self.install(&store, ready.snapshot().clone())?;
            }
            self.collect(ready.take_committed_entries());
            store.mem().wl().append(ready.entries())?;
            if let Some(hs) = ready.hs() {
                store.mem().wl().set_hardstate(hs.clone());
            }
            if let Some(j) = &mut self.journal {
                j.entries(ready.entries());
                if let Some(hs) = ready.hs() {
                    j.hard_state(hs);
                }
                // Durable before the messages that acknowledge it.
                j.flush()?;
            }
            self.outbox.extend(ready.take_persisted_messages());
            let mut light = self.node.advance(ready);
            if let Some(commit) = light.commit_index() {
                store.mem().wl().mut_hard_state().set_commit(commit);
                if let Some(j) = &mut self.journal {
                    j.commit(commit);
                }
            }
            self.outbox.extend(light.take_messages());
            self.collect(light.take_committed_entries());
            self.node.advance_apply();
            // A snapshot is reported sent as it leaves, so that the leader probes the
            // follower again: one lost on the way is found out like a lost append (the
            // follower refuses the next one) and sent again, instead of being waited for.
            for to in snapshots {
                self.node.report_snapshot(to, SnapshotStatus::Finish);
            }
        }
        self.compact_if_due()
    }

    fn collect(&mut self, entries: Vec<Entry>) {
        // Entries up to an installed snapshot are in its state.
        let floor = self.node.store().snapshot_index();
        for e in entries {
            if e.get_entry_type() == EntryType::EntryNormal && !e.data.is_empty() && e.index > floor
            {
                self.committed.push_back(Committed {
                    index: e.index,
                    term: e.term,
                    // The entry is consumed: its buffer becomes the record, no copy.
                    data: e.data.into(),
                });
            }
        }
    }
}
