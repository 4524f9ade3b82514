//! The agent's state and what it does with each input: [`Core`].
//!
//! Kept apart from the [`Ports`] so that the loop can borrow the ports (attached to its
//! waiter) while it mutates the state.

use std::time::{Duration, Instant};

use hnav_runtime::diag::is_no_space_io;
use hnav_runtime::grid::geometry::{cell_centre_m, cell_centre_pose, cell_index};
use hnav_runtime::grid::Cell;
use hnav_runtime::grid::Grid;
use hnav_runtime::hash::SplitMix64;
use hnav_runtime::msg::{
    CommitView, Decision, Estimate, MapHeader, Odometry, Pose, View, WheelCommand, WorldHeader,
};
use hnav_runtime::scenario::{AgentSpec, ClockMode, Planner, RepairRule, Scenario};

use super::checkpoint::{Checkpoint, CheckpointFile};
use super::oracle::Oracle;
use super::ports::{Ports, RobotPorts};
use super::sightings::Sightings;
use super::{AgentError, AgentOutcome};
use crate::controller::{ControllerParams, FreeSpace, WheelController, WheelDrive};
use crate::ga_fuzzy::{GaOptions, GaPlanner};
use crate::navigator::{Guidance, Navigator, Task};
use crate::odometry::{DeadReckoning, OdometryParams, Relocaliser};
use crate::pso::{PsoOptions, PsoPlanner};

/// How long a realtime agent waits for the commit of its open candidate before it sends it
/// again: four round deadlines (a round closes within one), and no less than 200 ms.
fn resend_after(scenario: &Scenario) -> Duration {
    let deadline = Duration::from_millis(u64::from(scenario.coordinator.round_deadline_ms));
    (4 * deadline).max(Duration::from_millis(200))
}

/// What the process's shared topics brought one robot in a pass: its newest odometry reading
/// and view, if any.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Inbox {
    odometry: Option<Odometry>,
    view: Option<View>,
}

impl Inbox {
    /// Keeps `o` if it is the newest reading so far.
    pub(super) fn odometry(&mut self, o: &Odometry) {
        if self.odometry.is_none_or(|l| o.period >= l.period) {
            self.odometry = Some(*o);
        }
    }

    /// Keeps `v` if it is the newest view so far.
    pub(super) fn view(&mut self, v: &View) {
        if self.view.is_none_or(|l| v.period >= l.period) {
            self.view = Some(*v);
        }
    }
}

/// One agent's state: its navigator, dead reckoning and wheel controller, and where it stands
/// in the rounds.
pub(super) struct Core {
    index: u32,
    clock: ClockMode,
    cell_size_m: f64,
    width: u32,
    nav: Navigator,
    dr: DeadReckoning,
    /// Takes the sim's localisation fixes into `dr` when it has drifted.
    reloc: Relocaliser,
    ctl: WheelDrive,
    checkpoint: Option<CheckpointFile>,
    last_commit: u64,
    outstanding: Option<u64>,
    /// When the open candidate was (last) sent: in realtime it is sent again if no commit
    /// answers it within `resend_after` (a candidate or its commit lost on a link between
    /// hosts; the coordinator answers a candidate for a decided round with the last commit).
    sent_at: Option<Instant>,
    resend_after: Duration,
    last_period: Option<u64>,
    wheel_due: Option<u64>,
    /// The last wheel command sent, for a restarted sim that asks for it again.
    last_wheels: Option<WheelCommand>,
    /// A candidate is due for the last odometry reading.
    candidate_due: bool,
    ticks: (i64, i64),
    /// How the neural map is repaired when the view differs from it; none: no sensing.
    repair: Option<RepairRule>,
    /// What the robot saw change, for the coordinator (with `[sensing]`).
    sightings: Option<Sightings>,
    /// The all-knowing baseline's events (`[sensing] all_knowing`).
    oracle: Option<Oracle>,
    /// A commit applied since the last pass rebuilt the neural map: a snapshot is due.
    rebuilt: bool,
}

