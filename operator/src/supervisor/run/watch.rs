//! The watch: from `Start` until the run ends. It blocks in a `Waiter` on the children's exit
//! descriptors and the `ready` topic, with a short tick for the progress bar and the fault
//! schedule, and on each look takes in the coordinator's progress, the `Up`s and holds on
//! `ready`, the fault schedule's due signals and the hang watch's verdicts; when a child
//! exits, it reaps, restarts, and watches the new set of children.
//!
//! The fault schedule, the hang watch and the slots decide; [`Watch::apply`] does what they
//! decided ([`Action`]), right after each of them, so that each sees the effect of the one
//! before (a lockstep hold resumes only after its faults' signals landed).

use std::time::{Duration, Instant};

use super::action::{Action, Landed, Shot, Why};
use super::dying::Dying;
use super::error::RunError;
use super::faults::FaultSchedule;
use super::hang::HangWatch;
use super::progress::ProgressView;
use super::slots::Slots;
use super::sweeper::Sweeper;
use crate::supervisor::child::Signal;
use crate::supervisor::events::{RunEvent, RunEvents};
use crate::supervisor::registry::RunRecord;
use crate::supervisor::startup::SupervisorPorts;
use hnav_runtime::msg::{Lifecycle, LifecycleEvent, Progress, StopReason, Truth, TruthView};
use hnav_runtime::scenario::{ClockMode, Scenario};
use hnav_runtime::topics::{self, TruthReceiver};
use hnav_runtime::transport::{Receiver, RunId, Transport, Wake};

/// Refresh period of the progress bar and the fault schedule.
const TICK: Duration = Duration::from_millis(50);

/// The longest a respawn waits for the dead-node clean-up in flight (it took 300 ms in a
/// debug build on a loaded machine).
const SWEEP_SETTLE: Duration = Duration::from_secs(5);

/// How the watched part of a run ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum End {
    AllAtGoal,
    TimeLimit,
    Signalled,
    /// The sim or the coordinator is gone for good, or no agent is left: why.
    CannotGoOn(String),
}

/// The supervisor's node on the run's transport and its ports (dropped in this order: the
/// ports, then the node).
pub(super) struct Ports {
    /// Removes dead nodes' resources off the watch's thread.
    sweeper: Sweeper,
    pub(super) life: SupervisorPorts,
    pub(super) progress: Receiver<Progress>,
    pub(super) truth: TruthReceiver,
    /// In a run across hosts, the `lifecycle` topic, where another host's supervisor that
    /// saw the run end first says `Stop` (the coordinator's last progress may not cross: a
    /// realtime bridge drops what a busy link cannot take).
    others_stop: Option<Receiver<Lifecycle>>,
    pub(super) transport: Transport,
}

impl Ports {
    /// The supervisor's node in `run` (it handles SIGINT and SIGTERM) and its ports, for a
    /// run of `agents` agents (`across` hosts: one more, for the other hosts' `Stop`).
    pub(super) fn open(run: &RunId, agents: usize, across: bool) -> Result<Self, RunError> {
        let transport = Transport::builder(run)
            .node_name("supervisor")
            .handle_signals(true)
            .create()?;
        let sweeper = Sweeper::start(transport.config().clone()).map_err(RunError::Sweeper)?;
        Ok(Self {
            sweeper,
            life: SupervisorPorts::open(&transport, agents)?,
            progress: transport.receiver(topics::PROGRESS, topics::progress_qos())?,
            truth: transport.slice_receiver(topics::TRUTH, topics::truth_qos())?,
            others_stop: across
                .then(|| transport.receiver(topics::LIFECYCLE, topics::lifecycle_qos(agents)))
                .transpose()?,
            transport,
        })
    }
}

/// The latest of what the run's processes published that the summary needs.
#[derive(Default)]
pub(super) struct Seen {
    pub(super) truth: Option<Truth>,
    pub(super) progress: Option<Progress>,
}

