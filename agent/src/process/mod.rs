//! The `hnav-agent` process: one robot's agent, wired to the run's services.
//!
//! Inputs: its robot's odometry (`odom/<i>`), the coordinator's commits, the supervisor's
//! lifecycle events. Outputs: candidates, wheel commands (`wheels/<i>`) and neural-map
//! snapshots (`map/<i>`, written in place into loaned shared memory). It blocks in one WaitSet
//! on the three inputs; there is no timer.
//!
//! Every control period (one odometry reading) the agent updates its dead reckoning, notices
//! arrival at `next`, and, unless a candidate of its own is still unanswered, publishes the
//! candidate for round `last commit + 1`. In **lockstep** it sends the wheel command for the
//! following period only once that round's commit is in, so the sim cannot step before the
//! swarm has decided: round r and period r are the same instant and the run is
//! deterministic. In **realtime** it answers every odometry reading with a wheel command at
//! once and applies commits whenever they arrive, as a robot would.
//!
//! A new coordinator (its notifier appearing on the commit topic after a restart) gets the
//! unanswered candidate again: the dead one may have taken it to its grave.

pub mod checkpoint;

use std::path::Path;
use std::time::Duration;

use hnav_runtime::grid::geometry::{cell_centre_m, cell_centre_pose, cell_index};
use hnav_runtime::grid::{Cell, Grid};
use hnav_runtime::launch::{LifecyclePorts, ProcessArgs, StartOutcome, LOST_WAKEUP_RECHECK};
use hnav_runtime::msg::{Commit, MapHeader, Odometry, Pose, Role, WheelCommand};
use hnav_runtime::scenario::{ClockMode, Scenario};
use hnav_runtime::topics;
use hnav_runtime::transport::{Receiver, Sender, SliceSender, Transport, TransportError};
use iceoryx2::prelude::CallbackProgression;
use iceoryx2::waitset::WaitSetRunResult;

use crate::controller::{ControllerParams, WheelController};
use crate::navigator::{Navigator, Task};
use crate::odometry::{DeadReckoning, OdometryParams};
use checkpoint::{Checkpoint, CheckpointFile};

/// How long the agent waits for the supervisor's start signal.
pub const START_TIMEOUT: Duration = Duration::from_secs(60);

/// What stopped or broke the agent.
#[derive(Debug, thiserror::Error)]
pub enum AgentError {
    /// The scenario could not be loaded.
    #[error(transparent)]
    Scenario(#[from] hnav_runtime::scenario::ScenarioError),
    /// The agent index is not in the scenario.
    #[error("agent {index} is not in the scenario ({agents} agents)")]
    NoSuchAgent {
        /// The index asked for.
        index: u32,
        /// Agents in the scenario.
        agents: usize,
    },
    /// The transport failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// Planning failed.
    #[error(transparent)]
    Plan(#[from] crate::Error),
    /// The WaitSet failed.
    #[error("waitset: {0}")]
    WaitSet(String),
}

/// How the agent's run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AgentOutcome {
    /// Control periods seen.
    pub periods: u64,
    /// Last commit round applied.
    pub last_commit: u64,
    /// Whether the robot stood on its goal at the end.
    pub at_goal: bool,
}

struct Ports {
    odom: Receiver<Odometry>,
    commit: Receiver<Commit>,
    wheels: Sender<WheelCommand>,
    candidates: Sender<hnav_runtime::msg::Candidate>,
    map: SliceSender<f32, MapHeader>,
    life: LifecyclePorts,
}

/// One agent process.
pub struct AgentProcess<'t> {
    transport: &'t Transport,
    ports: Ports,
    core: Core,
}

/// The agent's state, apart from its ports (so a WaitSet can borrow the ports while the loop
/// mutates the state).
struct Core {
    index: u32,
    clock: ClockMode,
    cell_size_m: f64,
    width: u32,
    nav: Navigator,
    dr: DeadReckoning,
    ctl: WheelController,
    checkpoint: Option<CheckpointFile>,
    last_commit: u64,
    outstanding: Option<u64>,
    last_period: Option<u64>,
    wheel_due: Option<u64>,
    /// A candidate is due for the last odometry reading.
    candidate_due: bool,
    ticks: (i64, i64),
}

