//! The `hnav-coordinator` process: the central compute block of the run.
//!
//! It blocks in one [`Waiter`] on the candidate and lifecycle topics. A round (`last + 1`)
//! closes when every live agent's candidate for it is in; in **realtime** also when
//! `round_deadline_ms` has passed since the round's first candidate (the missing agents count
//! as standing still); in **lockstep** only liveness closes it (an agent the supervisor
//! reports down stops being waited for), so a run's rounds do not depend on timing. Then:
//! [`Arbiter::decide`](crate::round::Arbiter::decide), append the round (and its replans) to
//! the consensus log, and only then publish the [`Commit`](hnav_runtime::msg::Commit) — under
//! the default fsync policy a commit an agent sees is already durable.
//!
//! **Restart.** On start the log in `DIR/log` is opened; a torn tail is cut off, the complete
//! records are replayed: the last round number, the tallies, the cells each robot was
//! committed to (an agent down with the coordinator holds them until it speaks again) and
//! whether the run ended. The agents still waiting for the last logged round get its commit
//! again, rebuilt from the log (never decided twice); a round in flight when the old
//! coordinator died is decided anew from the candidates the agents resend.
//!
//! Once every agent stands on its goal, or in lockstep once the round of the time limit
//! (`time_limit_s` of simulated time, [`SimParams::rounds_in`]) is committed, the coordinator
//! logs the end of the run, says so on the progress topic ([`Progress::done`]) and decides
//! nothing more, so the log of a lockstep run ends at the same record whatever the
//! supervisor's timing. In realtime the supervisor's wall clock ends the run.
//!
//! **Replicas** (`coordinator.replicas` 3 or 5, `--replica ID`). Each replica keeps its Raft
//! log in `DIR/log/<id>/` and talks to the others on `raft/<id>` ([`crate::replication`]).
//! It follows at first: it applies the leader's committed records to its own state and only
//! listens to the supervisor. Once Raft elects it and every earlier leader's record is
//! applied, it opens the candidate, commit and progress ports (agents resend their open
//! candidate to the new commit publisher), republishes the last committed round and decides
//! as a single coordinator does, except that a round's record is proposed and its Commit
//! published only once a majority holds it. A leader that loses its term after deciding
//! exits (`Deposed`): its state may hold a round the cluster never committed, and its
//! restart (the supervisor's) rebuilds it from its journal as a follower.
//!
//! | module | concept |
//! |---|---|
//! | `state` | what the coordinator knows between wake-ups: the open round, the roster, the end watch, the supervisor's events, a replica's committed records applied |
//! | `decision_log` | where its decisions become final: its own consensus log or its replica's Raft log |
//! | `ports` | the topics of the rounds: candidates in, commits and progress out |
//! | `outcome` | [`CoordinatorOutcome`], what a finished run reports |
//! | `error` | [`CoordinatorError`] |
//!
//! [`SimParams::rounds_in`]: hnav_runtime::scenario::params::SimParams::rounds_in
//! [`Progress::done`]: hnav_runtime::msg::Progress::done

use std::path::Path;
use std::time::Duration;

use hnav_runtime::consensus_log::EndReason;
use hnav_runtime::health::Heartbeat;
use hnav_runtime::launch::{LifecyclePorts, StartOutcome};
use hnav_runtime::msg::{Role, MAX_AGENTS};
use hnav_runtime::scenario::Scenario;
use hnav_runtime::transport::{Transport, Waiter, Wake};

mod decision_log;
mod error;
mod outcome;
mod ports;
mod state;

pub use error::CoordinatorError;
pub use outcome::CoordinatorOutcome;
use ports::Ports;
use state::State;

/// The coordinator process.
pub struct CoordinatorProcess<'t> {
    transport: &'t Transport,
    /// The candidate, commit and progress ports: a single coordinator opens them at once, a
    /// replica when it comes to lead.
    ports: Option<Ports>,
    life: LifecyclePorts,
    state: State,
    heart: Heartbeat,
    agents: usize,
    /// The map's cells when the run senses (`[sensing]`): the world's ports are opened.
    world_cells: Option<usize>,
    startup_timeout: Duration,
}

impl<'t> CoordinatorProcess<'t> {
    /// Opens the ports and the log in `run_dir/log` (replica `id`'s in `run_dir/log/<id>`),
    /// replaying what the log holds.
    pub fn new(
        transport: &'t Transport,
        scenario: &Scenario,
        run_dir: &Path,
        replica: Option<u64>,
    ) -> Result<Self, CoordinatorError> {
        let n = scenario.agents.len();
        if n > MAX_AGENTS {
            return Err(CoordinatorError::TooManyAgents(n));
        }
        let index = replica.map_or(0, |id| id as u32);
        let world_cells = scenario.sensing.is_some().then(|| scenario.map.grid.len());
        let (ports, state) = match replica {
            None => (
                Some(Ports::open(transport, n, world_cells)?),
                State::open(scenario, run_dir)?,
            ),
            Some(id) => (None, State::open_replica(transport, scenario, run_dir, id)?),
        };
        let life = LifecyclePorts::open(transport, Role::Coordinator, index, n)?;
        let heart = Heartbeat::open(transport, Role::Coordinator, index, n, scenario.heartbeat())?;
        Ok(CoordinatorProcess {
            heart,
            startup_timeout: scenario.startup_timeout(),
            transport,
            ports,
            life,
            state,
            agents: n,
            world_cells,
        })
    }

