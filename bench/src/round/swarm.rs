//! The N agents of a round benchmark, played from one process: per agent process one
//! candidate publisher and one commit subscriber (as each real `hnav-agent` has), in one
//! iceoryx2 node. An agent process hosts one robot, or `per_process` of them
//! (`[run] agents_per_process`): it then sends its robots' candidates silently and wakes the
//! coordinator once, and takes each commit once for all of them, as `hnav-agent` does.

use std::collections::HashMap;
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use anyhow::{bail, Result};

use hnav_operator::supervisor::child::Child;
use hnav_operator::supervisor::startup::SupervisorPorts;
use hnav_runtime::msg::{Candidate, CandidateFlags, CommitView, Lifecycle, Role};
use hnav_runtime::topics::{self, CommitReceiver};
use hnav_runtime::transport::{AttachmentId, Bell, BellWatch, RunId, Sender, Transport, Wake};

use super::layout::Layout;

/// How long one round may take before the benchmark gives up.
const ROUND_TIMEOUT: Duration = Duration::from_secs(10);
/// How long a round may go without any commit before it counts as stalled and the
/// coordinator is poked (rounds normally take well under 10 ms).
pub const STALL_AFTER: Duration = Duration::from_secs(1);

/// What one round looked like from the agents' side.
pub struct RoundObs<'a> {
    /// The round.
    pub round: u64,
    /// When the last candidate's `send` (publish + notify) was called.
    pub sent: Instant,
    /// When the first of the live agents' subscribers took commit `round`.
    pub first_in: Instant,
    /// When the last of the live agents' subscribers took commit `round`.
    pub all_in: Instant,
    /// Per agent: when its subscriber took commit `round` and whether the commit carries a
    /// decision for that agent (`None` for an agent without ports, i.e. down).
    pub got: &'a [Option<(Instant, bool)>],
    /// No commit came for [`STALL_AFTER`]; the round completed only after the coordinator
    /// was woken by an unrelated lifecycle event (see [`Swarm::play`]). Its times are not a
    /// latency of the system.
    pub stalled: bool,
}

/// An `after` for [`Swarm::play`] that never ends early; it reports a stalled round.
pub fn keep_going(obs: &RoundObs) -> ControlFlow<()> {
    if obs.stalled {
        hnav_runtime::errln!(
            "warning: round {} stalled: no commit for {STALL_AFTER:?} although every candidate \
             was sent; it completed only after an unrelated lifecycle event woke the \
             coordinator (a lost wake-up); not counted in the latencies",
            obs.round
        );
    }
    ControlFlow::Continue(())
}

/// The agents' ports.
pub struct Swarm {
    layout: Layout,
    /// Robots per agent process.
    per_process: usize,
    /// Agent processes that send candidates, in sending order.
    order: Vec<usize>,
    /// An agent process whose robots' next candidates carry the `RESTARTED` flag.
    restarted: Option<usize>,
    next_round: u64,
    /// Per agent process.
    tx: Vec<Option<Sender<Candidate>>>,
    /// Per agent process.
    rx: Vec<Option<CommitReceiver>>,
    /// Each agent process's watch of the commit bell, when the run has one.
    watch: Vec<Option<BellWatch>>,
    bell: Option<Bell>,
    transport: Transport,
}

impl Swarm {
    /// Opens every agent process's ports, `per_process` robots to a process; with a
    /// `bell`, each process watches it and its commit listener is one the coordinator does
    /// not send datagrams to.
    pub fn open(
        run: &RunId,
        layout: Layout,
        per_process: usize,
        bell: Option<Bell>,
    ) -> Result<Self> {
        let per_process = per_process.max(1);
        let n = layout.agents().div_ceil(per_process);
        let transport = Transport::builder(run).node_name("bench-agents").create()?;
        let mut swarm = Swarm {
            layout,
            per_process,
            order: Vec::with_capacity(n),
            restarted: None,
            next_round: 1,
            tx: (0..n).map(|_| None).collect(),
            rx: (0..n).map(|_| None).collect(),
            watch: (0..n).map(|_| None).collect(),
            bell,
            transport,
        };
        for i in 0..n {
            swarm.open_agent(i)?;
            swarm.order.push(i);
        }
        Ok(swarm)
    }