impl<'t> AgentProcess<'t> {
    /// Loads agent `index` of the run described by `args` and opens its ports. A restarted
    /// agent (`args.resume`) resumes from its checkpoint in the run directory if there is a
    /// valid one.
    pub fn new(
        transport: &'t Transport,
        args: &ProcessArgs,
        scenario: &Scenario,
        index: u32,
    ) -> Result<Self, AgentError> {
        let spec = scenario
            .agents
            .get(index as usize)
            .ok_or(AgentError::NoSuchAgent {
                index,
                agents: scenario.agents.len(),
            })?;
        let grid: &Grid = &scenario.map.grid;
        let n = scenario.agents.len();
        let i = index as usize;
        let ports = Ports {
            odom: transport.receiver(&topics::odometry(i), topics::state_qos())?,
            commit: transport.receiver(topics::COMMIT, topics::commit_qos(n))?,
            wheels: transport.sender(&topics::wheels(i), topics::state_qos())?,
            candidates: transport.sender(topics::CANDIDATES, topics::candidates_qos(n))?,
            map: transport.slice_sender(&topics::map(i), grid.len(), topics::state_qos())?,
            life: LifecyclePorts::open(transport, Role::Agent, index, n)?,
        };
        let checkpoint = match &args.dir {
            Some(d) => open_checkpoint(d, index),
            None => None,
        };
        let resumed = if args.resume {
            checkpoint.as_ref().and_then(|c| c.load())
        } else {
            None
        };
        let cs = scenario.robot.cell_size_m;
        let task = Task {
            index,
            goal: spec.goal,
            priority: spec.effective_priority(),
            speed: spec.speed,
        };
        let odo = OdometryParams::from(&scenario.robot);
        let cell = |i: u32| grid.cell_at(i as usize);
        let (nav, dr, last_commit, ticks) = match resumed
            .and_then(|c| Some((c, cell(c.current)?, cell(c.next)?, cell(c.target)?)))
        {
            Some((c, current, next, target)) => {
                let mut nav = Navigator::new(
                    grid,
                    scenario.map.corner_cutting,
                    task,
                    current,
                    next,
                    target,
                )?;
                nav.mark_restarted();
                let dr = DeadReckoning::with_baseline(odo, c.pose, (c.ticks_left, c.ticks_right));
                (nav, dr, c.last_commit, (c.ticks_left, c.ticks_right))
            }
            None => {
                let start = cell_centre_pose(cs, spec.start, spec.start_heading_rad());
                let mut nav = Navigator::new(
                    grid,
                    scenario.map.corner_cutting,
                    task,
                    spec.start,
                    spec.start,
                    spec.goal,
                )?;
                if args.resume {
                    nav.mark_restarted();
                }
                (nav, DeadReckoning::new(odo, start), 0, (0, 0))
            }
        };
        Ok(AgentProcess {
            transport,
            ports,
            core: Core {
                index,
                clock: scenario.sim.clock,
                cell_size_m: cs,
                width: grid.width(),
                nav,
                dr,
                ctl: WheelController::new(ControllerParams::new(&scenario.robot, spec.speed)),
                checkpoint,
                last_commit,
                outstanding: None,
                last_period: None,
                wheel_due: None,
                candidate_due: false,
                ticks,
            },
        })
    }

    /// The navigator (row, map, target).
    pub fn navigator(&self) -> &Navigator {
        &self.core.nav
    }