impl Core {
    /// The state of agent `index` (`spec`) of `scenario`: from `resumed` if it names valid
    /// cells, else at the start. `restarted` marks the navigator as restarted either way.
    pub(super) fn new(
        scenario: &Scenario,
        spec: &AgentSpec,
        index: u32,
        checkpoint: Option<CheckpointFile>,
        resumed: Option<Checkpoint>,
        restarted: bool,
    ) -> Result<Self, AgentError> {
        // Unmapped (`known_map = false`, seed 003): no wall is known until it is seen.
        let unmapped = scenario.sensing.is_some_and(|s| !s.known_map);
        let blank = unmapped.then(|| blank_like(&scenario.map.grid));
        let grid = blank.as_ref().unwrap_or(&scenario.map.grid);
        let cs = scenario.robot.cell_size_m;
        let task = Task {
            index,
            goal: spec.goal,
            priority: spec.effective_priority(),
            speed: spec.speed,
        };
        let odo = OdometryParams::from(&scenario.robot);
        let cell = |i: u32| grid.cell_at(i as usize);
        let corners = scenario.map.corner_cutting;
        let (nav, dr, last_commit, ticks) = match resumed
            .and_then(|c| Some((c, cell(c.current)?, cell(c.next)?, cell(c.target)?)))
        {
            Some((c, current, next, target)) => {
                let guide = guidance(scenario, spec, index)?;
                let mut nav = Navigator::new(grid, corners, task, (current, next, target), guide)?;
                nav.mark_restarted();
                let dr = DeadReckoning::with_baseline(odo, c.pose, (c.ticks_left, c.ticks_right));
                (nav, dr, c.last_commit, (c.ticks_left, c.ticks_right))
            }
            None => {
                let start = cell_centre_pose(cs, spec.start, spec.start_heading_rad());
                let row = (spec.start, spec.start, spec.goal);
                let guide = guidance(scenario, spec, index)?;
                let mut nav = Navigator::new(grid, corners, task, row, guide)?;
                if restarted {
                    nav.mark_restarted();
                }
                (nav, DeadReckoning::new(odo, start), 0, (0, 0))
            }
        };
        Ok(Self {
            index,
            clock: scenario.sim.clock,
            cell_size_m: cs,
            width: grid.width(),
            nav,
            dr,
            reloc: Relocaliser::new(&scenario.localisation, &odo),
            ctl: wheel_drive(scenario, spec),
            checkpoint,
            last_commit,
            outstanding: None,
            sent_at: None,
            resend_after: resend_after(scenario),
            last_period: None,
            wheel_due: None,
            last_wheels: None,
            candidate_due: false,
            ticks,
            repair: scenario.sensing.map(|s| s.repair),
            sightings: scenario.sensing.map(|_| Sightings::new(&scenario.map.grid)),
            oracle: Oracle::of(scenario),
            rebuilt: false,
        })
    }

    /// The navigator (row, map, target).
    pub(super) fn navigator(&self) -> &Navigator {
        &self.nav
    }

    /// How the run stands now.
    pub(super) fn outcome(&self) -> AgentOutcome {
        AgentOutcome {
            periods: self.last_period.map_or(0, |p| p + 1),
            last_commit: self.last_commit,
            at_goal: self.nav.at_goal(),
        }
    }

    /// What the agent publishes once started: its first map and, in a fresh lockstep run,
    /// period 0's wheel command (the sim steps the first period once every robot has one).
    pub(super) fn begin(
        &mut self,
        p: &Ports,
        r: &RobotPorts,
        resume: bool,
    ) -> Result<(), AgentError> {
        self.publish_map(r)?;
        if self.clock == ClockMode::Lockstep && !resume {
            self.wheel_due = Some(self.last_period.map_or(0, |p| p + 1));
            self.send_wheels(p)?;
        }
        Ok(())
    }

    /// The robot's index in the swarm.
    pub(super) fn index(&self) -> u32 {
        self.index
    }

    /// One pass over this robot's inputs once the process has handed it the new commits
    /// ([`Core::apply_commit`], [`Core::after_commits`]) and the coordinator's map
    /// ([`Core::learn_world`]) and sorted out its odometry and view (`inbox`), in the order
    /// that keeps lockstep runs deterministic: view, odometry, then what they made due.
    pub(super) fn step(
        &mut self,
        p: &Ports,
        r: &RobotPorts,
        inbox: Inbox,
    ) -> Result<(), AgentError> {
        self.on_view(inbox.view)?;
        self.on_odometry(p, r, inbox.odometry)?;
        self.send_candidate(p, r)?;
        self.resend_if_unanswered(p)?;
        self.send_wheels(p)
    }

