//! A replica's end of the cluster as the coordinator uses it ([`RaftLog`]): it proposes the
//! records of the rounds it decides while it leads, and takes the records other leaders
//! committed while it follows.
//!
//! A record a leading replica proposes is final once a majority of the replicas holds it
//! durably ([`RaftLog::settled`]), and only then may its Commit leave. A following replica
//! takes the leader's committed records ([`RaftLog::pump`]) for the coordinator to apply to
//! its own state, so that it is ready to lead.

use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::{Duration, Instant};

use hnav_runtime::consensus_log::{
    decode_record, encode_record, AppliedState, Record, ReplicaRole, RunHeader, ROLE_FILE,
};
use hnav_runtime::scenario::Scenario;
use hnav_runtime::transport::Transport;

use super::error::ReplicaError;
use super::lead::Lead;
use super::link::RaftLink;
use super::peer::{Replica, ReplicaConfig, Role};

/// A replica's end of the cluster: its Raft peer over its journal, the `raft/<i>` topics, and
/// the replica's logical clock.
pub struct RaftLog {
    replica: Replica,
    /// Shared with the process loop, which waits on its inbox while the state pumps it.
    link: Rc<RaftLink>,
    /// The encoding of the record being proposed, reused.
    buf: Vec<u8>,
    /// Whether it decides, and its last proposal.
    lead: Lead,
    tick: Duration,
    next_tick: Instant,
    /// Every voter's id.
    voters: Vec<u64>,
    /// The leader `.0` is known dead: this replica stands for election at `.1` unless a new
    /// leader has come by then ([`RaftLog::replica_down`]).
    campaign: Option<(u64, Instant)>,
    /// While following: when the leader was last heard, and the longest it was silent, the
    /// measure election timeouts are chosen from (logged at the end).
    heard_leader: Option<Instant>,
    longest_silence: Duration,
    /// Records committed by other leaders, in log order, for the coordinator to apply.
    applied: Vec<Record>,
    /// A snapshot's state the coordinator must start from before `applied`.
    installed: Option<AppliedState>,
    /// The replica's log directory, where its role file is kept for `hnav ps`.
    dir: PathBuf,
    /// The role and term the role file says.
    shown: Option<(Role, u64)>,
}

impl RaftLog {
    /// Replica `id` of `scenario`'s cluster, its journal in `run_dir/log/<id>` (created with
    /// `header`, or replayed).
    pub fn open(
        transport: &Transport,
        scenario: &Scenario,
        run_dir: &Path,
        id: u64,
        header: RunHeader,
    ) -> Result<Self, ReplicaError> {
        let c = &scenario.coordinator;
        let config = ReplicaConfig {
            election_ticks: c.election_ticks(),
            heartbeat_ticks: 1,
            snapshot_entries: c.snapshot_entries,
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
            lead: Lead::new(),
            tick,
            next_tick: Instant::now() + tick,
            voters: config.voters.clone(),
            campaign: None,
            heard_leader: None,
            longest_silence: Duration::ZERO,
            applied: Vec::new(),
            installed: None,
            dir,
            shown: None,
        };
        // The journal's committed entries: the state before this process.
        raft.take_committed()?;
        Ok(raft)
    }

    /// The link, whose inbox wakes the process loop.
    pub fn link(&self) -> Rc<RaftLink> {
        Rc::clone(&self.link)
    }

    /// This replica's Raft id.
    pub fn id(&self) -> u64 {
        self.replica.id()
    }

    /// The term it is in.
    pub fn term(&self) -> u64 {
        self.replica.term()
    }

    /// Its role now.
    pub fn role(&self) -> Role {
        self.replica.role()
    }

    /// When the next tick (or a campaign) is due: the latest a wait may last.
    pub fn deadline(&self) -> Instant {
        match self.campaign {
            Some((_, due)) => due.min(self.next_tick),
            None => self.next_tick,
        }
    }

    /// The supervisor says replica `dead` went down. If it led this replica, the surviving
    /// replicas stand for election in turn, lowest id first, one heartbeat apart: the first
    /// is usually elected within a round trip; the next stands only if no leader has come
    /// by its turn (the first's log was behind, or it died too). Without this, a follower
    /// waits out its election timeout, `[election_ms, 2 * election_ms)` of silence, before
    /// it notices; with it, a crashed leader costs a round trip, and the timeout is left to
    /// what no supervisor sees (a frozen leader, a cut network, a lost host).
    pub fn replica_down(&mut self, dead: u64) {
        if self.replica.role() != Role::Follower || self.replica.leader() != Some(dead) {
            return;
        }
        let id = self.replica.id();
        let rank = self.voters.iter().filter(|&&v| v != dead && v < id).count() as u32;
        self.campaign = Some((dead, Instant::now() + self.tick * rank));
    }