    /// Announces itself, waits for the start (unless resuming) and runs until the
    /// supervisor's `Stop` or a termination signal.
    pub fn run(&mut self, resume: bool) -> Result<AgentOutcome, AgentError> {
        let started = self
            .ports
            .life
            .handshake(self.transport, resume, START_TIMEOUT)?;
        let (p, core) = (&self.ports, &mut self.core);
        if started == StartOutcome::Stopped {
            return Ok(core.outcome());
        }
        core.publish_map(p)?;
        if core.clock == ClockMode::Lockstep && !resume {
            // Period 0's command: the sim steps the first period once every robot has one.
            core.wheel_due = Some(core.last_period.map_or(0, |p| p + 1));
            core.send_wheels(p)?;
        }
        let ws = self.transport.waitset()?;
        let ws_err = |e: &dyn std::fmt::Debug| AgentError::WaitSet(format!("{e:?}"));
        let _g1 = ws
            .attach_notification(p.odom.listener())
            .map_err(|e| ws_err(&e))?;
        let _g2 = ws
            .attach_notification(p.commit.listener())
            .map_err(|e| ws_err(&e))?;
        let _g3 = ws
            .attach_notification(p.life.events().listener())
            .map_err(|e| ws_err(&e))?;
        loop {
            if p.life.drain(|_, _, _| {})?.is_some() {
                break;
            }
            core.on_commits(p)?;
            core.on_odometry(p)?;
            core.send_candidate(p)?;
            core.send_wheels(p)?;
            match ws.wait_and_process_once_with_timeout(
                |_| CallbackProgression::Continue,
                LOST_WAKEUP_RECHECK,
            ) {
                Ok(WaitSetRunResult::TerminationRequest | WaitSetRunResult::Interrupt) => break,
                Ok(_) => {}
                Err(e) => return Err(ws_err(&e)),
            }
        }
        Ok(core.outcome())
    }
}

impl Core {
    fn outcome(&self) -> AgentOutcome {
        AgentOutcome {
            periods: self.last_period.map_or(0, |p| p + 1),
            last_commit: self.last_commit,
            at_goal: self.nav.at_goal(),
        }
    }

    /// Applies every new commit; resends the open candidate to a coordinator that just came up.
    fn on_commits(&mut self, p: &Ports) -> Result<(), AgentError> {
        let wake = p.commit.take_wakeup()?;
        let mut rebuilt = false;
        while let Some(sample) = p.commit.receive()? {
            let c = sample.payload();
            if c.round <= self.last_commit {
                continue;
            }
            self.last_commit = c.round;
            if let Some(d) = c.decisions().iter().find(|d| d.agent == self.index) {
                rebuilt |= self.nav.apply(d)?.map_rebuilt;
            }
            // A later round than asked for also answers the open candidate: this agent was
            // behind (restarted, or missed by the coordinator) and counted as standing in
            // the rounds it missed; it goes on from the round that was decided.
            if self.outstanding.is_some_and(|r| r <= c.round) {
                self.outstanding = None;
            }
        }
        if rebuilt {
            self.publish_map(p)?;
        }
        if wake.peer_up {
            if let Some(r) = self.outstanding {
                let cand = self.nav.candidate(r);
                p.candidates.send(cand)?;
            }
        }
        Ok(())
    }

    /// Folds in the newest odometry reading and opens the next round.
    fn on_odometry(&mut self, p: &Ports) -> Result<(), AgentError> {
        p.odom.take_wakeup()?;
        let mut latest: Option<Odometry> = None;
        p.odom.drain(|o| {
            if latest.is_none_or(|l| o.period >= l.period) {
                latest = Some(*o);
            }
        })?;
        let Some(o) = latest.filter(|o| self.last_period.is_none_or(|p| o.period > p)) else {
            return Ok(());
        };
        if o.agent != self.index {
            tracing::warn!(
                agent = self.index,
                from = o.agent,
                "odometry of another robot dropped"
            );
            return Ok(());
        }
        self.last_period = Some(o.period);
        self.ticks = (o.ticks_left, o.ticks_right);
        let pose = self.dr.update(o.ticks_left, o.ticks_right);
        if self.nav.is_moving() {
            let (x, y) = cell_centre_m(self.cell_size_m, self.nav.next());
            if self.ctl.arrived(pose, x, y) && self.nav.arrived()? {
                self.publish_map(p)?;
            }
        }
        self.candidate_due = true;
        self.wheel_due = Some(o.period + 1);
        Ok(())
    }