    /// When the open candidate is due to be sent again (realtime only).
    pub(super) fn resend_due(&self) -> Option<Instant> {
        match (self.clock, self.outstanding, self.sent_at) {
            (ClockMode::Realtime, Some(_), Some(at)) => Some(at + self.resend_after),
            _ => None,
        }
    }

    /// Sends the open candidate again once no commit answered it in time.
    fn resend_if_unanswered(&mut self, p: &Ports) -> Result<(), AgentError> {
        let (Some(due), Some(r)) = (self.resend_due(), self.outstanding) else {
            return Ok(());
        };
        let now = Instant::now();
        if now < due {
            return Ok(());
        }
        tracing::debug!(round = r, "no commit for the open candidate: sent again");
        p.candidates.post(self.nav.candidate(r))?;
        self.sent_at = Some(now);
        Ok(())
    }

    /// Applies commit `c` if it is new.
    pub(super) fn apply_commit(&mut self, c: CommitView<'_>) -> Result<(), AgentError> {
        if c.round() <= self.last_commit {
            return Ok(());
        }
        self.last_commit = c.round();
        // The coordinator writes decision i for agent i; the search is for a commit that
        // does not, so that a thousand robots do not each scan a thousand decisions.
        let own = |d: &&Decision| d.agent == self.index;
        let mine = c.decisions().get(self.index as usize).filter(own);
        if let Some(d) = mine.or_else(|| c.decisions().iter().find(own)) {
            if let Some(s) = &mut self.sightings {
                s.refused(d);
            }
            self.rebuilt |= self.nav.apply(d)?.map_rebuilt;
        }
        // A later round than asked for also answers the open candidate: this agent was
        // behind (restarted, or missed by the coordinator) and counted as standing in
        // the rounds it missed; it goes on from the round that was decided.
        if self.outstanding.is_some_and(|r| r <= c.round()) {
            self.outstanding = None;
            self.sent_at = None;
        }
        Ok(())
    }

    /// After the new commits: the snapshot of a map they rebuilt, and the open candidate
    /// again to a coordinator that just came up (`peer_up`).
    pub(super) fn after_commits(
        &mut self,
        p: &Ports,
        r: &RobotPorts,
        peer_up: bool,
    ) -> Result<(), AgentError> {
        if std::mem::take(&mut self.rebuilt) {
            self.publish_map(r)?;
        }
        if let Some(round) = self.outstanding.filter(|_| peer_up) {
            p.candidates.post(self.nav.candidate(round))?;
        }
        Ok(())
    }

    /// Folds in the newest view (it comes before the odometry of its period): cells that
    /// changed are learned and the guide repaired.
    fn on_view(&mut self, latest: Option<View>) -> Result<(), AgentError> {
        let Some(rule) = self.repair else {
            return Ok(());
        };
        // A repaired map is marked replanned: its snapshot goes out with the next candidate.
        if let Some(v) = latest {
            if let Some(s) = &mut self.sightings {
                s.fold(&v);
            }
            self.nav.sense(&v, rule)?;
        }
        Ok(())
    }

    /// The all-knowing baseline: the scenario's closes and opens due by `sim_time_ns`, folded
    /// in as if seen (and reported like sightings, so the coordinator knows them at once).
    fn tell(&mut self, sim_time_ns: u64, period: u64) -> Result<(), AgentError> {
        let (Some(oracle), Some(rule)) = (&mut self.oracle, self.repair) else {
            return Ok(());
        };
        let due = oracle.due(sim_time_ns as f64 * 1e-9);
        if due.is_empty() {
            return Ok(());
        }
        if let Some(s) = &mut self.sightings {
            for &(c, blocked) in &due {
                s.see(c.y * self.width + c.x, blocked);
            }
        }
        self.nav.learn(due.into_iter(), rule, period)?;
        Ok(())
    }

