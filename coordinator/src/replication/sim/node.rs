//! One simulated coordinator process ([`Node`]): its replica over the simulated disk, the
//! lead it takes, its inbox while paused, its tick clock, and its life (running, paused,
//! down); [`Node::call`] runs one call into the replica and collects what came out.
//!
//! A process is what the real coordinator runs, minus the link and the wall clock: a
//! [`Replica`] over a journal on its [`SimDisk`] (in a directory of the run's scratch
//! directory), whose early messages ([`Replica::send_early_to`]) and outbox the scheduler
//! carries, and a [`Lead`] that decides when it may propose and when a proposal is final.
//! Raft draws election timeouts from the thread's random numbers; the process replaces each
//! draw with one from the run's seed ([`Replica::set_election_timeout`]) after every call,
//! drawing anew when the role or term changed or an election began.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::path::PathBuf;
use std::rc::Rc;

use hnav_runtime::consensus_log::{AppliedState, RunHeader, WriterOptions};
use hnav_runtime::scenario::FsyncPolicy;
use raft::eraftpb::{HardState, Message, MessageType};
use raft::Storage;

use super::super::error::ReplicaError;
use super::super::lead::Lead;
use super::super::peer::{Committed, Replica, ReplicaConfig, Role};
use super::checker::LogEntry;
use super::clock::{TickClock, Time};
use super::disk::{Fired, SimDisk};
use super::rng::Rng;

/// Messages a paused process's inbox holds per sender before the oldest is overwritten, as
/// the `raft/<i>` topics do.
pub const INBOX: usize = 32;

/// Bytes at which the simulated journal starts a new segment: small, so that runs cross
/// segment boundaries (and crash in the middle of one).
pub const SEGMENT_BYTES: u64 = 4096;

/// A running process.
pub struct Process {
    /// The replica.
    pub replica: Replica<SimDisk>,
    /// Whether it decides, and its last proposal.
    pub lead: Lead,
    early: Rc<RefCell<Vec<Message>>>,
    pinned: usize,
    seen: (u64, Role),
    /// The record it proposed and has not seen settle, and when it proposed it.
    pub outstanding: Option<(Vec<u8>, Time)>,
    /// When it may propose next.
    pub next_proposal: Time,
}

/// What one call into a replica gave.
pub struct Called {
    /// The messages it sent, in order (the early ones first).
    pub messages: Vec<Message>,
    /// What it handed out as committed.
    pub committed: Vec<Committed>,
    /// A snapshot it started from before `committed` (its journal's after a restart, or its
    /// leader's), with the index it stands for.
    pub installed: Option<(u64, AppliedState)>,
    /// Whether `installed` came from the leader (not from the journal).
    pub from_leader: bool,
    /// The call's result.
    pub result: Result<(), ReplicaError>,
}

/// One coordinator process slot; see the [module docs](self).
pub struct Node {
    /// Its replica's id.
    pub id: u64,
    config: ReplicaConfig,
    dir: PathBuf,
    disk: SimDisk,
    /// Its tick clock.
    pub clock: TickClock,
    /// The running process; `None` while down.
    pub process: Option<Process>,
    /// Paused (`SIGSTOP`): nothing runs, messages wait in the inbox.
    pub paused: bool,
    /// Kept down until then (`stop`).
    pub stopped_until: Option<Time>,
    /// Messages that arrived while paused, per sender.
    inbox: Vec<VecDeque<Message>>,
    /// Incarnations started.
    pub incarnations: u32,
    timeouts: Rng,
}

impl Node {
    /// Replica `id` of `voters`, its journal in `dir` on `disk`, its tick every `period` us;
    /// not started.
    pub fn new(config: ReplicaConfig, dir: PathBuf, disk: SimDisk, period: u64, rng: Rng) -> Self {
        let n = config.voters.len();
        Node {
            id: config.id,
            config,
            dir,
            disk,
            clock: TickClock::new(period),
            process: None,
            paused: false,
            stopped_until: None,
            inbox: vec![VecDeque::new(); n],
            incarnations: 0,
            timeouts: rng,
        }
    }

    /// Its disk.
    pub fn disk(&self) -> &SimDisk {
        &self.disk
    }

    /// Whether it is running (up and not paused).
    pub fn running(&self) -> bool {
        self.process.is_some() && !self.paused
    }

    /// Starts a new incarnation over the journal; the committed entries it holds come out
    /// of the first [`Node::call`]. On an error the node stays down, its disk cut back as
    /// the fault that failed it says.
    pub fn start(&mut self, now: Time) -> Result<HardState, ReplicaError> {
        self.incarnations += 1;
        let disk = self.disk.incarnation();
        let options = WriterOptions {
            fsync: FsyncPolicy::EveryRecord,
            segment_bytes: SEGMENT_BYTES,
        };
        let opened = Replica::durable_on(disk.clone(), &self.config, &self.dir, header(), options);
        let mut replica = match opened {
            Ok(r) => r,
            Err(e) => {
                let _ = disk.crash(disk.fired());
                return Err(e);
            }
        };
        self.disk = disk;
        let early = Rc::new(RefCell::new(Vec::new()));
        let out = Rc::clone(&early);
        replica.send_early_to(move |m| out.borrow_mut().push(m.clone()));
        let hs = replica.storage().mem().rl().hard_state().clone();
        let seen = (replica.term(), replica.role());
        self.process = Some(Process {
            replica,
            lead: Lead::new(),
            early,
            pinned: 0,
            seen,
            outstanding: None,
            next_proposal: now,
        });
        self.draw_timeout();
        Ok(hs)
    }

