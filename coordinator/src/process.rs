//! The `hnav-coordinator` process: the central compute block of the run.
//!
//! It blocks in one WaitSet on the candidate and lifecycle topics. A round (`last + 1`)
//! closes when every live agent's candidate for it is in; in **realtime** also when
//! `round_deadline_ms` has passed since the round's first candidate (the missing agents count
//! as standing still); in **lockstep** only liveness closes it (an agent the supervisor
//! reports down stops being waited for), so a run's rounds do not depend on timing. Then:
//! [`Arbiter::decide`], append the round (and its replans) to the consensus log, and only
//! then publish the [`Commit`] — under the default fsync policy a commit an agent sees is
//! already durable.
//!
//! **Restart.** On start the log in `DIR/log` is opened; a torn tail is cut off, the complete
//! records are replayed: the last round number, the tallies and whether the run ended. The
//! agents still waiting for the last logged round get its commit again, rebuilt from the log
//! (never decided twice); a round in flight when the old coordinator died is decided anew from
//! the candidates the agents resend.
//!
//! Once every agent stands on its goal the coordinator logs the end of the run and decides
//! nothing more, so the log of a lockstep run ends at the same record whatever the
//! supervisor's timing.

use std::path::Path;
use std::time::{Duration, Instant};

use hnav_runtime::consensus_log::{
    candidates_digest, AgentEntry, EndReason, EndRecord, LifecycleRecord, LogError, LogWriter,
    LoggedDecision, Record, RoundRecord, RunHeader, FORMAT_VERSION,
};
use hnav_runtime::launch::{LifecyclePorts, StartOutcome, LOST_WAKEUP_RECHECK};
use hnav_runtime::msg::{
    Candidate, Commit, Lifecycle, LifecycleEvent, Progress, Role, StopReason, MAX_AGENTS,
};
use hnav_runtime::scenario::{ClockMode, Scenario};
use hnav_runtime::topics;
use hnav_runtime::transport::{Receiver, Sender, Transport, TransportError};
use iceoryx2::prelude::CallbackProgression;
use iceoryx2::waitset::WaitSetRunResult;

use crate::round::Arbiter;

/// How long the coordinator waits for the supervisor's start signal.
pub const START_TIMEOUT: Duration = Duration::from_secs(60);

/// What stopped or broke the coordinator.
#[derive(Debug, thiserror::Error)]
pub enum CoordinatorError {
    /// The transport failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// The consensus log failed: no commit may be published without it.
    #[error(transparent)]
    Log(#[from] LogError),
    /// The log belongs to another scenario or seed.
    #[error("the log in {dir} was written for another run: {what}")]
    ForeignLog {
        /// The log directory.
        dir: String,
        /// What differs.
        what: String,
    },
    /// The swarm is larger than a commit can carry.
    #[error("{0} agents; a commit carries at most {MAX_AGENTS}")]
    TooManyAgents(usize),
    /// The WaitSet failed.
    #[error("waitset: {0}")]
    WaitSet(String),
}

/// How the coordinator's run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CoordinatorOutcome {
    /// Last committed round.
    pub round: u64,
    /// Whether every agent reached its goal.
    pub all_at_goal: bool,
    /// Candidates dropped as malformed.
    pub dropped: u64,
}

struct Ports {
    candidates: Receiver<Candidate>,
    commit: Sender<Commit>,
    progress: Sender<Progress>,
    life: LifecyclePorts,
}

struct State {
    arbiter: Arbiter,
    log: LogWriter,
    clock: ClockMode,
    deadline: Duration,
    round: u64,
    last_record: Option<RoundRecord>,
    pending: Vec<Option<Candidate>>,
    present: Vec<Candidate>,
    live: Vec<bool>,
    opened: Option<Instant>,
    ended: bool,
    dropped: u64,
    restarts: Vec<u32>,
}

/// The coordinator process.
pub struct CoordinatorProcess<'t> {
    transport: &'t Transport,
    ports: Ports,
    state: State,
}

fn header(s: &Scenario) -> RunHeader {
    let g = &s.map.grid;
    RunHeader {
        version: FORMAT_VERSION,
        scenario_hash: s.scenario_hash(),
        seed: s.sim.seed,
        clock: match s.sim.clock {
            ClockMode::Lockstep => "lockstep".into(),
            ClockMode::Realtime => "realtime".into(),
        },
        width: g.width(),
        height: g.height(),
        agents: s
            .agents
            .iter()
            .map(|a| AgentEntry {
                start: g.index(a.start) as u32,
                goal: g.index(a.goal) as u32,
                speed: a.speed,
                priority: a.effective_priority(),
            })
            .collect(),
    }
}

