//! The coordinator's state between wake-ups, restored from the log on a restart: the last
//! decided round, the [`OpenRound`] being collected, the [`Roster`] of who is live, the
//! [`EndWatch`] of when the run is over, and the [`DecisionLog`] its decisions become final
//! in. A replica's Raft-specific parts live in [`crate::replication`]; here they are only
//! applied: the records other leaders committed are replayed like a restarted coordinator's
//! log, and what it heard while following is reconciled when it comes to lead.
//!
//! | module | concept |
//! |---|---|
//! | `supervisor` | the supervisor's events: liveness logged, a roster entry reconciled with the log, a following replica's memory of them |
//! | `end_watch` | [`EndWatch`]: why and when the run ends; unreachable goals confirmed by the walls |
//! | `open_round` | [`OpenRound`]: the open round's candidates, its deadline, its record |
//! | `roster` | [`Roster`]: per agent live, down or lost, and its restarts |
//! | `dropped` | [`Dropped`]: the counts of dropped candidates, kept across restarts |
//! | `world` | [`World`]: the agents' sightings waiting for their round, the restarted agents waiting for the map |
//! | `latency` | [`Latency`]: the rounds' candidate-to-commit latencies, kept across restarts |

mod dropped;
mod end_watch;
mod latency;
mod open_round;
mod roster;
mod supervisor;
mod world;

use std::path::Path;

use hnav_runtime::consensus_log::{
    AgentEntry, AppliedState, EndReason, EndRecord, LogWriter, Record, RoundRecord, RunHeader,
    UnreachableRecord, FORMAT_VERSION,
};
use hnav_runtime::msg::{CandidateFlags, Lifecycle, LifecycleEvent, Progress, Role};
use hnav_runtime::rejected::Rejected;
use hnav_runtime::scenario::{ClockMode, Scenario};
use hnav_runtime::transport::{Transport, Waiter, Wake};

use super::decision_log::DecisionLog;
use super::error::CoordinatorError;
use super::outcome::CoordinatorOutcome;
use super::ports::Ports;
use crate::replication::{Overheard, RaftLog};
use crate::round::Arbiter;
use dropped::Dropped;
use end_watch::EndWatch;
use latency::Latency;
use open_round::OpenRound;
use roster::Roster;
use world::World;

/// Everything the coordinator knows of the run.
pub(super) struct State {
    arbiter: Arbiter,
    log: DecisionLog,
    /// The last decided round, 0 before the first.
    round: u64,
    /// Its record, for the agents that missed its commit.
    last_record: Option<RoundRecord>,
    open: OpenRound,
    roster: Roster,
    watch: EndWatch,
    dropped: Dropped,
    latency: Latency,
    /// The supervisor's events of one drain, kept so that draining allocates nothing once warm.
    events: Vec<Lifecycle>,
    /// A following replica's memory of the supervisor.
    heard: Overheard,
    /// A restarted single coordinator before its own `Restarted`: the agents' events heard
    /// until then are not logged, since the roster that follows it says what they were.
    roster_due: bool,
    /// The shared picture's traffic (`[sensing]`).
    world: World,
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
        let mut state = State::new(scenario, run_dir, DecisionLog::Single(log));
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

    /// Replica `id`'s state: its journal in `run_dir/log/<id>` opened (or created), and the
    /// records it holds committed applied.
    pub(super) fn open_replica(
        transport: &Transport,
        scenario: &Scenario,
        run_dir: &Path,
        id: u64,
    ) -> Result<Self, CoordinatorError> {
        let raft = RaftLog::open(transport, scenario, run_dir, id, header(scenario))?;
        let log = DecisionLog::Replicated(Box::new(raft));
        let mut state = State::new(scenario, run_dir, log);
        state.apply_committed();
        state.say_resumed();
        Ok(state)
    }