    /// Whether it may start to decide: it leads and every earlier leader's committed entry is
    /// applied ([`Replica::can_decide`]). From then on it decides in this term only.
    pub fn take_lead(&mut self) -> bool {
        self.lead.take(&self.replica)
    }

    /// Whether it has started to decide.
    pub fn leading(&self) -> bool {
        self.lead.leading()
    }

    /// Whether it decided in a term it no longer leads: its state may hold decisions the
    /// cluster never committed, and only a restart from the journal sets that right.
    pub fn deposed(&self) -> Option<u64> {
        self.lead.deposed(&self.replica)
    }

    /// Whether every proposal is committed: a majority holds it durably.
    pub fn settled(&self) -> bool {
        self.lead.settled(&self.replica)
    }

    /// One pass of the replica: the messages that came in, a tick if one is due, the
    /// messages that go out, and the committed records of other leaders into
    /// [`take_applied`](Self::take_applied).
    pub fn pump(&mut self) -> Result<(), ReplicaError> {
        let replica = &mut self.replica;
        let mut failed = None;
        let (heard, longest) = (&mut self.heard_leader, &mut self.longest_silence);
        self.link.receive(|m| {
            if replica.role() == Role::Follower && replica.leader() == Some(m.from) {
                let now = Instant::now();
                if let Some(before) = heard.replace(now) {
                    *longest = (*longest).max(now - before);
                }
            }
            if let Err(e) = replica.step(m) {
                // A message of another term or a stale one is Raft's to refuse; only a storage
                // failure must stop the replica.
                match e {
                    ReplicaError::Log(_) | ReplicaError::Decode(_) => failed = Some(e),
                    other => tracing::debug!("raft message refused: {other}"),
                }
            }
        })?;
        if let Some(e) = failed {
            return Err(e);
        }
        let now = Instant::now();
        if let Some((dead, due)) = self.campaign {
            if now >= due {
                self.campaign = None;
                // A leader elected meanwhile makes this a no-op (`leader_died` checks).
                if self.replica.leader_died(dead)? {
                    tracing::info!(
                        dead,
                        term = self.replica.term(),
                        "the leader died: stands for election"
                    );
                }
            }
        }
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

    /// Makes everything its journal holds durable now.
    pub fn sync(&mut self) -> Result<(), ReplicaError> {
        self.replica.sync()
    }

    /// Says (at the process's end) how long the leader it followed was silent at most: set
    /// against `election_ms`, how near the run came to an election no one needed.
    pub fn report(&self) {
        tracing::info!(
            longest_leader_silence_ms = self.longest_silence.as_secs_f64() * 1e3,
            term = self.replica.term(),
            "replica's end"
        );
    }

    /// The records other leaders committed that the coordinator has not applied yet, in log
    /// order. The coordinator applies them and hands the emptied buffer back
    /// ([`RaftLog::recycle`]), so that following allocates nothing once warm.
    pub fn take_applied(&mut self) -> Vec<Record> {
        std::mem::take(&mut self.applied)
    }

    /// The state of a snapshot the coordinator must start from before the records of
    /// [`take_applied`](Self::take_applied): its journal's, after a restart over a compacted
    /// log, or the leader's, when this replica was too far behind for the entries.
    pub fn take_installed(&mut self) -> Option<AppliedState> {
        self.installed.take()
    }

    /// Takes back the buffer [`RaftLog::take_applied`] lent, emptied.
    pub fn recycle(&mut self, mut records: Vec<Record>) {
        records.clear();
        self.applied = records;
    }

    /// Tells the followers the commit index now (the run's end: they stop soon after).
    pub fn ping(&mut self) -> Result<(), ReplicaError> {
        self.replica.ping()?;
        self.send()
    }

    /// Proposes `record`; the leader only.
    pub fn propose(&mut self, record: &Record) -> Result<(), ReplicaError> {
        self.buf.clear();
        encode_record(record, &mut self.buf)?;
        self.replica.propose(&self.buf)?;
        self.lead.proposed(&self.replica);
        self.send()
    }

    /// Sends what Raft has to say. A message that does not go out is Raft's to resend.
    fn send(&mut self) -> Result<(), ReplicaError> {
        for m in self.replica.take_messages() {
            if let Err(e) = self.link.send(&m) {
                tracing::debug!(to = m.to, "raft message not sent: {e}");
            }
        }
        Ok(())
    }

    /// Moves the committed records this replica did not decide itself into `applied`.
    fn take_committed(&mut self) -> Result<(), ReplicaError> {
        if let Some((_, state)) = self.replica.take_installed() {
            // The records not yet applied are in the snapshot's state.
            self.applied.clear();
            self.installed = Some(state);
        }
        for c in self.replica.take_committed() {
            if self.lead.decided_here(&c) {
                continue;
            }
            let record = decode_record(&c.data)
                .map_err(|p| ReplicaError::Decode(format!("committed entry {}: {p}", c.index)))?;
            self.applied.push(record);
        }
        Ok(())
    }
}
