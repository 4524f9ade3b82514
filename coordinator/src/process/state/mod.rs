//! The coordinator's state between wake-ups: the open round's candidates, who is live, the
//! last decided round and where its decisions become final ([`Decisions`]: its consensus log,
//! or the Raft cluster of its replicas, `replica`).

mod replica;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use hnav_runtime::consensus_log::{
    candidates_digest, AgentEntry, EndReason, EndRecord, LifecycleRecord, LogWriter,
    LoggedDecision, Record, RoundRecord, RunHeader, UnreachableRecord, FORMAT_VERSION,
};
use hnav_runtime::grid::{reachable_from, Cell, CornerCutting, Grid};
use hnav_runtime::launch::LifecyclePorts;
use hnav_runtime::msg::{
    Candidate, CandidateFlags, Lifecycle, LifecycleEvent, Progress, Role, RosterState, StopReason,
};
use hnav_runtime::rejected::{Rejected, Rejections};
use hnav_runtime::scenario::{ClockMode, Scenario};
use hnav_runtime::transport::Waiter;

use super::decisions::Decisions;
use super::ports::Ports;
use super::{CoordinatorError, CoordinatorOutcome};
use crate::round::Arbiter;

/// Everything the coordinator knows of the run, restored from the log on a restart.
pub(super) struct State {
    arbiter: Arbiter,
    log: Decisions,
    clock: ClockMode,
    deadline: Duration,
    round: u64,
    last_record: Option<RoundRecord>,
    pending: Vec<Option<Candidate>>,
    present: Vec<Candidate>,
    live: Vec<bool>,
    opened: Option<Instant>,
    /// In lockstep, the round after which the time limit ends the run.
    round_limit: Option<u64>,
    /// Why the run ended, once the log holds its end.
    end: Option<EndReason>,
    /// Candidates dropped, per class; kept in `DIR/rejected.json` across restarts.
    rejected: Rejections,
    run_dir: PathBuf,
    /// Per agent: its restarts so far, as the supervisor counts them.
    restarts: Vec<u32>,
    /// Per agent: gone for good (`Lost`); its robot stands for the rest of the run and its
    /// goal counts as not reached.
    lost: Vec<bool>,
    /// The supervisor's events of one drain, kept so that draining allocates nothing once warm.
    events: Vec<Lifecycle>,
    /// The map's walls, for confirming an agent's report of an unreachable goal.
    walls: Grid,
    corners: CornerCutting,
    goals: Vec<Cell>,
    /// Per agent: `None` until it first reports its goal unreachable, then whether the walls
    /// confirm it. An agent stays in its connected part of the map, so one check is enough.
    unreachable: Vec<Option<bool>>,
    /// A following replica: per agent, the last liveness the supervisor told (roster state
    /// and restarts), reconciled with the log when the replica comes to lead.
    heard: Vec<Option<(RosterState, u32)>>,
}

/// The header a log of `s` must start with.
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

impl State {
    /// Opens the log in `run_dir/log` (cutting off a torn tail), writes its header if it is
    /// new, and replays the records it already holds.
    pub(super) fn open(scenario: &Scenario, run_dir: &Path) -> Result<Self, CoordinatorError> {
        let dir = run_dir.join("log");
        let (log, recovered) = LogWriter::open(&dir, scenario.coordinator.fsync)?;
        if recovered.truncated_bytes > 0 {
            tracing::warn!(
                bytes = recovered.truncated_bytes,
                "cut a torn tail off the consensus log"
            );
        }
        let mut state = State::new(scenario, run_dir, Decisions::Log(log));
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
        state.say_resumed();
        Ok(state)
    }