    /// The process exits or dies: killed (`how` none: the page cache stays), after a
    /// failed write or fsync, or in a power loss.
    pub fn crash(&mut self, how: Option<Fired>) {
        self.disk.kill();
        self.process = None;
        self.paused = false;
        self.clock.stop();
        self.inbox.iter_mut().for_each(VecDeque::clear);
        if let Err(e) = self.disk.crash(how) {
            panic!("the simulation's scratch directory failed: {e}");
        }
    }

    /// Runs `f` on the replica and collects what came out; `None` if it is not running.
    pub fn call(
        &mut self,
        f: impl FnOnce(&mut Replica<SimDisk>) -> Result<(), ReplicaError>,
    ) -> Option<Called> {
        if self.paused {
            return None;
        }
        let p = self.process.as_mut()?;
        let installs = p.replica.installs();
        let result = f(&mut p.replica);
        let from_leader = p.replica.installs() > installs;
        let mut messages: Vec<Message> = p.early.borrow_mut().drain(..).collect();
        messages.extend(p.replica.take_messages());
        let installed = p.replica.take_installed();
        let committed = p.replica.take_committed().collect();
        let now = (p.replica.term(), p.replica.role());
        let campaigned = messages.iter().any(|m| {
            matches!(
                m.get_msg_type(),
                MessageType::MsgRequestVote | MessageType::MsgRequestPreVote
            )
        });
        let changed = now != p.seen || campaigned;
        p.seen = now;
        if changed {
            self.draw_timeout();
        } else {
            p.replica.set_election_timeout(p.pinned);
        }
        Some(Called {
            messages,
            committed,
            installed,
            from_leader,
            result,
        })
    }

    fn draw_timeout(&mut self) {
        let Some(p) = self.process.as_mut() else {
            return;
        };
        let (lo, hi) = p.replica.election_timeout_range();
        p.pinned = self.timeouts.range(lo as u64, hi as u64) as usize;
        p.replica.set_election_timeout(p.pinned);
    }

    /// Keeps a message that arrived while paused (the oldest of its sender's dropped when
    /// the inbox is full).
    pub fn hold(&mut self, m: Message) {
        let q = &mut self.inbox[m.from as usize - 1];
        if q.len() == INBOX {
            q.pop_front();
        }
        q.push_back(m);
    }

    /// The messages held while paused, sender by sender.
    pub fn take_held(&mut self) -> Vec<Message> {
        self.inbox.iter_mut().flat_map(|q| q.drain(..)).collect()
    }

    /// The replica's role and term, if it runs.
    pub fn role(&self) -> Option<(Role, u64)> {
        let p = self.process.as_ref()?;
        Some((p.replica.role(), p.replica.term()))
    }

    /// The replica's log: the index its snapshot stands for (0 if none), and (term, data)
    /// per index after it.
    pub fn log(&self) -> Option<(u64, Vec<LogEntry>)> {
        let p = self.process.as_ref()?;
        let s = p.replica.storage();
        let (first, last) = (s.first_index().ok()?, s.last_index().ok()?);
        if last < first {
            return Some((first - 1, Vec::new()));
        }
        let ctx = raft::GetEntriesContext::empty(false);
        let entries = s.entries(first, last + 1, None, ctx).ok()?;
        let entries = entries
            .into_iter()
            .map(|e| (e.term, e.data.to_vec()))
            .collect();
        Some((first - 1, entries))
    }

    /// The index its snapshot stands for (0 if none, or while down).
    pub fn compacted(&self) -> u64 {
        self.process
            .as_ref()
            .map_or(0, |p| p.replica.snapshot_index())
    }

    /// The highest index the replica knows committed (0 while down).
    pub fn committed_index(&self) -> u64 {
        self.process
            .as_ref()
            .map_or(0, |p| p.replica.committed_index())
    }

    /// The term of the replica's entry at `index`, if it holds one.
    pub fn term_at(&self, index: u64) -> Option<u64> {
        let p = self.process.as_ref()?;
        let s = p.replica.storage();
        if index > s.last_index().ok()? {
            return None;
        }
        s.term(index).ok()
    }
}

/// The journal's header: the same for every replica and run.
pub fn header() -> RunHeader {
    RunHeader {
        version: 0,
        scenario_hash: 0x5157,
        seed: 0,
        clock: "raft-sim".into(),
        width: 1,
        height: 1,
        agents: Vec::new(),
    }
}
