//! Where the coordinator's decisions become final: its own consensus log (a single
//! coordinator), or the Raft cluster of its replicas (`coordinator.replicas` 3 or 5).
//!
//! A single coordinator appends a record and it is final once the append returns (durable by
//! the fsync policy). A replica that leads proposes the record instead; it is final once a
//! majority of the replicas holds it durably ([`RaftLog::settled`]), and only then may its
//! Commit leave. A replica that follows takes the leader's committed records
//! ([`RaftLog::pump`]) and applies them to its own state, so that it is ready to lead.

use std::path::PathBuf;
use std::rc::Rc;
use std::time::{Duration, Instant};

use hnav_runtime::consensus_log::{
    decode_record, encode_record, LogWriter, Record, ReplicaRole, RunHeader, ROLE_FILE,
};
use hnav_runtime::scenario::Scenario;
use hnav_runtime::transport::Transport;

use super::CoordinatorError;
use crate::replication::{RaftLink, Replica, ReplicaConfig, ReplicaError, Role};

/// The coordinator's decisions' destination.
pub(super) enum Decisions {
    /// A single coordinator's log.
    Log(LogWriter),
    /// A replica's Raft log.
    Raft(Box<RaftLog>),
}

impl Decisions {
    /// Makes `record` final (single) or proposes it (the leading replica).
    pub(super) fn append(&mut self, record: &Record) -> Result<(), CoordinatorError> {
        match self {
            Decisions::Log(log) => {
                log.append(record)?;
            }
            Decisions::Raft(raft) => raft.propose(record)?,
        }
        Ok(())
    }

    /// Makes everything appended durable now.
    pub(super) fn sync(&mut self) -> Result<(), CoordinatorError> {
        match self {
            Decisions::Log(log) => log.sync()?,
            Decisions::Raft(raft) => raft.replica.sync()?,
        }
        Ok(())
    }
}

/// A replica's end of the cluster: its Raft peer over its journal, the `raft/<i>` topics, and
/// the replica's logical clock.
pub(super) struct RaftLog {
    replica: Replica,
    /// Shared with the process loop, which waits on its inbox while the state pumps it.
    link: Rc<RaftLink>,
    /// The encoding of the record being proposed, reused.
    buf: Vec<u8>,
    /// The term this replica leads in, once it has started to decide.
    led: Option<u64>,
    /// The index of its last proposal.
    proposed: u64,
    tick: Duration,
    next_tick: Instant,
    /// Records committed by other leaders, in log order, for the state to apply.
    pub(super) applied: Vec<Record>,
    /// The replica's log directory, where its role file is kept for `hnav ps`.
    dir: PathBuf,
    /// The role and term the role file says.
    shown: Option<(Role, u64)>,
}

impl RaftLog {
    /// Replica `id` of `scenario`'s cluster, its journal in `run_dir/log/<id>` (created with
    /// `header`, or replayed).
    pub(super) fn open(
        transport: &Transport,
        scenario: &Scenario,
        run_dir: &std::path::Path,
        id: u64,
        header: RunHeader,
    ) -> Result<Self, CoordinatorError> {
        let c = &scenario.coordinator;
        let config = ReplicaConfig {
            election_ticks: c.election_ticks(),
            heartbeat_ticks: 1,
            ..ReplicaConfig::cluster(id, u64::from(c.replicas))
        };
        let dir = run_dir.join("log").join(id.to_string());
        let mut replica = Replica::durable(&config, &dir, header, c.fsync)?;
        // A role file of an earlier incarnation says nothing of this one.
        let _ = std::fs::remove_file(dir.join(ROLE_FILE));
        let link = Rc::new(RaftLink::open(transport, id, &config.voters)?);
        replica.send_early(Rc::clone(&link));
        let tick = Duration::from_millis(u64::from(c.raft_heartbeat_ms));
        let mut raft = RaftLog {
            replica,
            link,
            buf: Vec::new(),
            led: None,
            proposed: 0,
            tick,
            next_tick: Instant::now() + tick,
            applied: Vec::new(),
            dir,
            shown: None,
        };
        // The journal's committed entries: the state before this process.
        raft.take_committed()?;
        Ok(raft)
    }

    /// The link, whose inbox wakes the process loop.
    pub(super) fn link(&self) -> Rc<RaftLink> {
        Rc::clone(&self.link)
    }

