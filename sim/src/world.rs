//! The world: N robots stepped together, stored as struct-of-arrays, with no allocation per
//! step (collision records aside, which grow only when a contact begins).
//!
//! Ground truth is kept in nalgebra types: each robot's centre is a `Point2<f64>` and its
//! heading a [`Heading`] (`UnitComplex<f64>`, the rotation `(cos θ, sin θ)`), next to the
//! unwrapped-then-wrapped angle `θ` that [`Pose`] messages carry. [`World::isometry`] gives a
//! robot's pose as an `Isometry2<f64>`. A step is [`kinematics::arc_step`], a rigid motion
//! composed of plain `f64` operations: nalgebra's fixed-size types inline to the same
//! arithmetic, in the same order, as the hand-written `x`/`y`/`cos`/`sin` fields they replaced
//! (the truth streams are bit-identical; `hnav-bench sim` is unchanged within the VM's noise,
//! and callgrind counts ~3 % fewer instructions per robot-step), so the inner loop needs no
//! separate scalar representation.
//!
//! [`kinematics::arc_step`]: crate::kinematics::arc_step

use crate::collision::{Collision, Detector};
use crate::error::SimError;
use crate::hall::{self, SlipNoise};
use crate::kinematics::{arc_step, heading, Heading};
use crate::localiser::Localiser;
use crate::robot::RobotModel;
use crate::watchdog::Watchdog;
use hnav_runtime::grid::geometry::{cell_centre_pose, wrap_angle};
use hnav_runtime::grid::Grid;
use hnav_runtime::msg::{MoverPlace, Odometry, Pose, Truth, TruthHeader};
use hnav_runtime::scenario::params::{RobotParams, SimParams};
use hnav_runtime::scenario::LocalisationParams;
use hnav_runtime::scenario::Scenario;
use nalgebra::{Isometry2, Point2, Translation2};

mod changes;
mod criteria;
mod sensing;
mod snapshot;

use changes::{Changes, Robots};
use criteria::Meter;

pub use snapshot::SnapshotError;

/// Steps between re-derivations of the heading vectors from the heading angles.
const RESYNC_STEPS: u64 = 256;

/// Every robot of a run, its motors, wheels, Hall counters and ground truth.
#[derive(Debug, Clone)]
pub struct World {
    model: RobotModel,
    grid: Grid,
    watchdog: Watchdog,
    step_ns: u64,
    steps_per_slip: u64,
    steps_per_odometry: u64,
    steps: u64,
    // Ground truth, per robot: centre (m) and heading angle, wrapped to (-π, π].
    pos: Vec<Point2<f64>>,
    theta: Vec<f64>,
    // The heading as a rotation, carried along so a step needs no library trigonometry.
    heading: Vec<Heading>,
    // Actual and commanded wheel speeds, rad/s.
    wl: Vec<f64>,
    wr: Vec<f64>,
    cmd_l: Vec<f64>,
    cmd_r: Vec<f64>,
    cmd_at: Vec<Option<u64>>,
    cmd_period: Vec<Option<u64>>,
    // Whether the watchdog brakes each robot, as of the last step: a change is logged (a
    // robot whose agent went silent, its host cut off, say, and its rejoining).
    braked: Vec<bool>,
    // Whether each robot is in motion at this step (its wheels turn or are commanded to, the
    // watchdog not braking): a mover that yields waits for one about to enter its next cell.
    in_motion: Vec<bool>,
    // Wheel angles since the start (what the Hall sensors see), rad.
    phil: Vec<f64>,
    phir: Vec<f64>,
    // Current slip factors and their generators.
    slip_l: Vec<f64>,
    slip_r: Vec<f64>,
    noise: Vec<SlipNoise>,
    slip_on: bool,
    detector: Detector,
    collisions: Vec<Collision>,
    /// The scenario's `[[events]]`: cells that close or open, movers.
    changes: Changes,
    /// Energy drawn and goal times, for the summary's criteria.
    meter: Meter,
    // Localisation fixes carried by the odometry readings; none unless set.
    localiser: Option<Localiser>,
    odometry_hz: u32,
    seed: u64,
}