    /// A state with nothing decided yet, whose decisions go to `log`.
    fn new(scenario: &Scenario, run_dir: &Path, log: Decisions) -> Self {
        let n = scenario.agents.len();
        State {
            arbiter: Arbiter::new(scenario),
            clock: scenario.sim.clock,
            deadline: Duration::from_millis(u64::from(scenario.coordinator.round_deadline_ms)),
            round: 0,
            last_record: None,
            pending: vec![None; n],
            present: Vec::with_capacity(n),
            live: vec![true; n],
            opened: None,
            round_limit: (scenario.sim.clock == ClockMode::Lockstep)
                .then(|| scenario.sim.rounds_in(scenario.coordinator.time_limit_s)),
            end: None,
            rejected: load_rejections(run_dir),
            run_dir: run_dir.to_path_buf(),
            restarts: vec![0; n],
            lost: vec![false; n],
            events: Vec::new(),
            walls: scenario.map.grid.clone(),
            corners: scenario.map.corner_cutting,
            goals: scenario.agents.iter().map(|a| a.goal).collect(),
            unreachable: vec![None; n],
            heard: vec![None; n],
            log,
        }
    }

    /// Says where a restarted coordinator resumes.
    fn say_resumed(&self) {
        if self.round > 0 {
            let down = self.live.iter().filter(|l| !**l).count();
            tracing::info!(
                round = self.round,
                agents_down = down,
                "resumed from the consensus log"
            );
        }
    }

    /// What the run came to so far.
    pub(super) fn outcome(&self) -> CoordinatorOutcome {
        CoordinatorOutcome {
            round: self.round,
            all_at_goal: self.ended() && self.at_goal() as usize == self.arbiter.agents(),
            dropped: self.rejected.total(),
        }
    }

    /// Whether the log already holds the end of the run.
    pub(super) fn ended(&self) -> bool {
        self.end.is_some()
    }

    /// Folds one record of an existing log into the state.
    fn replay(&mut self, r: &Record) {
        match r {
            Record::Round(rec) => {
                self.round = self.round.max(rec.round);
                self.arbiter.replay(rec);
                self.last_record = Some(rec.clone());
            }
            Record::End(e) => self.end = Some(e.reason),
            Record::Lifecycle(l) => {
                if let (Some(Role::Agent), Some(ev)) =
                    (Role::from_u8(l.role), LifecycleEvent::from_u8(l.event))
                {
                    self.agent_event(l.index, ev, l.restarts);
                }
            }
            Record::Unreachable(u) => {
                if let Some(r) = self.unreachable.get_mut(u.agent as usize) {
                    *r = Some(true);
                }
            }
            Record::Header(_) | Record::Replan(_) | Record::Raft(_) | Record::RaftState(_) => {}
        }
    }

    /// What an agent's lifecycle event (heard or replayed) says of who is live: a `Down`
    /// agent is not waited for until it is back, a `Lost` one never again.
    fn agent_event(&mut self, index: u32, ev: LifecycleEvent, restarts: u32) {
        let i = index as usize;
        let (Some(live), Some(lost), Some(r)) = (
            self.live.get_mut(i),
            self.lost.get_mut(i),
            self.restarts.get_mut(i),
        ) else {
            return;
        };
        *r = (*r).max(restarts);
        match ev {
            LifecycleEvent::Down => *live = false,
            LifecycleEvent::Restarted => *live = !*lost,
            LifecycleEvent::Lost => (*live, *lost) = (false, true),
            _ => {}
        }
    }

    /// Agents at their goal, lost ones not counted (what the end record says).
    fn at_goal(&self) -> u32 {
        (0..self.arbiter.agents())
            .filter(|&i| self.arbiter.agent_at_goal(i) && !self.lost[i])
            .count() as u32
    }

    /// Whether every agent is at its goal, confirmed unable to reach it, or lost.
    fn settled(&self) -> bool {
        (0..self.arbiter.agents()).all(|i| {
            self.arbiter.agent_at_goal(i) || self.unreachable[i] == Some(true) || self.lost[i]
        })
    }