impl<'t> CoordinatorProcess<'t> {
    /// Opens the ports and the log in `run_dir/log`, replaying what the log holds.
    pub fn new(
        transport: &'t Transport,
        scenario: &Scenario,
        run_dir: &Path,
    ) -> Result<Self, CoordinatorError> {
        let n = scenario.agents.len();
        if n > MAX_AGENTS {
            return Err(CoordinatorError::TooManyAgents(n));
        }
        let ports = Ports {
            candidates: transport.receiver(topics::CANDIDATES, topics::candidates_qos(n))?,
            commit: transport.sender(topics::COMMIT, topics::commit_qos(n))?,
            progress: transport.sender(topics::PROGRESS, topics::state_qos())?,
            life: LifecyclePorts::open(transport, Role::Coordinator, 0, n)?,
        };
        let dir = run_dir.join("log");
        let (log, recovered) = LogWriter::open(&dir, scenario.coordinator.fsync)?;
        if recovered.truncated_bytes > 0 {
            tracing::warn!(
                bytes = recovered.truncated_bytes,
                "cut a torn tail off the consensus log"
            );
        }
        let mut state = State {
            arbiter: Arbiter::new(scenario),
            clock: scenario.sim.clock,
            deadline: Duration::from_millis(u64::from(scenario.coordinator.round_deadline_ms)),
            round: 0,
            last_record: None,
            pending: vec![None; n],
            present: Vec::with_capacity(n),
            live: vec![true; n],
            opened: None,
            ended: false,
            dropped: 0,
            restarts: vec![0; n],
            log,
        };
        let expected = header(scenario);
        match recovered.records.first() {
            None => {
                state.log.append(&Record::Header(expected))?;
            }
            Some(Record::Header(h)) if *h == expected => {}
            Some(other) => {
                return Err(CoordinatorError::ForeignLog {
                    dir: dir.display().to_string(),
                    what: format!("first record {:?}", other.kind()),
                })
            }
        }
        for r in &recovered.records {
            state.replay(r);
        }
        if state.round > 0 {
            tracing::info!(round = state.round, "resumed from the consensus log");
        }
        Ok(CoordinatorProcess {
            transport,
            ports,
            state,
        })
    }

    /// Announces itself, waits for the start (unless `resume`) and runs rounds until the
    /// supervisor's `Stop` or a termination signal.
    pub fn run(&mut self, resume: bool) -> Result<CoordinatorOutcome, CoordinatorError> {
        let started = self
            .ports
            .life
            .handshake(self.transport, resume, START_TIMEOUT)?;
        let (p, st) = (&self.ports, &mut self.state);
        if started == StartOutcome::Stopped {
            if !st.ended {
                st.end(EndReason::Stopped)?;
            }
            return Ok(st.outcome());
        }
        if let Some(rec) = &st.last_record {
            // Agents that missed the dead coordinator's last commit get it again.
            p.commit.send_in_place(|slot| rec.write_commit(slot))?;
        }
        st.publish_progress(p)?;
        let ws = self.transport.waitset()?;
        let ws_err = |e: &dyn std::fmt::Debug| CoordinatorError::WaitSet(format!("{e:?}"));
        let _g1 = ws
            .attach_notification(p.candidates.listener())
            .map_err(|e| ws_err(&e))?;
        let _g2 = ws
            .attach_notification(p.life.events().listener())
            .map_err(|e| ws_err(&e))?;
        let reason = loop {
            let mut events: Vec<(Role, u32, LifecycleEvent)> = Vec::new();
            let stop = p.life.drain(|r, i, e| events.push((r, i, e)))?;
            for (role, index, ev) in events {
                st.on_lifecycle(role, index, ev)?;
            }
            if let Some(reason) = stop {
                break match reason {
                    StopReason::TimeLimit => EndReason::TimeLimit,
                    StopReason::Requested => EndReason::Stopped,
                };
            }
            st.collect(p)?;
            if st.ready() {
                st.close_round(p)?;
                continue;
            }
            let timeout = match (st.clock, st.opened) {
                (ClockMode::Realtime, Some(t)) => Some(st.deadline.saturating_sub(t.elapsed())),
                _ => None,
            };
            let r = match timeout {
                Some(t) if t.is_zero() => {
                    st.close_round(p)?;
                    continue;
                }
                Some(t) => {
                    ws.wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, t)
                }
                None => ws.wait_and_process_once_with_timeout(
                    |_| CallbackProgression::Continue,
                    LOST_WAKEUP_RECHECK,
                ),
            };
            match r {
                Ok(WaitSetRunResult::TerminationRequest | WaitSetRunResult::Interrupt) => {
                    break EndReason::Stopped;
                }
                Ok(_) => {}
                Err(e) => return Err(ws_err(&e)),
            }
        };
        if !st.ended {
            st.end(reason)?;
        }
        st.log.sync()?;
        Ok(st.outcome())
    }
}

impl State {
    fn outcome(&self) -> CoordinatorOutcome {
        CoordinatorOutcome {
            round: self.round,
            all_at_goal: self.ended && self.arbiter.at_goal() as usize == self.arbiter.agents(),
            dropped: self.dropped,
        }
    }

    /// Folds one record of an existing log into the state.
    fn replay(&mut self, r: &Record) {
        match r {
            Record::Round(rec) => {
                self.round = self.round.max(rec.round);
                self.arbiter.replay(rec);
                self.last_record = Some(rec.clone());
            }
            Record::End(_) => self.ended = true,
            Record::Lifecycle(l) => {
                if let Some(r) = self.restarts.get_mut(l.index as usize) {
                    *r = (*r).max(l.restarts);
                }
            }
            Record::Header(_) | Record::Replan(_) => {}
        }
    }