/// A wheel turning slower than this, rad/s, stands still (a mover does not wait for it).
const STILL_RAD_S: f64 = 1e-3;

impl World {
    /// A world of robots at `starts` on `grid`, with the scenario's robot and sim parameters.
    pub fn new(
        robot: &RobotParams,
        sim: &SimParams,
        grid: Grid,
        starts: &[Pose],
    ) -> Result<World, SimError> {
        let model = RobotModel::new(robot, sim)?;
        if sim.odometry_hz == 0 {
            return Err(SimError::BadParam {
                name: "sim.odometry_hz",
                value: 0.0,
                why: "must be > 0",
            });
        }
        if !(sim.slip_hold_s.is_finite() && sim.slip_hold_s > 0.0) {
            return Err(SimError::BadParam {
                name: "sim.slip_hold_s",
                value: sim.slip_hold_s,
                why: "must be finite and > 0",
            });
        }
        if let Some(i) = starts
            .iter()
            .position(|p| !(p.x_m.is_finite() && p.y_m.is_finite() && p.theta_rad.is_finite()))
        {
            return Err(SimError::NonFinitePose { robot: i });
        }
        let n = starts.len();
        let step_ns = u64::from(sim.step_ms) * 1_000_000;
        let per = |period_s: f64| ((period_s / model.dt).round() as u64).max(1);
        Ok(World {
            steps_per_slip: per(sim.slip_hold_s),
            steps_per_odometry: sim.steps_per_control_period(),
            watchdog: Watchdog::from_ms(sim.watchdog_ms),
            step_ns,
            steps: 0,
            pos: starts.iter().map(|p| Point2::new(p.x_m, p.y_m)).collect(),
            theta: starts.iter().map(|p| wrap_angle(p.theta_rad)).collect(),
            heading: starts.iter().map(|p| heading(p.theta_rad)).collect(),
            wl: vec![0.0; n],
            wr: vec![0.0; n],
            cmd_l: vec![0.0; n],
            cmd_r: vec![0.0; n],
            cmd_at: vec![None; n],
            cmd_period: vec![None; n],
            braked: vec![true; n],
            in_motion: vec![false; n],
            phil: vec![0.0; n],
            phir: vec![0.0; n],
            slip_l: vec![0.0; n],
            slip_r: vec![0.0; n],
            noise: (0..n as u64)
                .map(|i| SlipNoise::new(sim.seed, i, sim.slip_std))
                .collect(),
            slip_on: sim.slip_std > 0.0,
            detector: Detector::new(n, &grid, model.cell_size_m, model.body_radius_m),
            collisions: Vec::new(),
            changes: Changes::default(),
            meter: Meter::new(n, model.wheel_radius_m, model.dt),
            localiser: None,
            odometry_hz: sim.odometry_hz,
            seed: sim.seed,
            model,
            grid,
        })
    }

    /// The world of a scenario: its robot and sim parameters, its map, one robot per agent
    /// at the centre of the agent's start cell, facing its `start_heading_deg`, and its
    /// `[localisation]` fixes.
    pub fn from_scenario(scenario: &Scenario) -> Result<World, SimError> {
        let cs = scenario.robot.cell_size_m;
        let starts: Vec<_> = scenario
            .agents
            .iter()
            .map(|a| cell_centre_pose(cs, a.start, a.start_heading_rad()))
            .collect();
        let mut world = World::new(
            &scenario.robot,
            &scenario.sim,
            scenario.map.grid.clone(),
            &starts,
        )?;
        world.changes = Changes::new(scenario.events.clone());
        world
            .meter
            .set_goals(scenario.agents.iter().map(|a| a.goal));
        world.apply_changes();
        world.set_localisation(scenario.localisation);
        Ok(world)
    }

    /// Applies the events due by now; the movers are moved by the next step.
    fn apply_changes(&mut self) {
        let t_s = self.time_ns() as f64 * 1e-9;
        if self.changes.apply_due(t_s, &mut self.grid, self.pos.len()) {
            self.detector.refresh_open(&self.grid);
        }
    }