    /// Publishes the candidate for round `last commit + 1` if one is due and none is open.
    fn send_candidate(&mut self, p: &Ports) -> Result<(), AgentError> {
        if !self.candidate_due || self.outstanding.is_some() {
            return Ok(());
        }
        self.candidate_due = false;
        // In lockstep round r+1 is decided between period r's odometry and period r+1's wheel
        // command, for every agent, so the period names the round; a restarted agent gets it
        // right at once. In realtime rounds run at their own pace: ask for the next one.
        let round = match (self.clock, self.last_period) {
            (ClockMode::Lockstep, Some(period)) => period + 1,
            _ => self.last_commit + 1,
        };
        if round <= self.last_commit {
            return Ok(()); // decided without this agent; it stood still
        }
        let cand = self.nav.candidate(round);
        p.candidates.send(cand)?;
        self.outstanding = Some(round);
        Ok(())
    }

    /// Sends the due wheel command; in lockstep only once the open round is decided.
    fn send_wheels(&mut self, p: &Ports) -> Result<(), AgentError> {
        let Some(period) = self.wheel_due else {
            return Ok(());
        };
        if self.clock == ClockMode::Lockstep && self.outstanding.is_some() {
            return Ok(());
        }
        let pose = self.dr.pose();
        let (l, r) = if self.nav.is_moving() {
            let (x, y) = cell_centre_m(self.cell_size_m, self.nav.next());
            let w = self.ctl.command(pose, x, y);
            (w.left_rad_s, w.right_rad_s)
        } else {
            (0.0, 0.0)
        };
        p.wheels.send(WheelCommand {
            period,
            agent: self.index,
            flags: 0,
            left_rad_s: l,
            right_rad_s: r,
        })?;
        self.wheel_due = None;
        if let Some(p) = self.last_period {
            self.store_checkpoint(p, pose);
        }
        Ok(())
    }

    /// Publishes the neural map, written straight into loaned shared memory.
    fn publish_map(&mut self, p: &Ports) -> Result<(), AgentError> {
        let map = self.nav.map();
        let len = p.map.max_len();
        let mut loan = p.map.loan(len)?;
        *loan.header_mut() = MapHeader {
            round: self.last_commit,
            agent: self.index,
            width: self.width,
            height: (len / self.width.max(1) as usize) as u32,
            iterations: self.nav.report().sweeps,
            target: cell_index(self.width, self.nav.target()) as u32,
            activation: map.options().activation.to_kind() as u8,
            reserved: [0; 3],
        };
        let out = loan.payload_mut();
        for v in out.iter_mut() {
            v.write(0.0);
        }
        // SAFETY: every element was initialised by the loop above, and `MaybeUninit<f32>` has
        // the layout of `f32`.
        let values: &mut [f32] =
            unsafe { std::slice::from_raw_parts_mut(out.as_mut_ptr().cast::<f32>(), out.len()) };
        map.write_values_f32(values)?;
        // SAFETY: every element was initialised above.
        unsafe { loan.assume_init_and_send() }?;
        Ok(())
    }

    fn store_checkpoint(&self, period: u64, pose: Pose) {
        let Some(f) = &self.checkpoint else { return };
        let idx = |c: Cell| cell_index(self.width, c) as u32;
        let c = Checkpoint {
            period,
            ticks_left: self.ticks.0,
            ticks_right: self.ticks.1,
            pose,
            current: idx(self.nav.current()),
            next: idx(self.nav.next()),
            target: idx(self.nav.target()),
            last_commit: self.last_commit,
        };
        if let Err(e) = f.store(&c) {
            tracing::warn!(path = %f.path().display(), "checkpoint not written: {e}");
        }
    }
}

fn open_checkpoint(dir: &Path, index: u32) -> Option<CheckpointFile> {
    let path = CheckpointFile::path_in(dir, index);
    match CheckpointFile::open(&path) {
        Ok(f) => Some(f),
        Err(e) => {
            tracing::warn!(path = %path.display(), "no checkpoint file: {e}");
            None
        }
    }
}