    /// A supervisor event: liveness of agents, logged for the record.
    fn on_lifecycle(
        &mut self,
        role: Role,
        index: u32,
        ev: LifecycleEvent,
    ) -> Result<(), CoordinatorError> {
        if !matches!(ev, LifecycleEvent::Down | LifecycleEvent::Restarted) {
            return Ok(());
        }
        if role == Role::Agent {
            if let Some(l) = self.live.get_mut(index as usize) {
                *l = ev == LifecycleEvent::Restarted;
            }
        }
        if role == Role::Agent && ev == LifecycleEvent::Restarted {
            if let Some(r) = self.restarts.get_mut(index as usize) {
                *r += 1;
            }
        }
        if !self.ended {
            let restarts = self
                .restarts
                .get(index as usize)
                .copied()
                .unwrap_or_default();
            let event = match ev {
                LifecycleEvent::Restarted => Lifecycle::restarted(role, index, restarts),
                _ => Lifecycle::down(role, index, restarts),
            };
            self.log
                .append(&Record::Lifecycle(LifecycleRecord::new(self.round, &event)))?;
        }
        Ok(())
    }

    /// Takes every candidate in; keeps those for the open round, re-sends the last commit to
    /// agents asking for a round already decided.
    fn collect(&mut self, p: &Ports) -> Result<(), CoordinatorError> {
        p.candidates.take_wakeup()?;
        let mut resend = false;
        while let Some(s) = p.candidates.receive()? {
            let c = *s.payload();
            if !self.arbiter.valid(&c) {
                self.dropped += 1;
                tracing::warn!(
                    agent = c.agent,
                    round = c.round,
                    "malformed candidate dropped"
                );
                continue;
            }
            let i = c.agent as usize;
            if c.round == self.round + 1 && !self.ended {
                if self.pending.iter().all(Option::is_none) {
                    self.opened = Some(Instant::now());
                }
                self.pending[i] = Some(c);
                self.live[i] = true;
            } else if c.round <= self.round && self.round > 0 {
                // An agent behind (a restarted one, or one the dead coordinator never
                // answered): the last commit brings it up to date.
                resend = true;
            }
        }
        if resend {
            if let Some(rec) = &self.last_record {
                p.commit.send_in_place(|slot| rec.write_commit(slot))?;
            }
        }
        Ok(())
    }

    /// Whether the open round has every live agent's candidate.
    fn ready(&self) -> bool {
        !self.ended
            && self.pending.iter().any(Option::is_some)
            && self
                .live
                .iter()
                .zip(&self.pending)
                .all(|(&l, c)| !l || c.is_some())
    }

    /// Decides the open round, makes it durable, then commits it.
    fn close_round(&mut self, p: &Ports) -> Result<(), CoordinatorError> {
        let round = self.round + 1;
        let (decisions, replans) = self.arbiter.decide(round, &self.pending);
        for r in replans {
            self.log.append(&Record::Replan(r.clone()))?;
        }
        // The record's buffers are reused round after round: no allocation once warm.
        self.present.clear();
        self.present.extend(self.pending.iter().flatten());
        let mut rec = self
            .last_record
            .take()
            .unwrap_or_else(|| RoundRecord::new(0, &[], &[]));
        rec.round = round;
        rec.candidates = self.present.len() as u32;
        rec.candidates_digest = candidates_digest(&self.present);
        rec.decisions.clear();
        rec.decisions
            .extend(decisions.iter().map(LoggedDecision::from));
        let record = Record::Round(rec);
        self.log.append(&record)?;
        let Record::Round(rec) = record else {
            unreachable!("built as a round record above")
        };
        p.commit.send_in_place(|slot| rec.write_commit(slot))?;
        self.last_record = Some(rec);
        self.round = round;
        self.pending.iter_mut().for_each(|c| *c = None);
        self.opened = None;
        if self.arbiter.at_goal() as usize == self.arbiter.agents() {
            self.end(EndReason::AllAtGoal)?;
        }
        self.publish_progress(p)
    }

    fn end(&mut self, reason: EndReason) -> Result<(), CoordinatorError> {
        self.log.append(&Record::End(EndRecord {
            round: self.round,
            at_goal: self.arbiter.at_goal(),
            reason,
        }))?;
        self.log.sync()?;
        self.ended = true;
        Ok(())
    }

    fn publish_progress(&self, p: &Ports) -> Result<(), CoordinatorError> {
        let t = self.arbiter.tally();
        p.progress.send(Progress {
            round: self.round,
            agents: self.arbiter.agents() as u32,
            at_goal: self.arbiter.at_goal(),
            conflicts: t.conflicts(),
            replans: t.replans(),
            done: u8::from(self.ended && self.arbiter.at_goal() as usize == t.agents().len()),
            reserved: [0; 7],
        })?;
        Ok(())
    }
}
