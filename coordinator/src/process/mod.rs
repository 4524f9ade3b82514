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
//! records are replayed: the last round number, the tallies and whether the run ended. The
//! agents still waiting for the last logged round get its commit again, rebuilt from the log
//! (never decided twice); a round in flight when the old coordinator died is decided anew from
//! the candidates the agents resend.
//!
//! Once every agent stands on its goal, or in lockstep once the round of the time limit
//! (`time_limit_s` of simulated time, [`SimParams::rounds_in`]) is committed, the coordinator
//! logs the end of the run, says so on the progress topic ([`Progress::done`]) and decides
//! nothing more, so the log of a lockstep run ends at the same record whatever the
//! supervisor's timing. In realtime the supervisor's wall clock ends the run.
//!
//! [`SimParams::rounds_in`]: hnav_runtime::scenario::params::SimParams::rounds_in
//! [`Progress::done`]: hnav_runtime::msg::Progress::done

use std::path::Path;
use std::time::Duration;

use hnav_runtime::consensus_log::{EndReason, LogError};
use hnav_runtime::health::Heartbeat;
use hnav_runtime::launch::StartOutcome;
use hnav_runtime::msg::{Role, MAX_AGENTS};
use hnav_runtime::scenario::Scenario;
use hnav_runtime::transport::{Transport, TransportError, Waiter, Wake};

mod ports;
mod state;

use ports::Ports;
use state::State;

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
}

/// How the coordinator's run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CoordinatorOutcome {
    /// Last committed round.
    pub round: u64,
    /// Whether every agent reached its goal.
    pub all_at_goal: bool,
    /// Candidates dropped as malformed or hostile (every class of
    /// [`Rejected`](hnav_runtime::rejected::Rejected) together).
    pub dropped: u64,
}

/// The coordinator process.
pub struct CoordinatorProcess<'t> {
    transport: &'t Transport,
    ports: Ports,
    state: State,
    heart: Heartbeat,
    startup_timeout: Duration,
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
        let ports = Ports::open(transport, n)?;
        let heart = Heartbeat::open(transport, Role::Coordinator, 0, n, scenario.heartbeat())?;
        let state = State::open(scenario, run_dir)?;
        Ok(CoordinatorProcess {
            heart,
            startup_timeout: scenario.startup_timeout(),
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
            .handshake(self.transport, resume, self.startup_timeout)?;
        let (p, st) = (&self.ports, &mut self.state);
        if started == StartOutcome::Stopped {
            if !st.ended() {
                st.end(EndReason::Stopped)?;
            }
            st.report_rejections();
            return Ok(st.outcome());
        }
        // A coordinator that died between its last round and the run's end ends it now.
        st.end_if_over()?;
        // Agents that missed the dead coordinator's last commit get it again.
        st.resend_last_commit(p)?;
        st.publish_progress(p)?;
        let waiter = self.transport.waiter()?;
        let _candidates = waiter.attach(&p.candidates)?;
        let _lifecycle = waiter.attach(p.life.events())?;
        let reason = rounds(p, st, &waiter, &self.heart)?;
        if !st.ended() {
            st.end(reason)?;
        }
        st.sync()?;
        st.report_rejections();
        Ok(st.outcome())
    }
}

/// Decides rounds until the supervisor's `Stop` or a termination signal; returns why the run
/// ends.
fn rounds(
    p: &Ports,
    st: &mut State,
    waiter: &Waiter,
    heart: &Heartbeat,
) -> Result<EndReason, CoordinatorError> {
    // A failed beat inside a long decision shows again at the loop's own beat.
    let mut tick = || {
        let _ = heart.beat();
    };
    loop {
        // Every pass beats if due: a backlog of rounds closes back to back without a wait.
        heart.beat()?;
        // Candidates first, then the supervisor: an event sent before a candidate (an agent's
        // `Restarted` before the round the sim resumed for) is then always heard before that
        // round closes, so it is logged at the same round in every lockstep run.
        st.collect(p)?;
        if let Some(reason) = st.hear_supervisor(p)? {
            return Ok(reason);
        }
        if st.ready() {
            st.close_round(p, &mut tick)?;
            continue;
        }
        // Lockstep has no round deadline: only candidates and liveness close a round, and
        // the waiter's own re-check covers a lost wake-up. The heartbeat's deadline only
        // bounds the wait; the round deadline is checked on the clock.
        let deadline = st.round_deadline();
        if deadline.is_some_and(|d| std::time::Instant::now() >= d) {
            st.close_round(p, &mut tick)?;
            continue;
        }
        match waiter.wait(heart.until(deadline)?)? {
            // A passed deadline closes the round on the next pass, after one more drain.
            Wake::Data | Wake::TimedOut => {}
            Wake::Stop => return Ok(EndReason::Stopped),
        }
    }
}