    fn open_agent(&mut self, i: usize) -> Result<()> {
        let n = self.layout.agents();
        self.tx[i] = Some(
            self.transport
                .sender(topics::CANDIDATES, topics::candidates_qos(n))?,
        );
        let qos = topics::commit_qos(n);
        self.rx[i] = Some(match &self.bell {
            Some(_) => self.transport.slice_bell_receiver(topics::COMMIT, qos)?,
            None => self.transport.slice_receiver(topics::COMMIT, qos)?,
        });
        self.watch[i] = self.bell.as_ref().map(Bell::watch).transpose()?;
        Ok(())
    }

    /// The robots of agent process `p`.
    fn robots(&self, p: usize) -> std::ops::Range<usize> {
        let first = p * self.per_process;
        first..(first + self.per_process).min(self.layout.agents())
    }

    /// Agent process `i` dies: its ports are gone and it sends nothing.
    pub fn kill(&mut self, i: usize) {
        self.tx[i] = None;
        self.rx[i] = None;
        self.watch[i] = None;
        self.order.retain(|&j| j != i);
    }

    /// Agent process `i` comes back with new ports (what a restarted process opens before it
    /// announces itself); from the next round on it sends first, its first candidate flagged
    /// `RESTARTED`.
    pub fn restart(&mut self, i: usize) -> Result<()> {
        self.open_agent(i)?;
        self.order.retain(|&j| j != i);
        self.order.insert(0, i);
        self.restarted = Some(i);
        Ok(())
    }