impl Seen {
    /// Keeps `t` as the latest ground truth, in the memory of the one before.
    pub(super) fn hold_truth(&mut self, t: TruthView<'_>) {
        self.truth.get_or_insert_with(Truth::default).set(t);
    }
}

/// What one look at the run found.
enum Look {
    /// The run is over.
    End(End),
    /// A restart is due: reap, restart, and watch the new set of children.
    RestartDue,
    /// Nothing to do before this instant (or an event).
    WaitUntil(Instant),
}

/// The state of the watch between two changes of the set of running processes.
pub(super) struct Watch<'s> {
    ports: &'s Ports,
    /// `DIR/events.jsonl`: exits, respawns, `Up`s, hangs and the faults' signals.
    journal: RunEvents,
    view: ProgressView,
    /// The latest ground truth and progress taken in.
    seen: &'s mut Seen,
    faults: FaultSchedule<'s>,
    hang: HangWatch,
    /// The processes SIGKILLed here, until they are told `Down`.
    dying: Dying,
    /// The last committed round the coordinator reported.
    round: u64,
    t0: Instant,
    /// The wall-clock limit (realtime only).
    limit: Option<Duration>,
}

impl<'s> Watch<'s> {
    /// The watch of a run of `scenario` from now (`Start`), its progress shown on a bar if
    /// `show_progress`.
    pub(super) fn start(
        ports: &'s Ports,
        scenario: &'s Scenario,
        faults: FaultSchedule<'s>,
        journal: RunEvents,
        hang: HangWatch,
        show_progress: bool,
        seen: &'s mut Seen,
    ) -> Self {
        let lockstep = scenario.sim.clock == ClockMode::Lockstep;
        Self {
            ports,
            journal,
            view: ProgressView::new(show_progress, scenario.agents.len()),
            seen,
            faults,
            hang,
            dying: Dying::default(),
            round: 0,
            t0: Instant::now(),
            // In lockstep the coordinator counts the limit in rounds and says when it is
            // reached. A limit too large for a Duration (a valid scenario may say 1e300 s)
            // never ends it.
            limit: (!lockstep).then(|| {
                Duration::try_from_secs_f64(scenario.coordinator.time_limit_s.max(0.0))
                    .unwrap_or(Duration::MAX)
            }),
        }
    }

    /// Watches, reaping and restarting whatever dies, until the run ends; then continues
    /// whatever the plan froze, so that it can stop politely.
    pub(super) fn until_end(
        mut self,
        slots: &mut Slots,
        record: &mut RunRecord,
    ) -> Result<End, RunError> {
        let end = self.watch(slots, record);
        let thaws = self.faults.thaw_all();
        let thawed = self.apply(thaws, slots);
        self.view.finish();
        let end = end?;
        thawed?;
        Ok(end)
    }

    fn watch(&mut self, slots: &mut Slots, record: &mut RunRecord) -> Result<End, RunError> {
        loop {
            if let Some(end) = self.until_change(slots)? {
                return Ok(end);
            }
            // The end first: in a run across hosts, the host that saw the coordinator's last
            // progress before this one did sends `Stop`, and a process here that exits on it
            // has not failed the run (the base host ended "cannot go on" in 1 of 4 runs).
            if let Some(end) = self.on_progress(slots)? {
                return Ok(end);
            }
            let reaped = slots.reap_and_restart();
            self.apply(reaped.todo, slots)?;
            if let Some(why) = reaped.verdict? {
                return Ok(End::CannotGoOn(why));
            }
            slots.write_record(record);
        }
    }