    /// Logs, once per agent and before the round's record, a goal its agent reports
    /// unreachable (`NO_PATH`) when the walls confirm it. A report the walls do not confirm
    /// (the agent's map counts robots it was blocked by as obstacles, and robots move on) is
    /// not logged: the agent stands still as it asked and is asked again later.
    fn confirm_unreachable(&mut self, round: u64) -> Result<(), CoordinatorError> {
        for (i, c) in self.pending.iter().enumerate() {
            let Some(c) = c.filter(|c| c.flags & CandidateFlags::NO_PATH != 0) else {
                continue;
            };
            if self.unreachable[i].is_some() || self.walls.cell_at(c.current as usize).is_none() {
                continue;
            }
            let reach = reachable_from(&self.walls, self.goals[i], self.corners);
            let unreachable = !reach[c.current as usize];
            self.unreachable[i] = Some(unreachable);
            if unreachable {
                tracing::warn!(agent = i, "goal unreachable; the agent stands still");
                self.log.append(&Record::Unreachable(UnreachableRecord {
                    round,
                    agent: i as u32,
                    cell: c.current,
                }))?;
            }
        }
        Ok(())
    }

    /// Takes in every pending supervisor event; returns how the run ends if one was `Stop`.
    pub(super) fn hear_supervisor(
        &mut self,
        p: &Ports,
        life: &LifecyclePorts,
    ) -> Result<Option<EndReason>, CoordinatorError> {
        // Taken out so that applying the events may borrow the state; an error ends the
        // process, so losing the buffer then costs nothing.
        let mut events = std::mem::take(&mut self.events);
        events.clear();
        let stop = life.drain_samples(|_, _, l| events.push(*l))?;
        let ended = self.ended();
        for l in &events {
            self.on_lifecycle(l)?;
        }
        self.events = events;
        // A robot lost while every other one is settled ends the run here, between rounds.
        self.end_if_over()?;
        if self.ended() && !ended {
            self.publish_progress(p)?;
        }
        Ok(stop.map(|reason| match reason {
            StopReason::TimeLimit => EndReason::TimeLimit,
            StopReason::Requested => EndReason::Stopped,
        }))
    }

    /// A supervisor event: liveness of agents, logged for the record with the restart count
    /// the supervisor gives; a roster entry is reconciled with what the log holds.
    fn on_lifecycle(&mut self, l: &Lifecycle) -> Result<(), CoordinatorError> {
        let (Some(role), Some(ev)) = (Role::from_u8(l.role), LifecycleEvent::from_u8(l.event))
        else {
            return Ok(());
        };
        match ev {
            LifecycleEvent::Down | LifecycleEvent::Restarted | LifecycleEvent::Lost => {
                if role == Role::Agent {
                    self.agent_event(l.index, ev, l.restarts);
                }
                self.log_event(role, l.index, ev, l.restarts)
            }
            LifecycleEvent::Roster if role == Role::Agent => match RosterState::from_u8(l.reason) {
                Some(state) => self.reconcile(l.index, state, l.restarts),
                None => Ok(()),
            },
            _ => Ok(()),
        }
    }

    /// A roster entry (sent after this coordinator came up): the records the log misses
    /// because the agent died, came back or was given up while no coordinator listened are
    /// logged now, at the current round, and the agent is waited for or not accordingly.
    fn reconcile(
        &mut self,
        index: u32,
        state: RosterState,
        restarts: u32,
    ) -> Result<(), CoordinatorError> {
        let i = index as usize;
        let (Some(&live), Some(&lost), Some(&logged)) =
            (self.live.get(i), self.lost.get(i), self.restarts.get(i))
        else {
            return Ok(());
        };
        let mut missed: [Option<(LifecycleEvent, u32)>; 2] = [None, None];
        match state {
            // Up with restarts the log has not seen: it died and came back meanwhile.
            RosterState::Up if !lost && (!live || logged < restarts) => {
                if live {
                    missed[0] = Some((LifecycleEvent::Down, restarts.saturating_sub(1)));
                }
                missed[1] = Some((LifecycleEvent::Restarted, restarts));
            }
            RosterState::Down if live => missed[0] = Some((LifecycleEvent::Down, restarts)),
            RosterState::Lost if !lost => {
                if live {
                    missed[0] = Some((LifecycleEvent::Down, restarts));
                }
                missed[1] = Some((LifecycleEvent::Lost, restarts));
            }
            _ => {}
        }
        for (ev, count) in missed.into_iter().flatten() {
            self.agent_event(index, ev, count);
            self.log_event(Role::Agent, index, ev, count)?;
        }
        Ok(())
    }

