//! A call into a replica and what follows it, as the coordinator's loop would have it:
//! the messages it sent go on the network, the committed entries are applied, and then the
//! coordinator's own step: a deposed leader exits, a leader whose last proposal settled
//! acknowledges it, and one that may decide proposes the next record. A call that fails on
//! the journal is the process exiting; its supervisor restarts it.

use hnav_runtime::consensus_log::{encode_record, AppliedState, Record, RoundRecord};
use protobuf::Message as _;
use raft::eraftpb::Message;

use super::super::super::error::ReplicaError;
use super::super::super::lead::Lead;
use super::super::super::link::MAX_MESSAGE_BYTES;
use super::super::super::peer::Role;
use super::super::disk::Fired;
use super::super::node::{header, Called};
use super::{Ev, Sabotage, World, HEAL};

/// How long a supervisor waits before it restarts a process that exited: from 20 to 300 ms.
const RESTART_US: (u64, u64) = (20_000, 300_000);

/// A leader's pause between two decisions: up to 30 ms.
const DECIDE_US: u64 = 30_000;

impl World {
    /// One tick of replica `i`.
    pub(super) fn tick_now(&mut self, i: usize) {
        if let Some(called) = self.nodes[i].call(|r| r.tick()) {
            self.after(i, called);
        }
    }

    /// Replica `i` takes message `m`. A message Raft refuses (stale, of another term) is
    /// Raft's business; a journal that fails is the process's end.
    pub(super) fn step(&mut self, i: usize, m: Message) {
        let called = self.nodes[i].call(|r| match r.step(m) {
            Err(e @ (ReplicaError::Log(_) | ReplicaError::Decode(_))) => Err(e),
            _ => Ok(()),
        });
        if let Some(called) = called {
            self.after(i, called);
        }
    }

    /// The coordinator of replica `i` looks whether it may decide.
    pub(super) fn wake(&mut self, i: usize) {
        if let Some(called) = self.nodes[i].call(|_| Ok(())) {
            self.after(i, called);
        }
    }

    /// The supervisor starts replica `i` again (unless it runs, or is kept down).
    pub(super) fn restart(&mut self, i: usize) {
        let node = &mut self.nodes[i];
        if node.process.is_some() || node.stopped_until.is_some_and(|t| t > self.now) {
            return;
        }
        node.stopped_until = None;
        match node.start(self.now) {
            Ok(hs) => {
                let id = node.id;
                let phase = self.rng.range(0, super::TICK_US);
                if let Some(at) = self.nodes[i].clock.start_with_phase(self.now, phase) {
                    self.push(at, Ev::Tick(i));
                }
                self.checker.started(self.now, id, &hs);
                self.note(|| format!("n{id} started (term {}, vote {})", hs.term, hs.vote));
                self.wake(i);
            }
            Err(e) => {
                let id = node.id;
                self.note(|| format!("n{id} failed to start: {e}"));
                self.restart_later(i);
            }
        }
    }

    pub(super) fn restart_later(&mut self, i: usize) {
        let at = self.now.after(self.rng.range(RESTART_US.0, RESTART_US.1));
        self.push(at, Ev::Restart(i));
    }

    /// The process of replica `i` exits, or dies: `how` says what its disk keeps.
    pub(super) fn crash(&mut self, i: usize, how: Option<Fired>, why: &str) {
        let id = self.nodes[i].id;
        self.note(|| format!("n{id} exits: {why}"));
        self.crashes += 1;
        self.nodes[i].crash(how);
        self.restart_later(i);
    }