    /// A state with nothing decided yet, whose decisions go to `log`.
    fn new(scenario: &Scenario, run_dir: &Path, log: DecisionLog) -> Self {
        let n = scenario.agents.len();
        State {
            arbiter: Arbiter::new(scenario),
            log,
            round: 0,
            last_record: None,
            open: OpenRound::new(scenario),
            roster: Roster::new(n),
            watch: EndWatch::new(scenario),
            dropped: Dropped::load(run_dir),
            latency: Latency::load(run_dir),
            events: Vec::new(),
            heard: Overheard::new(n),
            roster_due: false,
            world: World::default(),
        }
    }

    /// Says where a restarted coordinator resumes.
    fn say_resumed(&self) {
        if self.round > 0 {
            tracing::info!(
                round = self.round,
                agents_down = self.roster.down(),
                "resumed from the consensus log"
            );
        }
    }

    /// Where its decisions become final.
    pub(super) fn log(&self) -> &DecisionLog {
        &self.log
    }

    /// What the run came to so far.
    pub(super) fn outcome(&self) -> CoordinatorOutcome {
        CoordinatorOutcome {
            round: self.round,
            all_at_goal: self.ended()
                && self.roster.at_goal(&self.arbiter) as usize == self.arbiter.agents(),
            dropped: self.dropped.total(),
        }
    }

    /// Whether the log already holds the end of the run.
    pub(super) fn ended(&self) -> bool {
        self.watch.reason().is_some()
    }

    /// Folds one record of an existing log (or one another leader committed) into the state.
    fn replay(&mut self, r: &Record) {
        match r {
            Record::Round(rec) => {
                self.round = self.round.max(rec.round);
                self.arbiter.replay(rec);
                self.last_record = Some(rec.clone());
            }
            Record::End(e) => self.watch.ended(e.reason),
            Record::Lifecycle(l) => {
                match (Role::from_u8(l.role), LifecycleEvent::from_u8(l.event)) {
                    (Some(Role::Agent), Some(ev)) => self.roster.event(l.index, ev, l.restarts),
                    (Some(role), Some(ev)) => self.heard.logged(role, l.index, ev, l.restarts),
                    _ => {}
                }
            }
            Record::Unreachable(u) => self.watch.logged_unreachable(u.agent),
            Record::Task(t) => self.arbiter.replay_task(t),
            Record::MapChange(m) => self.arbiter.apply_map_change(m),
            Record::Header(_)
            | Record::Replan(_)
            | Record::Raft(_)
            | Record::RaftState(_)
            | Record::Snapshot(_) => {}
        }
    }

    /// Starts from a snapshot's state, as if its records had been replayed (a replica over a
    /// compacted journal, or one its leader sent a snapshot).
    fn restore(&mut self, s: &AppliedState) {
        self.round = self.round.max(s.round);
        self.arbiter.restore_tally(s.tally.clone());
        self.last_record.clone_from(&s.last_round);
        self.roster.restore(&s.agents);
        if let Some(e) = s.end {
            self.watch.ended(e.reason);
        }
        for u in &s.unreachable {
            self.watch.logged_unreachable(u.agent);
        }
        // The other processes' events and the tasks are kept as records: replayed as such.
        for l in &s.processes {
            self.replay(&Record::Lifecycle(*l));
        }
        for t in &s.tasks {
            self.replay(&Record::Task(*t));
        }
        for m in &s.map_changes {
            self.replay(&Record::MapChange(m.clone()));
        }
    }