    /// Logs a lifecycle event at the current round, unless the run has ended.
    fn log_event(
        &mut self,
        role: Role,
        index: u32,
        ev: LifecycleEvent,
        restarts: u32,
    ) -> Result<(), CoordinatorError> {
        if self.ended() {
            return Ok(());
        }
        let event = match ev {
            LifecycleEvent::Restarted => Lifecycle::restarted(role, index, restarts),
            LifecycleEvent::Lost => Lifecycle::lost(role, index, restarts),
            _ => Lifecycle::down(role, index, restarts),
        };
        self.log
            .append(&Record::Lifecycle(LifecycleRecord::new(self.round, &event)))?;
        Ok(())
    }

    /// Takes every candidate in; keeps those for the open round, re-sends the last commit to
    /// agents asking for a round already decided, drops (and counts) the rest.
    pub(super) fn collect(&mut self, p: &Ports) -> Result<(), CoordinatorError> {
        let mut resend = false;
        p.candidates.drain_pending(|&c| {
            if let Err(class) = self.arbiter.classify(&c, self.round) {
                // An agent behind (a restarted one, or one the dead coordinator never
                // answered): the last commit brings it up to date.
                resend |= class == Rejected::PastRound && self.round > 0;
                self.reject(class, &c);
                return;
            }
            if !self.ended() {
                let i = c.agent as usize;
                if self.pending.iter().all(Option::is_none) {
                    self.opened = Some(Instant::now());
                }
                self.pending[i] = Some(c);
                // A candidate shows an agent live, unless the supervisor gave it up (a
                // sample it sent before it died).
                self.live[i] = !self.lost[i];
            }
        })?;
        if resend {
            self.resend_last_commit(p)?;
        }
        Ok(())
    }

    /// Counts a dropped candidate; only the first of its class is logged, so that a flood
    /// costs no log line and no allocation per message.
    fn reject(&mut self, class: Rejected, c: &Candidate) {
        if self.rejected.note(class) {
            tracing::warn!(
                class = class.name(),
                agent = c.agent,
                round = c.round,
                "candidate dropped; further ones of this class are only counted"
            );
        }
    }

    /// Logs the totals of dropped candidates (if any) and keeps them in `DIR/rejected.json`
    /// for the run summary and for a coordinator restarted after this one.
    pub(super) fn report_rejections(&self) {
        if self.rejected.total() > 0 {
            tracing::warn!(counts = %self.rejected, "candidates dropped in this run");
        }
        if let Err(e) = self.rejected.store(&self.run_dir) {
            tracing::warn!(
                "cannot write {}: {e}",
                self.run_dir.join(hnav_runtime::rejected::FILE).display()
            );
        }
    }

    /// Publishes the last logged round's commit again, if there is one.
    pub(super) fn resend_last_commit(&self, p: &Ports) -> Result<(), CoordinatorError> {
        if let Some(rec) = &self.last_record {
            let term = self.term();
            p.commit.send_in_place(|slot| {
                rec.write_commit(slot);
                slot.term = term;
            })?;
        }
        Ok(())
    }

    /// Whether the open round has every live agent's candidate.
    pub(super) fn ready(&self) -> bool {
        !self.ended()
            && self.pending.iter().any(Option::is_some)
            && self
                .live
                .iter()
                .zip(&self.pending)
                .all(|(&l, c)| !l || c.is_some())
    }

    /// When the open round closes without the missing candidates: in realtime
    /// `round_deadline_ms` after its first candidate; never in lockstep, or with no round open.
    pub(super) fn round_deadline(&self) -> Option<Instant> {
        match (self.clock, self.opened) {
            (ClockMode::Realtime, Some(opened)) => Some(opened + self.deadline),
            _ => None,
        }
    }