    /// Announces itself, waits for the start (unless `resume`) and runs rounds until the
    /// supervisor's `Stop` or a termination signal.
    pub fn run(&mut self, resume: bool) -> Result<CoordinatorOutcome, CoordinatorError> {
        // A replica hears its own `Restarted` while following (see `Overheard`).
        if resume && self.ports.is_some() {
            self.state.await_roster();
        }
        let started = self
            .life
            .handshake(self.transport, resume, self.startup_timeout)?;
        let st = &mut self.state;
        if started == StartOutcome::Stopped {
            if !st.ended() && self.ports.is_some() {
                st.end(EndReason::Stopped)?;
            }
            st.report_rejections();
            return Ok(st.outcome());
        }
        if self.ports.is_none() {
            if let Some(reason) = follow(&self.life, st, self.transport, &self.heart)? {
                st.sync()?;
                tracing::info!(reason = reason.name(), "replica stops while following");
                return Ok(st.outcome());
            }
            self.ports = Some(Ports::open(self.transport, self.agents, self.world_cells)?);
        }
        let p = self.ports.as_ref().expect("opened above");
        // A coordinator that died between its last round and the run's end ends it now.
        st.end_if_over()?;
        // Agents that missed the dead coordinator's last commit get it again.
        st.resend_last_commit(p)?;
        st.publish_progress(p)?;
        let waiter = self.transport.waiter()?;
        let _candidates = waiter.attach(&p.candidates)?;
        let _lifecycle = waiter.attach(self.life.events())?;
        let link = st.log().link();
        let _raft = link
            .as_ref()
            .map(|l| waiter.attach(l.inbox()))
            .transpose()?;
        match rounds(p, &self.life, st, &waiter, &self.heart)? {
            // A replica's own termination signal takes it out of the cluster, not the run
            // out of the world: an end logged now would be replicated, and the replica
            // elected next would find the run over and decide nothing more.
            Stop::Signal if link.is_some() => {
                tracing::info!("replica stops on a signal; the others go on");
            }
            Stop::Signal if !st.ended() => st.end(EndReason::Stopped)?,
            Stop::Run(reason) if !st.ended() => st.end(reason)?,
            Stop::Signal | Stop::Run(_) => {}
        }
        st.sync()?;
        st.report_rejections();
        Ok(st.outcome())
    }
}

/// A replica follows the leader until it comes to lead (`None`) or the run stops (why).
fn follow(
    life: &LifecyclePorts,
    st: &mut State,
    transport: &Transport,
    heart: &Heartbeat,
) -> Result<Option<EndReason>, CoordinatorError> {
    let waiter = transport.waiter()?;
    let _lifecycle = waiter.attach(life.events())?;
    let link = st.log().link();
    let _raft = link
        .as_ref()
        .map(|l| waiter.attach(l.inbox()))
        .transpose()?;
    if let Some((role, term)) = st.log().role() {
        tracing::info!(role, term, "replica up, following");
    }
    loop {
        heart.beat()?;
        st.pump()?;
        if let Some(reason) = st.overhear(life)? {
            return Ok(Some(reason));
        }
        if st.take_lead()? {
            if let Some((_, term)) = st.log().role() {
                tracing::info!(term, "replica leads");
            }
            return Ok(None);
        }
        let until = st.log().deadline();
        if waiter.wait(heart.until(until)?)? == Wake::Stop {
            return Ok(Some(EndReason::Stopped));
        }
    }
}

/// Why [`rounds`] returned.
enum Stop {
    /// The run ends, for the reason the supervisor gave.
    Run(EndReason),
    /// This process got SIGTERM or SIGINT.
    Signal,
}

/// Decides rounds until the supervisor's `Stop` or a termination signal.
fn rounds(
    p: &Ports,
    life: &LifecyclePorts,
    st: &mut State,
    waiter: &Waiter,
    heart: &Heartbeat,
) -> Result<Stop, CoordinatorError> {
    // A failed beat inside a long decision shows again at the loop's own beat.
    let mut tick = || {
        let _ = heart.beat();
    };
    loop {
        // Every pass beats if due: a backlog of rounds closes back to back without a wait.
        heart.beat()?;
        // A replica's Raft messages and ticks; a deposed leader stops here.
        st.pump()?;
        // Candidates first, then the supervisor: an event sent before a candidate (an agent's
        // `Restarted` before the round the sim resumed for) is then always heard before that
        // round closes, so it is logged at the same round in every lockstep run.
        st.collect(p)?;
        if let Some(reason) = st.hear_supervisor(p, life)? {
            return Ok(Stop::Run(reason));
        }
        if st.ready() {
            st.close_round(p, waiter, &mut tick)?;
            continue;
        }
        // Lockstep has no round deadline: only candidates and liveness close a round, and
        // the waiter's own re-check covers a lost wake-up. The heartbeat's deadline only
        // bounds the wait; the round deadline is checked on the clock.
        let deadline = st.round_deadline();
        if deadline.is_some_and(|d| std::time::Instant::now() >= d) {
            st.close_round(p, waiter, &mut tick)?;
            continue;
        }
        let until = match (deadline, st.log().deadline()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        match waiter.wait(heart.until(until)?)? {
            // A passed deadline closes the round on the next pass, after one more drain.
            Wake::Data | Wake::TimedOut => {}
            Wake::Stop => return Ok(Stop::Signal),
        }
    }
}