    /// Folds in the coordinator's map as it stands (`h`, `cells`), when it was sent to this
    /// agent (it restarted): the map at start is out of date by every change the swarm saw
    /// since.
    pub(super) fn learn_world(&mut self, h: &WorldHeader, slice: &[u32]) -> Result<(), AgentError> {
        let (to, cells) = h.split(slice);
        let Some(rule) = self
            .repair
            .filter(|_| WorldHeader::is_for(to, self.index as usize))
        else {
            return Ok(());
        };
        let (period, width) = (self.last_period.unwrap_or(0), self.width);
        let closed = (h.closed as usize).min(cells.len());
        let state = |k: usize| (cells[k], k < closed);
        if let Some(s) = self.sightings.as_mut() {
            (0..cells.len()).map(state).for_each(|(c, b)| s.learn(c, b));
        }
        let known = (0..cells.len())
            .map(state)
            .map(|(c, b)| (Cell::new(c % width.max(1), c / width.max(1)), b));
        tracing::info!(
            closed,
            opened = cells.len() - closed,
            round = h.round,
            "the coordinator's map"
        );
        self.nav.learn(known, rule, period)?;
        Ok(())
    }

    /// Folds in the newest odometry reading and opens the next round.
    fn on_odometry(
        &mut self,
        p: &Ports,
        r: &RobotPorts,
        latest: Option<Odometry>,
    ) -> Result<(), AgentError> {
        if let Some(o) = latest.filter(|o| Some(o.period) == self.last_period) {
            self.on_repeated_odometry(p, o.period);
            return Ok(());
        }
        let Some(o) = latest.filter(|o| self.last_period.is_none_or(|p| o.period > p)) else {
            return Ok(());
        };
        self.last_period = Some(o.period);
        self.tell(o.sim_time_ns, o.period)?;
        self.ticks = (o.ticks_left, o.ticks_right);
        let mut pose = self.dr.update(o.ticks_left, o.ticks_right);
        if let Some(fix) = o.fix() {
            if self.reloc.apply(&mut self.dr, fix) {
                tracing::debug!(?pose, ?fix, "drifted beyond the gate: took the fix");
                pose = self.dr.pose();
            }
        }
        // Silent: the recorder and viewers take the latest at their own pace.
        r.estimate.send_silently(Estimate {
            sim_time_ns: o.sim_time_ns,
            agent: self.index,
            reserved: 0,
            pose,
        })?;
        if self.nav.is_moving() {
            let (x, y) = cell_centre_m(self.cell_size_m, self.nav.next());
            if self.ctl.arrived(pose, x, y) && self.nav.arrived()? {
                self.publish_map(r)?;
            }
        }
        self.candidate_due = true;
        self.wheel_due = Some(o.period + 1);
        Ok(())
    }

    /// The reading of a period already folded in, again: a restarted sim resumed from its
    /// checkpoint publishes its last period once more. It subscribed after this agent sent
    /// its command for the next period (an iceoryx2 subscriber does not get what was sent
    /// before it existed), so in lockstep it would wait for that command for ever: send it
    /// again. The reading itself changes nothing.
    fn on_repeated_odometry(&mut self, p: &Ports, period: u64) {
        if let Some(c) = self.last_wheels.filter(|c| c.period == period + 1) {
            p.wheels.post(c);
        }
    }

    /// Publishes the candidate for round `last commit + 1` if one is due and none is open.
    fn send_candidate(&mut self, p: &Ports, r: &RobotPorts) -> Result<(), AgentError> {
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
        if let (Some(s), Some(tx)) = (&mut self.sightings, &p.sightings) {
            s.send(tx, round, self.index)?;
        }
        p.candidates.post(cand)?;
        self.outstanding = Some(round);
        self.sent_at = Some(Instant::now());
        if self.nav.take_replanned() {
            self.publish_map(r)?;
        }
        Ok(())
    }

    /// Posts the due wheel command (the pass sends it); in lockstep only once the open round
    /// is decided.
    fn send_wheels(&mut self, p: &Ports) -> Result<(), AgentError> {
        let Some(period) = self.wheel_due else {
            return Ok(());
        };
        if self.clock == ClockMode::Lockstep && self.outstanding.is_some() {
            return Ok(());
        }
        let pose = self.dr.pose();
        let (cx, cy) = cell_centre_m(self.cell_size_m, self.nav.current());
        let from_centre = (pose.x_m - cx).hypot(pose.y_m - cy) / self.cell_size_m;
        let (left, right) = if self.nav.is_moving() && !self.nav.waits_for_mover(from_centre) {
            let (x, y) = cell_centre_m(self.cell_size_m, self.nav.next());
            let free = if self.ctl.needs_free_space() {
                FreeSpace::from_grid(self.nav.grid(), self.cell_size_m, pose, self.ctl.range_m())
            } else {
                FreeSpace::open(0.0)
            };
            let w = self.ctl.command(pose, x, y, &free);
            (w.left_rad_s, w.right_rad_s)
        } else {
            (0.0, 0.0)
        };
        // Before the command, not after: once the sim has every command of a period it may
        // hold there for a planned fault and the supervisor kill this agent, which must then
        // resume from this period's checkpoint in every run, never from the one before.
        if let Some(p) = self.last_period {
            self.store_checkpoint(p, pose)?;
        }
        let command = WheelCommand {
            period,
            agent: self.index,
            flags: 0,
            left_rad_s: left,
            right_rad_s: right,
        };
        p.wheels.post(command);
        self.last_wheels = Some(command);
        self.wheel_due = None;
        Ok(())
    }