    /// Plays up to `rounds` rounds from the next one on against the `coordinators` (one
    /// process, or every replica of a cluster):
    /// `before_send(round)`, every live agent's candidate (one `send` per agent, through its
    /// own publisher), then a wait in the transport's `Waiter` until every live agent's subscriber has taken
    /// commit `round`; `after(obs)` may end early. Returns the rounds played. Fails if a
    /// coordinator exits or a round takes longer than 10 s.
    ///
    /// **Stalls.** If no commit comes for [`STALL_AFTER`], the coordinator is poked once
    /// through the supervisor's `life` ports with a lifecycle event it ignores (`Up` of the
    /// sim); the round is reported `stalled`. Seen
    /// under load at 128 agents: every candidate was in, yet the coordinator slept until the
    /// poke, i.e. a notification on the candidates topic was lost (a lost wake-up in the
    /// notifier/listener hand-over of iceoryx2's event service).
    pub fn play(
        &mut self,
        coordinators: &[Child],
        life: &SupervisorPorts,
        rounds: u64,
        mut before_send: impl FnMut(u64) -> Result<()>,
        mut after: impl FnMut(&RoundObs) -> ControlFlow<()>,
    ) -> Result<u64> {
        let n = self.layout.agents();
        let processes = self.tx.len();
        let waiter = self.transport.waiter()?;
        let exits = coordinators
            .iter()
            .map(|c| c.watch(&waiter))
            .collect::<Result<Vec<_>, _>>()?;
        let exit_ids: Vec<AttachmentId> = exits.iter().map(|e| e.id()).collect();
        let mut attached = Vec::with_capacity(processes);
        let mut owner: HashMap<AttachmentId, usize> = HashMap::with_capacity(processes);
        let mut live = 0;
        for (i, rx) in self.rx.iter().enumerate() {
            if let Some(rx) = rx {
                let a = waiter.attach(rx)?;
                owner.insert(a.id(), i);
                attached.push(a);
                live += 1;
            }
            if let Some(w) = &self.watch[i] {
                let a = waiter.attach_bell(w)?;
                owner.insert(a.id(), i);
                attached.push(a);
            }
        }
        let mut got: Vec<Option<(Instant, bool)>> = vec![None; n];
        let mut fired: Vec<usize> = Vec::with_capacity(processes);
        let mut played = 0;
        while played < rounds {
            let round = self.next_round;
            got.iter_mut().for_each(|g| *g = None);
            before_send(round)?;
            let mut sent = Instant::now();
            for &p in &self.order {
                let Some(tx) = &self.tx[p] else { continue };
                // The clock starts as the last candidates go out: before the last
                // process's first send.
                sent = Instant::now();
                for i in self.robots(p) {
                    let mut c = self.layout.candidate(i, round);
                    if self.restarted == Some(p) {
                        c.flags |= CandidateFlags::RESTARTED;
                    }
                    if self.per_process == 1 {
                        tx.send(c)?;
                    } else {
                        tx.send_silently(c)?;
                    }
                }
                if self.per_process > 1 {
                    tx.notify()?;
                }
            }
            self.restarted = None;
            let deadline = sent + ROUND_TIMEOUT;
            let mut missing = live;
            let mut stalled = false;
            let mut first_in = None;
            let mut all_in = sent;
            while missing > 0 {
                let now = Instant::now();
                if !stalled && missing == live && now >= sent + STALL_AFTER {
                    stalled = true;
                    life.publish(Lifecycle::up(Role::Sim, 0))?;
                }
                let left = deadline.saturating_duration_since(now);
                if left.is_zero() {
                    bail!(
                        "round {round}: {missing} of {live} agent processes got no commit within \
                         {ROUND_TIMEOUT:?}"
                    );
                }
                fired.clear();
                let mut exited = None;
                let wait = if !stalled && missing == live {
                    left.min((sent + STALL_AFTER).saturating_duration_since(now))
                } else {
                    left
                };
                let wake = waiter.wait_with(Some(now + wait), |id| {
                    if let Some(k) = exit_ids.iter().position(|e| *e == id) {
                        exited = Some(k);
                    } else if let Some(&i) = owner.get(&id) {
                        fired.push(i);
                    }
                })?;
                match wake {
                    Wake::Stop => bail!("interrupted"),
                    // Nothing named: an interrupted wait or the waiter's lost-wake-up
                    // re-check. Look at every receiver, or a lost wake-up stays lost.
                    Wake::Data if fired.is_empty() && exited.is_none() => {
                        fired.extend(owner.values().copied());
                    }
                    Wake::Data | Wake::TimedOut => {}
                }
                if let Some(k) = exited {
                    let c = &coordinators[k];
                    bail!(
                        "round {round}: {} exited ({})",
                        c.spec().role.node_name(c.spec().index),
                        c.try_reap()
                            .map_or("not reaped".to_string(), |e| e.to_string())
                    );
                }
                for &p in &fired {
                    let Some(rx) = &self.rx[p] else { continue };
                    let (robots, mut late) = (self.robots(p), None);
                    let drained = rx.drain_pending(|h, d| {
                        let c = CommitView::new(h, d);
                        if c.round() == round && got[robots.start].is_none() {
                            let now = Instant::now();
                            for i in robots.clone() {
                                let decided = c.decisions().iter().any(|d| d.agent as usize == i);
                                got[i] = Some((now, decided));
                            }
                            first_in.get_or_insert(now);
                            all_in = now;
                            missing -= 1;
                        } else if c.round() > round {
                            late.get_or_insert(c.round());
                        }
                    })?;
                    if let Some(r) = late {
                        bail!("agent process {p} got commit {r} while round {round} is open");
                    }
                    // A coordinator came to lead (or back) after this round's candidates
                    // went out: like a real agent, resend the open candidates to it.
                    if drained.wakeup.peer_up && got[robots.start].is_none() {
                        if let Some(tx) = &self.tx[p] {
                            for i in robots {
                                tx.send(self.layout.candidate(i, round))?;
                            }
                        }
                    }
                }
            }
            self.next_round += 1;
            played += 1;
            let obs = RoundObs {
                round,
                sent,
                first_in: first_in.unwrap_or(all_in),
                all_in,
                got: &got,
                stalled,
            };
            if after(&obs).is_break() {
                break;
            }
        }
        Ok(played)
    }
}