    /// What follows a call into replica `i`, until its coordinator has nothing to propose.
    fn after(&mut self, i: usize, mut called: Called) {
        let id = self.nodes[i].id;
        loop {
            for m in std::mem::take(&mut called.messages) {
                self.send(m);
            }
            if let Err(e) = called.result {
                let fired = self.nodes[i].disk().fired();
                let why = match fired {
                    Some(Fired::Power) => format!("power lost during a write ({e})"),
                    Some(Fired::Fsync) => format!("{e}; the unsynced writes are lost"),
                    _ => e.to_string(),
                };
                self.crash(i, fired, &why);
                return;
            }
            if let Some(installed) = &called.installed {
                let fresh = AppliedState::new(&header());
                self.checker.installed(self.now, id, installed, fresh);
                if called.from_leader {
                    self.installs += 1;
                    self.note(|| format!("n{id} installed the snapshot at {}", installed.0));
                }
            }
            self.checker.committed(self.now, id, &called.committed);
            if let Some(p) = &self.nodes[i].process {
                for c in called.committed.iter().filter(|c| !p.lead.decided_here(c)) {
                    self.checker.applied(self.now, id, &c.data);
                }
            }
            if let Some((role, term)) = self.nodes[i].role() {
                if self.checker.role(self.now, id, role, term) {
                    self.note(|| format!("n{id} leads term {term}"));
                    let node = &self.nodes[i];
                    let compacted = node.compacted();
                    self.checker
                        .complete(self.now, (id, term), compacted, |index| node.term_at(index));
                    self.check_logs();
                }
                if role == Role::Leader {
                    let committed = self.nodes[i].committed_index();
                    self.checker.leader_committed(term, committed);
                }
            }
            match self.decide(i) {
                Some(next) => called = next,
                None => return,
            }
        }
    }

    /// The coordinator's step after a pass of its replica: exit if deposed, acknowledge a
    /// settled proposal, propose the next record when one is due. The call of a proposal,
    /// if it made one.
    fn decide(&mut self, i: usize) -> Option<Called> {
        let now = self.now;
        let node = &mut self.nodes[i];
        let id = node.id;
        let p = node.process.as_mut()?;
        if let Some(term) = p.lead.deposed(&p.replica) {
            if self.sabotage == Sabotage::StaleLeader {
                p.lead = Lead::new();
                p.outstanding = None;
                return None;
            }
            self.crash(i, None, &format!("deposed from term {term}"));
            return None;
        }
        if !p.lead.take(&p.replica) {
            return None;
        }
        if p.outstanding.is_some() {
            if p.lead.settled(&p.replica) {
                self.ack(i);
            }
            return None;
        }
        if now < p.next_proposal {
            return None;
        }
        self.next_record += 1;
        let mut record = Vec::new();
        let round = RoundRecord::new(self.next_record, &[], &[]);
        encode_record(&Record::Round(round), &mut record).expect("a round record encodes");
        // The coordinator applies its decision when it makes it, before it is logged.
        self.checker.applied(now, id, &record);
        let node = &mut self.nodes[i];
        let called = node.call(|r| r.propose(&record))?;
        let p = node.process.as_mut()?;
        p.lead.proposed(&p.replica);
        p.outstanding = Some((record, now));
        if self.sabotage == Sabotage::EarlyAck && called.result.is_ok() {
            self.ack(i);
        }
        Some(called)
    }

    /// The coordinator of replica `i` acknowledges its outstanding proposal (its round's
    /// `Commit` leaves) and waits a little before the next.
    fn ack(&mut self, i: usize) {
        let now = self.now;
        let node = &mut self.nodes[i];
        let (id, incarnation) = (node.id, node.incarnations);
        let Some(p) = node.process.as_mut() else {
            return;
        };
        let Some((record, proposed_at)) = p.outstanding.take() else {
            return;
        };
        let index = p.lead.last_proposal();
        p.next_proposal = now.after(self.rng.range(1, DECIDE_US));
        let wake = p.next_proposal;
        self.checker.acked(now, index, &record);
        if self.healed && proposed_at >= HEAL && self.recovered.is_none() {
            self.recovered = Some((now, index));
            self.note(|| format!("n{id} commits index {index}, the first since the heal"));
        }
        self.push(wake, Ev::Wake(i, incarnation));
    }

    /// Puts `m` on the network.
    fn send(&mut self, m: Message) {
        self.checker.sent(self.now, m.from, &m);
        // The link refuses a message over its topic's size; Raft resends.
        if m.compute_size() as usize > MAX_MESSAGE_BYTES {
            return;
        }
        for at in self.network.route(self.now, m.from, m.to) {
            self.push(at, Ev::Deliver(m.clone()));
        }
    }
}