    /// Publishes the neural map, written straight into loaned shared memory.
    fn publish_map(&mut self, r: &RobotPorts) -> Result<(), AgentError> {
        let nav = &self.nav;
        let len = r.map.max_len();
        let mut loan = r.map.loan(len)?;
        *loan.header_mut() = MapHeader {
            round: self.last_commit,
            agent: self.index,
            width: self.width,
            height: (len / self.width.max(1) as usize) as u32,
            iterations: nav.snapshot_iterations(),
            target: cell_index(self.width, nav.target()) as u32,
            activation: nav.snapshot_kind() as u8,
            reserved: [0; 3],
        };
        // Zero first: cells the map does not write (a slice longer than the grid) read 0.
        loan.fill_with(0.0, |values| {
            nav.write_snapshot(values).map_err(AgentError::from)
        })?;
        Ok(())
    }

    /// Writes the restart checkpoint for `period`. A failure is logged, not fatal (the robot
    /// can go on without one), except a full disk: that ends the agent with
    /// [`AgentError::NoSpace`], because a restart into the same full disk would not help and
    /// the supervisor must learn why the run cannot go on.
    fn store_checkpoint(&self, period: u64, pose: Pose) -> Result<(), AgentError> {
        let Some(f) = &self.checkpoint else {
            return Ok(());
        };
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
        match f.store(&c) {
            Err(e) if is_no_space_io(&e) => Err(AgentError::NoSpace {
                path: f.path().to_path_buf(),
                source: e,
            }),
            Err(e) => {
                tracing::warn!(path = %f.path().display(), "checkpoint not written: {e}");
                Ok(())
            }
            Ok(()) => Ok(()),
        }
    }
}

/// The guide of `spec`'s planner. A swarm's random stream is seeded by the run's seed and the
/// agent's index, so a lockstep run repeats itself and two PSO agents do not share a stream.
fn guidance(scenario: &Scenario, spec: &AgentSpec, index: u32) -> Result<Guidance, AgentError> {
    let corners = scenario.map.corner_cutting;
    Ok(match spec.planner {
        Planner::Hnav => Guidance::NeuralMap,
        Planner::Pso => {
            let seed = SplitMix64::new(scenario.sim.seed ^ u64::from(index)).next_u64();
            Guidance::Route(Box::new(PsoPlanner::new(
                PsoOptions::default(),
                corners,
                seed,
            )?))
        }
        Planner::GaFuzzy => Guidance::Route(Box::new(GaPlanner::new(GaOptions {
            corner_cutting: corners,
            seed: scenario.sim.seed ^ u64::from(index),
            ..GaOptions::default()
        })?)),
    })
}

/// The wheel controller of `spec`'s planner: seed 004's fuzzy one for `ga-fuzzy`, the
/// proportional one otherwise.
fn wheel_drive(scenario: &Scenario, spec: &AgentSpec) -> WheelDrive {
    match spec.planner {
        Planner::GaFuzzy => WheelDrive::fuzzy(&scenario.robot, spec.speed),
        Planner::Hnav | Planner::Pso => WheelDrive::Proportional(WheelController::new(
            ControllerParams::new(&scenario.robot, spec.speed),
        )),
    }
}

/// A grid of `grid`'s size with no wall: what an agent knows of an unmapped world.
fn blank_like(grid: &Grid) -> Grid {
    let mut blank = grid.clone();
    for c in grid.cells() {
        blank.set_blocked(c, false);
    }
    blank
}