    /// This replica's Raft id.
    pub(super) fn id(&self) -> u64 {
        self.replica.id()
    }

    /// The term it is in.
    pub(super) fn term(&self) -> u64 {
        self.replica.term()
    }

    /// Its role now.
    pub(super) fn role(&self) -> Role {
        self.replica.role()
    }

    /// When the next tick is due: the latest a wait may last.
    pub(super) fn deadline(&self) -> Instant {
        self.next_tick
    }

    /// Whether it may start to decide: it leads and every earlier leader's committed entry is
    /// applied ([`Replica::can_decide`]). From then on it decides in this term only.
    pub(super) fn take_lead(&mut self) -> bool {
        if self.led.is_none() && self.replica.can_decide() {
            self.led = Some(self.replica.term());
        }
        self.led.is_some()
    }

    /// Whether it has started to decide.
    pub(super) fn leading(&self) -> bool {
        self.led.is_some()
    }

    /// Whether it decided in a term it no longer leads: its state may hold decisions the
    /// cluster never committed, and only a restart from the journal sets that right.
    pub(super) fn deposed(&self) -> Option<u64> {
        let led = self.led?;
        (self.replica.role() != Role::Leader || self.replica.term() != led).then_some(led)
    }

    /// Whether every proposal is committed: a majority holds it durably.
    pub(super) fn settled(&self) -> bool {
        self.replica.committed_index() >= self.proposed
    }

    /// One pass of the replica: the messages that came in, a tick if one is due, the
    /// messages that go out, and the committed records of other leaders into
    /// [`applied`](Self::applied).
    pub(super) fn pump(&mut self) -> Result<(), CoordinatorError> {
        let replica = &mut self.replica;
        let mut failed = None;
        self.link.receive(|m| {
            if let Err(e) = replica.step(m) {
                // A message of another term or a stale one is Raft's to refuse; only a storage
                // failure must stop the replica.
                match e {
                    ReplicaError::Log(_) | ReplicaError::Snapshot => failed = Some(e),
                    other => tracing::debug!("raft message refused: {other}"),
                }
            }
        })?;
        if let Some(e) = failed {
            return Err(e.into());
        }
        let now = Instant::now();
        if now >= self.next_tick {
            self.replica.tick()?;
            // From now: a replica that was late ticks once, not in a burst.
            self.next_tick = now + self.tick;
        }
        self.send()?;
        self.show_role();
        self.take_committed()
    }

    /// Rewrites the role file when the role or the term changed (rarely: elections). It only
    /// informs `hnav ps`, so a failed write is a warning.
    fn show_role(&mut self) {
        let now = (self.replica.role(), self.replica.term());
        if self.shown == Some(now) {
            return;
        }
        self.shown = Some(now);
        let role = ReplicaRole {
            role: now.0.name().to_string(),
            term: now.1,
        };
        if let Err(e) = role.write(&self.dir) {
            tracing::warn!("{}: {e}", self.dir.join(ROLE_FILE).display());
        }
    }

    /// Tells the followers the commit index now (the run's end: they stop soon after).
    pub(super) fn ping(&mut self) -> Result<(), CoordinatorError> {
        self.replica.ping()?;
        self.send()
    }

    /// Proposes `record`; the leader only.
    fn propose(&mut self, record: &Record) -> Result<(), CoordinatorError> {
        self.buf.clear();
        encode_record(record, &mut self.buf)?;
        self.replica.propose(&self.buf)?;
        self.proposed = self.replica.last_index();
        self.send()
    }

    /// Sends what Raft has to say. A message that does not go out is Raft's to resend.
    fn send(&mut self) -> Result<(), CoordinatorError> {
        for m in self.replica.take_messages() {
            if let Err(e) = self.link.send(&m) {
                tracing::debug!(to = m.to, "raft message not sent: {e}");
            }
        }
        Ok(())
    }

    /// Moves the committed records this replica did not decide itself into `applied`.
    fn take_committed(&mut self) -> Result<(), CoordinatorError> {
        for c in self.replica.take_committed() {
            if Some(c.term) == self.led {
                continue;
            }
            let record = decode_record(&c.data).map_err(|p| {
                CoordinatorError::Replica(ReplicaError::Decode(format!(
                    "committed entry {}: {p}",
                    c.index
                )))
            })?;
            self.applied.push(record);
        }
        Ok(())
    }
}