    /// The moving obstacles under way: name and centre (m).
    pub fn movers(&self) -> impl Iterator<Item = (&str, Point2<f64>)> {
        self.changes.movers()
    }

    /// How many movers are on the floor.
    pub fn movers_on_floor(&self) -> usize {
        self.changes.movers_on_floor()
    }

    /// The `n`-th mover on the floor as the `movers` topic carries it: its index (in the
    /// order the movers appeared), centre (m) and heading along its leg.
    pub fn mover_place(&self, n: usize) -> MoverPlace {
        self.changes
            .mover_pose(n)
            .map_or_else(MoverPlace::default, |(k, at, heading)| MoverPlace {
                mover: u32::try_from(k).unwrap_or(u32::MAX),
                reserved: 0,
                pose: Pose {
                    x_m: at.x,
                    y_m: at.y,
                    theta_rad: heading,
                },
            })
    }

    /// Makes the odometry readings carry localisation fixes as `params` says (a world made
    /// by [`World::new`] has none), seeded by the run's seed.
    pub fn set_localisation(&mut self, params: LocalisationParams) {
        self.localiser = params
            .enabled()
            .then(|| Localiser::new(params, self.odometry_hz, self.seed));
    }

    /// Number of robots.
    pub fn robots(&self) -> usize {
        self.pos.len()
    }

    /// The validated robot model.
    pub fn model(&self) -> &RobotModel {
        &self.model
    }

    /// The map.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// Sim time, ns since the start.
    pub fn time_ns(&self) -> u64 {
        self.steps * self.step_ns
    }

    /// Physics steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Physics steps per odometry reading (from `sim.odometry_hz`, at least 1).
    pub fn steps_per_odometry(&self) -> u64 {
        self.steps_per_odometry
    }

    /// Whether the last step closed an odometry period (a reading is due).
    pub fn odometry_due(&self) -> bool {
        self.steps > 0 && self.steps.is_multiple_of(self.steps_per_odometry)
    }

    fn check(&self, agent: u32) -> Result<usize, SimError> {
        let i = agent as usize;
        if i < self.robots() {
            Ok(i)
        } else {
            Err(SimError::UnknownAgent {
                agent,
                robots: self.robots(),
            })
        }
    }

    /// Sets robot `agent`'s wheel speed set-points (rad/s) for control period `period`,
    /// received at sim time `now_ns` (the watchdog measures from there).
    pub fn apply_command(
        &mut self,
        agent: u32,
        period: u64,
        left: f64,
        right: f64,
        now_ns: u64,
    ) -> Result<(), SimError> {
        let i = self.check(agent)?;
        if !(left.is_finite() && right.is_finite()) {
            return Err(SimError::NonFiniteCommand { agent, left, right });
        }
        self.cmd_l[i] = left;
        self.cmd_r[i] = right;
        self.cmd_at[i] = Some(now_ns);
        self.cmd_period[i] = Some(period);
        Ok(())
    }

    /// Drops robot `agent`'s command so that it brakes from now on (its agent is down).
    /// Unknown agents are ignored.
    pub fn brake(&mut self, agent: u32) {
        if let Some(t) = self.cmd_at.get_mut(agent as usize) {
            *t = None;
        }
    }

    /// The control period of robot `agent`'s last command, if any.
    pub fn command_period(&self, agent: u32) -> Option<u64> {
        self.cmd_period.get(agent as usize).copied().flatten()
    }

    /// Sets robot `agent`'s actual wheel speeds (rad/s) directly, bypassing the motor model:
    /// for initial conditions and tests that start a robot already at speed.
    pub fn set_wheel_speeds(&mut self, agent: u32, left: f64, right: f64) -> Result<(), SimError> {
        let i = self.check(agent)?;
        if !(left.is_finite() && right.is_finite()) {
            return Err(SimError::NonFiniteCommand { agent, left, right });
        }
        self.wl[i] = left;
        self.wr[i] = right;
        Ok(())
    }