    /// Decides the open round, makes it durable, then commits it. `tick` is called often
    /// while the decision takes long (LaCAM's search): the caller beats its heartbeat there.
    pub(super) fn close_round(
        &mut self,
        p: &Ports,
        waiter: &Waiter,
        tick: &mut dyn FnMut(),
    ) -> Result<(), CoordinatorError> {
        let round = self.round + 1;
        self.confirm_unreachable(round)?;
        let (decisions, replans) = self.arbiter.decide_with(round, &self.pending, tick);
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
        // A replica's round is final once a majority holds it; only then may it leave.
        let settled = self.settle(waiter, tick)?;
        let term = self.term();
        if settled {
            p.commit.send_in_place(|slot| {
                rec.write_commit(slot);
                slot.term = term;
            })?;
        }
        self.last_record = Some(rec);
        self.round = round;
        self.pending.iter_mut().for_each(|c| *c = None);
        self.opened = None;
        self.end_if_over()?;
        // The end of the run, if this round ended it, is final before the progress says so.
        if self.settle(waiter, tick)? {
            self.publish_progress(p)?;
        }
        Ok(())
    }

    /// Ends the run once every agent is at its goal or, in lockstep, once the round of its
    /// time limit is committed: the limit is counted here, in rounds of simulated time, so
    /// that a lockstep run ends at the same record whatever the wall clock says.
    pub(super) fn end_if_over(&mut self) -> Result<(), CoordinatorError> {
        if self.ended() || self.round == 0 {
            return Ok(());
        }
        if self.at_goal() as usize == self.arbiter.agents() {
            self.end(EndReason::AllAtGoal)?;
        } else if self.settled() && self.lost.iter().any(|l| *l) {
            self.end(EndReason::AllAtGoalOrLost)?;
        } else if self.settled() {
            self.end(EndReason::AllAtGoalOrUnreachable)?;
        } else if self.round_limit.is_some_and(|limit| self.round >= limit) {
            self.end(EndReason::TimeLimit)?;
        }
        Ok(())
    }

    /// Logs the end of the run (durably) and decides nothing more.
    pub(super) fn end(&mut self, reason: EndReason) -> Result<(), CoordinatorError> {
        self.log.append(&Record::End(EndRecord {
            round: self.round,
            at_goal: self.at_goal(),
            reason,
        }))?;
        self.log.sync()?;
        self.end = Some(reason);
        Ok(())
    }

    /// Flushes the log to disk.
    pub(super) fn sync(&mut self) -> Result<(), CoordinatorError> {
        self.log.sync()?;
        Ok(())
    }

    /// Tells the supervisor and the sim how far the run is.
    pub(super) fn publish_progress(&self, p: &Ports) -> Result<(), CoordinatorError> {
        let t = self.arbiter.tally();
        p.progress.send(Progress {
            round: self.round,
            agents: self.arbiter.agents() as u32,
            at_goal: self.at_goal(),
            conflicts: t.conflicts(),
            replans: t.replans(),
            leader: self.replica_id() as u8,
            done: match self.end {
                // Nothing is left to decide for the unreachable ones either.
                Some(
                    EndReason::AllAtGoal
                    | EndReason::AllAtGoalOrUnreachable
                    | EndReason::AllAtGoalOrLost,
                ) => Progress::ALL_AT_GOAL,
                Some(EndReason::TimeLimit) => Progress::TIME_LIMIT,
                Some(EndReason::Stopped) | None => 0,
            },
            reserved: [0; 6],
        })?;
        Ok(())
    }
}

/// The counts an earlier coordinator of the run left, or none; a file that cannot be read is
/// reported and counting starts again from zero, since the counts never decide anything.
fn load_rejections(run_dir: &Path) -> Rejections {
    Rejections::load(run_dir).unwrap_or_else(|e| {
        tracing::warn!("{e}; counting dropped candidates from zero");
        Rejections::default()
    })
}