    /// Follows the run until it ends (`Some`) or until a child exits, a restart is due or a
    /// process announces itself (`None`: reap, restart, and watch the new set of children).
    fn until_change(&mut self, slots: &mut Slots) -> Result<Option<End>, RunError> {
        let ports = self.ports;
        let waiter = ports.transport.waiter()?;
        let exits = slots.exit_fds().map_err(RunError::ExitFd)?;
        let mut attached = vec![waiter.attach(ports.life.ready())?];
        for fd in &exits {
            attached.push(waiter.attach_fd(fd)?);
        }
        loop {
            let until = match self.look(slots)? {
                Look::End(end) => return Ok(Some(end)),
                Look::RestartDue => return Ok(None),
                Look::WaitUntil(until) => until,
            };
            self.hang.before_wait(until);
            match waiter.wait(Some(until))? {
                Wake::Stop => return Ok(Some(End::Signalled)),
                // A child's exit, an `Up`, or only a re-check: reap and look again.
                Wake::Data => return Ok(None),
                Wake::TimedOut => {}
            }
        }
    }

    /// One look at the run: progress, `ready`, the fault schedule, the time limit, hangs,
    /// restarts; and until when nothing is due.
    fn look(&mut self, slots: &mut Slots) -> Result<Look, RunError> {
        // Progress first: it names the leader of replicated coordinators, whom a fault at
        // "the coordinator" hits when the sim holds for it below.
        if let Some(end) = self.on_progress(slots)? {
            return Ok(Look::End(end));
        }
        let told = self.dying.check(slots);
        self.apply(told, slots)?;
        self.on_ready(slots)?;
        let due = self.faults.resume_due(slots);
        self.apply(due, slots)?;
        let due = self.faults.thaw_due(Instant::now());
        self.apply(due, slots)?;
        let due = self.faults.fire_due(slots, self.t0.elapsed());
        self.apply(due, slots)?;
        let left = self.limit.map(|l| l.saturating_sub(self.t0.elapsed()));
        if left.is_some_and(|l| l.is_zero()) {
            return Ok(Look::End(End::TimeLimit));
        }
        self.hang.follow(slots);
        let (hung, hung_due) = self.hang.check(self.round)?;
        self.apply(hung, slots)?;
        let now = Instant::now();
        let restart_due = slots.next_restart();
        if restart_due.is_some_and(|d| d <= now) {
            return Ok(Look::RestartDue);
        }
        // The next tick of the progress bar and the fault schedule, sooner if a restart, a
        // hang deadline, a fault in seconds, the end of a freeze or a killed process's next
        // look is due, never past the time limit.
        let mut until = now + left.map_or(TICK, |l| TICK.min(l));
        let timed = [
            restart_due,
            hung_due,
            self.faults.next_deadline(self.t0),
            self.dying.next_look(now),
        ];
        for d in timed.into_iter().flatten() {
            until = until.min(d);
        }
        Ok(Look::WaitUntil(until))
    }

    /// Shows the coordinator's latest progress and, in realtime, fires the faults due by its
    /// round (or by the time since `Start`); `AllAtGoal` or `TimeLimit` once it reports that
    /// it ended the run.
    fn on_progress(&mut self, slots: &mut Slots) -> Result<Option<End>, RunError> {
        let seen = &mut *self.seen;
        (self.ports.truth).drain_pending(|h, p| seen.hold_truth(TruthView::new(h, p)))?;
        let mut last = None;
        self.ports.progress.drain_pending(|p| last = Some(*p))?;
        if let Some(end) = self.other_host_stopped()? {
            return Ok(Some(end));
        }
        let Some(p) = last else {
            return Ok(None);
        };
        self.seen.progress = Some(p);
        self.view.show(&p);
        self.round = p.round;
        self.faults.on_round(p.round);
        self.faults.on_leader(p.leader);
        let due = self.faults.fire_due(slots, self.t0.elapsed());
        self.apply(due, slots)?;
        Ok(match p.done {
            Progress::ALL_AT_GOAL => Some(End::AllAtGoal),
            Progress::TIME_LIMIT => Some(End::TimeLimit),
            _ => None,
        })
    }