    /// Robot `agent`'s actual wheel speeds `(left, right)`, rad/s.
    pub fn wheel_speeds(&self, agent: u32) -> Option<(f64, f64)> {
        let i = agent as usize;
        (i < self.robots()).then(|| (self.wl[i], self.wr[i]))
    }

    /// Whether robot `agent`'s watchdog is braking it now.
    pub fn braking(&self, agent: u32) -> bool {
        let i = agent as usize;
        i < self.robots() && self.watchdog.expired(self.cmd_at[i], self.time_ns())
    }

    /// Advances the world by one physics step and returns how many collisions began in it.
    pub fn step(&mut self) -> usize {
        let now = self.time_ns();
        let m = &self.model;
        let (dt, r, inv_b) = (m.dt, m.wheel_radius_m, 1.0 / m.axle_track_m);
        // Re-derive the heading vectors from the angles now and then (cost amortised to
        // nothing) so that rounding in the rotations cannot accumulate.
        let resync = self.steps.is_multiple_of(RESYNC_STEPS);
        let wheel = self.meter.wheel;
        let redraw = self.slip_on && self.steps.is_multiple_of(self.steps_per_slip);
        for i in 0..self.pos.len() {
            let (l0, r0) = (self.wl[i], self.wr[i]);
            let expired = self.watchdog.expired(self.cmd_at[i], now);
            if expired != self.braked[i] {
                self.braked[i] = expired;
                log_brake(i, expired, now, self.cmd_at[i]);
            }
            let (l1, r1) = if expired {
                (m.brake_step(l0), m.brake_step(r0))
            } else {
                (
                    m.motor_step(l0, self.cmd_l[i]),
                    m.motor_step(r0, self.cmd_r[i]),
                )
            };
            self.wl[i] = l1;
            self.wr[i] = r1;
            self.meter.energy_j[i] += wheel.step_j(l0, l1) + wheel.step_j(r0, r1);
            let commanded = !expired && (self.cmd_l[i] != 0.0 || self.cmd_r[i] != 0.0);
            // The motor lag decays a wheel speed geometrically, never quite to zero.
            self.in_motion[i] = commanded || l1.abs() > STILL_RAD_S || r1.abs() > STILL_RAD_S;
            // Trapezoidal wheel angle: exact for the acceleration-limited (linear) ramp.
            let (dphl, dphr) = (0.5 * (l0 + l1) * dt, 0.5 * (r0 + r1) * dt);
            self.phil[i] += dphl;
            self.phir[i] += dphr;
            let (mut dsl, mut dsr) = (r * dphl, r * dphr);
            if self.slip_on {
                if redraw {
                    (self.slip_l[i], self.slip_r[i]) = self.noise[i].draw();
                }
                dsl *= 1.0 + self.slip_l[i];
                dsr *= 1.0 + self.slip_r[i];
            }
            let (ds, dth) = (0.5 * (dsr + dsl), (dsr - dsl) * inv_b);
            let (p, q) = arc_step(&self.pos[i], &self.heading[i], ds, dth);
            self.pos[i] = p;
            self.theta[i] = wrap_angle(self.theta[i] + dth);
            self.heading[i] = if resync { heading(self.theta[i]) } else { q };
        }
        self.steps += 1;
        let t = self.time_ns();
        if self.odometry_due() {
            self.meter.note_goals(&self.pos, self.model.cell_size_m, t);
        }
        if self.changes.is_empty() {
            return self
                .detector
                .check(&self.grid, &self.pos, t, &mut self.collisions);
        }
        self.apply_changes();
        let robots = Robots {
            centres: &self.pos,
            in_motion: &self.in_motion,
            radius: self.model.body_radius_m,
            cell: self.model.cell_size_m,
        };
        let movers = self
            .changes
            .mover_contacts(t as f64 * 1e-9, t, &robots, &mut self.collisions);
        movers
            + self
                .detector
                .check(&self.grid, &self.pos, t, &mut self.collisions)
    }

    /// Robot `agent`'s ground-truth pose.
    pub fn pose(&self, agent: u32) -> Option<Pose> {
        let i = agent as usize;
        (i < self.robots()).then(|| self.pose_at(i))
    }