    /// Logs, once per agent and before the round's record, a goal its agent reports
    /// unreachable (`NO_PATH`) when the walls confirm it ([`EndWatch::confirm_unreachable`]).
    fn confirm_unreachable(&mut self, round: u64) -> Result<(), CoordinatorError> {
        for (i, c) in self.open.candidates().iter().enumerate() {
            let Some(c) = c.filter(|c| c.flags & CandidateFlags::NO_PATH != 0) else {
                continue;
            };
            if self.watch.confirm_unreachable(i, c.current) {
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

    /// Takes every candidate in; keeps those for the open round, re-sends the last commit to
    /// agents asking for a round already decided, drops (and counts) the rest.
    pub(super) fn collect(&mut self, p: &Ports) -> Result<(), CoordinatorError> {
        let mut resend = false;
        p.candidates.drain_pending(|&c| {
            if c.flags & CandidateFlags::RESTARTED != 0 {
                self.world.asked_by(c.agent as usize, self.arbiter.agents());
            }
            if let Err(class) = self.arbiter.classify(&c, self.round) {
                // An agent behind (a restarted one, or one the dead coordinator never
                // answered): the last commit brings it up to date.
                resend |= class == Rejected::PastRound && self.round > 0;
                self.dropped.note(class, &c);
                return;
            }
            if !self.ended() {
                self.open.take(c);
                self.roster.heard_from(c.agent as usize);
            }
        })?;
        if resend {
            self.resend_last_commit(p)?;
        }
        // After the candidates: each agent's sightings go out before its candidate.
        self.world.collect(p, self.arbiter.agents())?;
        self.world.answer(p, &self.arbiter, self.round)?;
        Ok(())
    }

    /// Logs the totals of dropped candidates (if any) and keeps them, with the rounds'
    /// latencies, for the run summary and for a coordinator restarted after this one.
    pub(super) fn report_rejections(&self) {
        self.dropped.report();
        self.latency.report();
    }

    /// Publishes the last logged round's commit again, if there is one.
    pub(super) fn resend_last_commit(&self, p: &Ports) -> Result<(), CoordinatorError> {
        if let Some(rec) = &self.last_record {
            publish_commit(p, rec, self.log.term())?;
        }
        Ok(())
    }

    /// Whether the open round has every live agent's candidate.
    pub(super) fn ready(&self) -> bool {
        !self.ended() && self.open.complete(&self.roster)
    }

    /// When the open round closes without the missing candidates ([`OpenRound::deadline`]).
    pub(super) fn round_deadline(&self) -> Option<std::time::Instant> {
        self.open.deadline()
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
        // What the agents saw, one agent at a time: the second to see a door close finds it
        // closed already.
        for (agent, seen) in self.world.take_due(round) {
            if let Some(m) = self.arbiter.map_change(round, agent, seen) {
                self.log.append(&Record::MapChange(m.clone()))?;
                self.arbiter.apply_map_change(&m);
            }
        }
        self.confirm_unreachable(round)?;
        let (decisions, replans) = self
            .arbiter
            .decide_with(round, self.open.candidates(), tick);
        for r in replans {
            self.log.append(&Record::Replan(r.clone()))?;
        }
        let rec = self.open.record(round, decisions, self.last_record.take());
        // A lifelong run's new tasks, like replans, just before the round that tells them.
        for t in self.arbiter.assigned() {
            self.log.append(&Record::Task(*t))?;
        }
        let record = Record::Round(rec);
        self.log.append(&record)?;
        let Record::Round(rec) = record else {
            unreachable!("built as a round record above")
        };
        // A replica's round is final once a majority holds it; only then may it leave.
        if self.settle(waiter, tick)? {
            publish_commit(p, &rec, self.log.term())?;
            self.latency.note(self.open.came());
        }
        self.last_record = Some(rec);
        self.round = round;
        self.open.clear();
        self.end_if_over()?;
        // The end of the run, if this round ended it, is final before the progress says so.
        if self.settle(waiter, tick)? {
            self.publish_progress(p)?;
        }
        Ok(())
    }

    /// Ends the run once it is over ([`EndWatch::due`]).
    pub(super) fn end_if_over(&mut self) -> Result<(), CoordinatorError> {
        match self.watch.due(self.round, &self.arbiter, &self.roster) {
            Some(reason) => self.end(reason),
            None => Ok(()),
        }
    }

    /// Logs the end of the run (durably) and decides nothing more.
    pub(super) fn end(&mut self, reason: EndReason) -> Result<(), CoordinatorError> {
        self.log.append(&Record::End(EndRecord {
            round: self.round,
            at_goal: self.roster.at_goal(&self.arbiter),
            reason,
        }))?;
        self.log.sync()?;
        self.watch.ended(reason);
        Ok(())
    }

    /// Flushes the log to disk at the process's end.
    pub(super) fn sync(&mut self) -> Result<(), CoordinatorError> {
        if let Some(raft) = self.log.raft() {
            raft.report();
        }
        self.log.sync()
    }

    /// Tells the run's observers how far the run is: the supervisor (`hnav run` ends the run
    /// on `done` and learns the leader of replicas from it), `hnav top`, and the bridge, which
    /// carries it to the other hosts.
    pub(super) fn publish_progress(&self, p: &Ports) -> Result<(), CoordinatorError> {
        let t = self.arbiter.tally();
        p.progress.send(Progress {
            round: self.round,
            agents: self.arbiter.agents() as u32,
            at_goal: self.roster.at_goal(&self.arbiter),
            conflicts: t.conflicts(),
            replans: t.replans(),
            leader: self.log.replica_id() as u8,
            done: self.watch.done(),
            reserved: [0; 6],
        })?;
        Ok(())
    }

    /// One pass of a replica (messages, tick) and the other leaders' committed records
    /// applied. A leader that was deposed after it decided stops here: its state may hold
    /// decisions the cluster never took, and its restart rebuilds it from the journal.
    pub(super) fn pump(&mut self) -> Result<(), CoordinatorError> {
        let Some(raft) = self.log.raft() else {
            return Ok(());
        };
        raft.pump()?;
        if let Some(term) = raft.deposed() {
            return Err(CoordinatorError::Deposed {
                term,
                now: raft.term(),
            });
        }
        self.apply_committed();
        Ok(())
    }

    /// Applies the records other leaders committed, as a restarted coordinator replays its
    /// log.
    fn apply_committed(&mut self) {
        let Some(raft) = self.log.raft() else { return };
        if let Some(state) = raft.take_installed() {
            self.restore(&state);
        }
        let Some(raft) = self.log.raft() else { return };
        let records = raft.take_applied();
        for r in &records {
            self.replay(r);
        }
        if let Some(raft) = self.log.raft() {
            raft.recycle(records);
        }
    }

    /// Whether this replica may decide now (a single coordinator always may): it leads, and
    /// every record of earlier leaders is applied. The first time, the supervisor's events
    /// it heard while following are reconciled with the log (what no leader logged is
    /// logged now).
    pub(super) fn take_lead(&mut self) -> Result<bool, CoordinatorError> {
        let Some(raft) = self.log.raft() else {
            return Ok(true);
        };
        let first = !raft.leading();
        if !raft.take_lead() {
            return Ok(false);
        }
        if first {
            self.log_overheard()?;
        }
        Ok(true)
    }

    /// Waits until the records proposed so far are committed (at once for a single
    /// coordinator, whose appends are final). `false` when the process is told to stop first.
    fn settle(
        &mut self,
        waiter: &Waiter,
        tick: &mut dyn FnMut(),
    ) -> Result<bool, CoordinatorError> {
        loop {
            self.pump()?;
            let ended = self.ended();
            let Some(raft) = self.log.raft() else {
                return Ok(true);
            };
            if raft.settled() {
                if ended {
                    // The followers are stopped soon after the end: they learn now that it
                    // is committed, not at the next heartbeat.
                    raft.ping()?;
                }
                return Ok(true);
            }
            tick();
            if waiter.wait(Some(raft.deadline()))? == Wake::Stop {
                return Ok(false);
            }
        }
    }
}

/// Publishes `rec`'s commit in term `term`.
fn publish_commit(p: &Ports, rec: &RoundRecord, term: u32) -> Result<(), CoordinatorError> {
    let n = rec.decisions.len();
    p.commit
        .send_from_fn(rec.commit_header(term), n, |i| rec.decision(i))?;
    Ok(())
}
