//! The campaign's observer of one run: a node of the run subscribed to the commits, the
//! lifecycle events, the candidates and the ground truth, stamping every sample with
//! [`monotonic_ns`] (the supervisor's `events.jsonl` carries the same clock).
//!
//! It joins before `hnav run` starts anything, so it sees every commit, and it leaves as soon
//! as the supervisor publishes `Stop`, so that the supervisor's clean-up finds no live node
//! of the run and removes every file.

use hnav_runtime::clock::monotonic_ns;
use hnav_runtime::hash::Fnv1a64;
use hnav_runtime::msg::{Candidate, CommitView, Lifecycle, LifecycleEvent, Role};
use hnav_runtime::topics::{self, CommitReceiver, TruthReceiver};
use hnav_runtime::transport::{Receiver, RunId, Transport, TransportError, Waiter};

/// One commit as the observer received it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SeenCommit {
    /// When it was taken ([`monotonic_ns`]).
    pub t_ns: u64,
    /// Its round.
    pub round: u64,
    /// [`commit_digest`] of it.
    pub digest: u64,
}

/// A lifecycle event about one process, as the observer received it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SeenLifecycle {
    /// When it was taken.
    pub t_ns: u64,
    /// `Down` or `Restarted`.
    pub event: LifecycleEvent,
    /// The process's role.
    pub role: Role,
    /// Its agent index (0 for the sim and the coordinator).
    pub index: u32,
}

/// Everything the observer saw of one run, in order of receipt.
#[derive(Debug, Default, Clone)]
pub struct Observed {
    /// Every commit.
    pub commits: Vec<SeenCommit>,
    /// `Down` and `Restarted` events.
    pub lifecycle: Vec<SeenLifecycle>,
    /// Each candidate's stamp and agent.
    pub candidates: Vec<(u64, u32)>,
    /// Each ground-truth sample's stamp.
    pub truths: Vec<u64>,
    /// When `Start` arrived.
    pub started_ns: Option<u64>,
    /// When `Stop` arrived.
    pub stopped_ns: Option<u64>,
}

/// A digest of a commit's round and valid decisions, equal for equal commits: the log's
/// commit of a round and the one received are compared through it, without keeping every
/// round's decisions.
pub fn commit_digest(c: CommitView<'_>) -> u64 {
    let mut h = Fnv1a64::new();
    h.u64(c.round()).u64(c.decisions().len() as u64);
    for d in c.decisions() {
        h.u64(u64::from(d.agent))
            .u64(u64::from(d.verdict))
            .u64(u64::from(d.refused))
            .u64(u64::from(d.kind))
            .u64(u64::from(d.cell))
            .u64(u64::from(d.waypoint));
    }
    h.finish()
}

/// The observer's node and ports in one run.
pub struct Observer {
    transport: Transport,
    commit: CommitReceiver,
    life: Receiver<Lifecycle>,
    candidates: Receiver<Candidate>,
    truth: TruthReceiver,
}

impl Observed {
    /// Empty, with room reserved for a run of the chaos scenario (a few hundred rounds of
    /// `agents` candidates), so the receive loop does not grow its buffers mid-run.
    pub fn with_room(agents: usize) -> Self {
        let mut seen = Observed::default();
        seen.commits.reserve(4096);
        seen.candidates.reserve(4096 * agents.max(1));
        seen.truths.reserve(4096);
        seen
    }
}

impl Observer {
    /// Joins `run` (a swarm of `agents`) with the QoS every process of it uses. Room for
    /// this observer: every topic admits `Qos::EXTRA_NODES` nodes besides the agents, of
    /// which the sim, the coordinator (twice while a restarted one replaces a dead one) and
    /// the supervisor use at most three.
    pub fn join(run: &RunId, agents: usize) -> Result<Observer, TransportError> {
        let transport = Transport::builder(run)
            .node_name("chaos-observer")
            .handle_signals(false)
            .create()?;
        Ok(Observer {
            commit: transport.slice_receiver(topics::COMMIT, topics::commit_qos(agents))?,
            life: transport.receiver(topics::LIFECYCLE, topics::lifecycle_qos(agents))?,
            candidates: transport.receiver(topics::CANDIDATES, topics::candidates_qos(agents))?,
            truth: transport.slice_receiver(topics::TRUTH, topics::truth_qos())?,
            transport,
        })
    }

    /// A waiter of the observer's node (attach [`Observer::attach`] and the child to it).
    pub fn waiter(&self) -> Result<Waiter, TransportError> {
        self.transport.waiter()
    }

    /// Attaches the four receivers to `waiter`; keep the returned guards while waiting.
    pub fn attach<'w, 'a>(
        &'a self,
        waiter: &'w Waiter,
    ) -> Result<Vec<hnav_runtime::transport::Attachment<'w, 'a>>, TransportError> {
        Ok(vec![
            waiter.attach(&self.commit)?,
            waiter.attach(&self.life)?,
            waiter.attach(&self.candidates)?,
            waiter.attach(&self.truth)?,
        ])
    }

    /// Takes everything pending on the four topics, stamping each sample as it is taken.
    /// Candidates are drained first: their delivery applies backpressure, and an agent must
    /// never wait on the observer.
    pub fn drain(&self, seen: &mut Observed) -> Result<(), TransportError> {
        self.candidates
            .drain_pending(|c| seen.candidates.push((monotonic_ns(), c.agent)))?;
        self.commit.drain_pending(|h, d| {
            let c = CommitView::new(h, d);
            seen.commits.push(SeenCommit {
                t_ns: monotonic_ns(),
                round: c.round(),
                digest: commit_digest(c),
            })
        })?;
        self.truth
            .drain_pending(|_, _| seen.truths.push(monotonic_ns()))?;
        self.life.drain_pending(|l| {
            let t_ns = monotonic_ns();
            match LifecycleEvent::from_u8(l.event) {
                Some(LifecycleEvent::Start) => seen.started_ns = seen.started_ns.or(Some(t_ns)),
                Some(LifecycleEvent::Stop) => seen.stopped_ns = seen.stopped_ns.or(Some(t_ns)),
                Some(event @ (LifecycleEvent::Down | LifecycleEvent::Restarted)) => {
                    if let Some(role) = Role::from_u8(l.role) {
                        seen.lifecycle.push(SeenLifecycle {
                            t_ns,
                            event,
                            role,
                            index: l.index,
                        });
                    }
                }
                _ => {}
            }
        })?;
        Ok(())
    }
}