    /// In a run across hosts, how the run ended if another host's supervisor said `Stop`:
    /// at the time limit, or (all robots home, or stopped there) over.
    fn other_host_stopped(&mut self) -> Result<Option<End>, RunError> {
        let Some(rx) = &self.ports.others_stop else {
            return Ok(None);
        };
        let mut stop = None;
        let own = [self.ports.life.events_id()];
        rx.drain_pending_except(&own, |l| {
            if l.event == LifecycleEvent::Stop as u8 {
                stop = Some(l.reason);
            }
        })?;
        Ok(stop.map(|reason| match StopReason::from_u8(reason) {
            Some(StopReason::TimeLimit) => End::TimeLimit,
            _ => End::AllAtGoal,
        }))
    }

    /// Takes what came in on `ready`: a restarted process that is up is announced
    /// `Restarted`; a hold of the sim (lockstep) fires the faults of its round.
    fn on_ready(&mut self, slots: &mut Slots) -> Result<(), RunError> {
        let mut ups = Vec::new();
        let mut holds = Vec::new();
        self.ports
            .life
            .ready()
            .drain_pending(|l| match LifecycleEvent::from_u8(l.event) {
                Some(LifecycleEvent::Up) => ups.push((l.role, l.index)),
                Some(LifecycleEvent::Hold) => holds.push(l.period()),
                // A start-up phase report is not yet the process being up.
                _ => {}
            })?;
        let announced = slots.on_up(&ups);
        self.apply(announced, slots)?;
        for period in holds {
            let shots = self.faults.on_hold(slots, period);
            self.apply(shots, slots)?;
        }
        Ok(())
    }

    /// Does what the fault schedule, the hang watch or the slots decided, in order: the one
    /// place where the run's processes are signalled and respawned, its journal written and
    /// its lifecycle topic told.
    fn apply(
        &mut self,
        todo: impl IntoIterator<Item = Action>,
        slots: &mut Slots,
    ) -> Result<(), RunError> {
        for action in todo {
            match action {
                Action::Signal(shot) => {
                    let landed = self.shoot(&shot, slots);
                    if landed != Landed::Missed && shot.signal == Signal::SIGKILL {
                        self.dying.killed(shot.target);
                    }
                    if let Why::Fault(i) = shot.why {
                        self.faults.landed(i, shot.target, landed);
                    }
                }
                Action::Journal(event) => self.journal.record(event),
                Action::Publish(message) => self.ports.life.publish(message)?,
                Action::CleanUpDead => self.ports.sweeper.sweep(),
                Action::Respawn { role, index } => {
                    // A respawned process should find its predecessor's ports gone (it
                    // would clean up itself as it starts, later).
                    if !self.ports.sweeper.settle(SWEEP_SETTLE) {
                        tracing::warn!("dead-node clean-up still running at a respawn");
                    }
                    if let Some(spawned) = slots.respawn(role, index)? {
                        self.journal.record(spawned);
                    }
                }
            }
        }
        Ok(())
    }

    /// Sends `shot` and journals it, if its incarnation still runs.
    fn shoot(&self, shot: &Shot, slots: &Slots) -> Landed {
        let Shot { target, signal, .. } = *shot;
        let node = target.role.node_name(target.index);
        let child = slots
            .child(target.role, target.index)
            .filter(|c| c.pid() == target.pid && c.exit().is_none());
        let Some(c) = child else {
            if let Why::Thaw(_) = shot.why {
                tracing::info!(node, pid = target.pid, "frozen process is gone; no SIGCONT");
            }
            return Landed::Missed;
        };
        if let Err(e) = c.signal(signal) {
            match shot.why {
                Why::Fault(_) => tracing::warn!("fault not injected: {e}"),
                Why::Thaw(_) => tracing::warn!("freeze not ended: {e}"),
                Why::Hung => tracing::warn!(node, "hung process not killed: {e}"),
            }
            return Landed::Missed;
        }
        if let Why::Thaw(_) = shot.why {
            tracing::warn!(node, "fault: continued");
        }
        self.journal.record(RunEvent::Signalled {
            node,
            pid: target.pid,
            signal: signal.to_string(),
            fault: shot.why.fault(),
            round: shot.round,
        });
        if shot.wait_stop && !c.wait_stopped() {
            return Landed::DiedInstead;
        }
        Landed::Sent
    }
}