    /// Robot `i`'s pose as the ground truth gives it (`i` below [`World::robots`]): the
    /// unchecked [`World::pose`], for filling a truth sample in place.
    pub fn pose_at(&self, i: usize) -> Pose {
        Pose {
            x_m: self.pos[i].x,
            y_m: self.pos[i].y,
            theta_rad: self.theta[i],
        }
    }

    /// Robot `agent`'s ground-truth pose as a rigid transform (robot frame to world frame).
    pub fn isometry(&self, agent: u32) -> Option<Isometry2<f64>> {
        let i = agent as usize;
        (i < self.robots()).then(|| {
            Isometry2::from_parts(
                Translation2::from(self.pos[i].coords),
                heading(self.theta[i]),
            )
        })
    }

    /// Robot `agent`'s ground-truth centre, m.
    pub fn position(&self, agent: u32) -> Option<Point2<f64>> {
        self.pos.get(agent as usize).copied()
    }

    /// Robot `agent`'s cumulative Hall ticks `(left, right)`.
    pub fn ticks(&self, agent: u32) -> Option<(i64, i64)> {
        let i = agent as usize;
        let n = self.model.ticks_per_rev;
        (i < self.robots()).then(|| (hall::ticks(self.phil[i], n), hall::ticks(self.phir[i], n)))
    }

    /// Robot `agent`'s odometry message for control period `period`, with its localisation
    /// fix if one is due then.
    pub fn odometry(&self, agent: u32, period: u64) -> Option<Odometry> {
        let (ticks_left, ticks_right) = self.ticks(agent)?;
        let fix = self
            .localiser
            .and_then(|l| l.fix(agent, period, self.pose_at(agent as usize)));
        Some(Odometry {
            sim_time_ns: self.time_ns(),
            period,
            agent,
            flags: if fix.is_some() { Odometry::FIX } else { 0 },
            ticks_left,
            ticks_right,
            fix: fix.unwrap_or_default(),
        })
    }

    /// The header of the ground truth for control period `period`: time, robots and the
    /// collision count; [`World::pose_at`] gives each robot's pose to go with it.
    pub fn truth_header(&self, period: u64) -> TruthHeader {
        TruthHeader {
            sim_time_ns: self.time_ns(),
            period,
            robots: u32::try_from(self.robots()).unwrap_or(u32::MAX),
            collisions: u32::try_from(self.collisions.len()).unwrap_or(u32::MAX),
        }
    }

    /// Fills `truth` for control period `period`, reusing its poses' memory.
    pub fn fill_truth(&self, period: u64, truth: &mut Truth) {
        let h = self.truth_header(period);
        truth.sim_time_ns = h.sim_time_ns;
        truth.period = h.period;
        truth.collisions = h.collisions;
        truth.poses.clear();
        truth
            .poses
            .extend((0..self.robots()).map(|i| self.pose_at(i)));
    }

    /// What the sim measured of each robot for the summary: energy drawn, first time at
    /// its goal.
    pub fn criteria(&self) -> hnav_runtime::criteria::SimCriteria {
        self.meter.criteria()
    }

    /// Every collision recorded so far, in order of the step that began it (robot contacts
    /// after wall contacts within one step): its time, the robot, what it hit (robot or cell)
    /// and both positions. `Truth::collisions` is the length of this list.
    pub fn collisions(&self) -> &[Collision] {
        &self.collisions
    }
}

/// Logs that robot `i`'s watchdog started (`braking`) or stopped braking at sim time `now`.
#[cold]
fn log_brake(i: usize, braking: bool, now: u64, last_cmd: Option<u64>) {
    let sim_time_s = now as f64 / 1e9;
    if braking {
        let silent_ms = last_cmd.map_or(0.0, |t| now.saturating_sub(t) as f64 / 1e6);
        tracing::warn!(
            robot = i,
            sim_time_s,
            silent_ms,
            "watchdog: no fresh wheel command, braking"
        );
    } else {
        tracing::info!(robot = i, sim_time_s, "watchdog: wheel commands again");
    }
}
