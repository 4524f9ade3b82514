//! The validated parameter sections of a scenario, with their defaults.
//!
//! Defaults describe an s-bot-like robot (small differential drive, BLDC hub motors with Hall
//! sensors) on 16 cm cells, a 1 kHz lockstep physics step and a coordinator that never
//! publishes a commit before its log record is durable.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// Robot geometry and drive limits (`[robot]`).
#[derive(Clone, PartialEq, Debug, Serialize)]
pub struct RobotParams {
    /// Wheel radius in metres.
    pub wheel_radius_m: f64,
    /// Distance between the wheel contact points (track width) in metres.
    pub axle_track_m: f64,
    /// Radius of the round body in metres; the body must fit in a cell.
    pub body_radius_m: f64,
    /// Largest wheel speed in rad/s.
    pub max_wheel_speed_rad_s: f64,
    /// Largest wheel acceleration in rad/s^2.
    pub max_wheel_accel_rad_s2: f64,
    /// First-order motor time constant in seconds (0 = ideal motor).
    pub motor_lag_s: f64,
    /// Hall ticks per wheel revolution: `6 * pole_pairs * gear_ratio` unless given directly.
    pub ticks_per_rev: f64,
    /// Edge length of a grid cell in metres. The default, 16 cm for a 116 mm body, leaves
    /// 22 mm on each side of a robot at a cell's centre: two robots in neighbouring cells or a
    /// robot beside a wall stay clear while the wheel controller settles and the odometry
    /// drifts by a few ticks (with 12 cm cells the demo's robots grazed walls by microns).
    pub cell_size_m: f64,
}

impl RobotParams {
    /// Default motor pole pairs (3 Hall sensors give 6 states per electrical revolution).
    pub const DEFAULT_POLE_PAIRS: u32 = 7;

    /// Highest agent speed in cells/s the wheels allow when driving straight.
    pub fn max_speed_cells_s(&self) -> f64 {
        self.max_wheel_speed_rad_s * self.wheel_radius_m / self.cell_size_m
    }
}

impl Default for RobotParams {
    fn default() -> Self {
        RobotParams {
            wheel_radius_m: 0.021,
            axle_track_m: 0.10,
            body_radius_m: 0.058,
            max_wheel_speed_rad_s: 20.0,
            max_wheel_accel_rad_s2: 200.0,
            motor_lag_s: 0.02,
            ticks_per_rev: 6.0 * f64::from(Self::DEFAULT_POLE_PAIRS),
            cell_size_m: 0.16,
        }
    }
}

/// How the simulator's clock advances (`[sim] clock`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ClockMode {
    /// Advance a control period only when every live agent has sent its command for it, so
    /// a run is deterministic for a given seed.
    #[default]
    Lockstep,
    /// Follow the wall clock; late commands are simply late, as on hardware.
    Realtime,
}

impl ClockMode {
    /// The name used in scenario files, on the command line (`--mode`) and in the consensus
    /// log's run header: `"lockstep"` or `"realtime"`.
    pub fn name(self) -> &'static str {
        match self {
            ClockMode::Lockstep => "lockstep",
            ClockMode::Realtime => "realtime",
        }
    }
}

impl fmt::Display for ClockMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A clock mode that could not be parsed.
#[derive(Clone, PartialEq, Eq, Debug, thiserror::Error)]
pub enum ClockModeError {
    /// Neither `lockstep` nor `realtime`.
    #[error("unknown mode {name:?}: expected lockstep or realtime")]
    Unknown {
        /// The text as given.
        name: String,
    },
}

impl FromStr for ClockMode {
    type Err = ClockModeError;

    /// Accepts exactly the names [`ClockMode::name`] prints.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "lockstep" => Ok(ClockMode::Lockstep),
            "realtime" => Ok(ClockMode::Realtime),
            other => Err(ClockModeError::Unknown { name: other.into() }),
        }
    }
}

/// Physics stepper parameters (`[sim]`).
#[derive(Clone, PartialEq, Debug, Serialize)]
pub struct SimParams {
    /// Physics step in milliseconds.
    pub step_ms: u32,
    /// Odometry (Hall tick) publication rate in Hz; at most one message per step.
    pub odometry_hz: u32,
    /// Clock mode.
    pub clock: ClockMode,
    /// Seed of every random choice of the run (slip noise, generated agents).
    pub seed: u64,
    /// Standard deviation of relative wheel slip (0 = no slip).
    pub slip_std: f64,
    /// Motor watchdog: wheels brake when the last command is older than this.
    pub watchdog_ms: u32,
    /// How long a drawn wheel-slip factor holds, in seconds. Slip is redrawn on this fixed
    /// time grid (rounded to whole steps, at least one), not every physics step, so that
    /// `slip_std` means the same for any step length.
    pub slip_hold_s: f64,
    /// Lockstep only: how long the simulator waits for a live robot's missing wheel command
    /// before counting that robot as down (it then brakes until it sends again). 0 = wait
    /// indefinitely; a robot is then counted down only when its agent's process dies or
    /// leaves (peer-death events), and a positive value is a fallback for agents that hang.
    pub lockstep_deadline_ms: u32,
    /// What moves the robots: HNAV's own physics stepper, or robots outside HNAV reached
    /// through ROS 2.
    pub kind: SimKind,
}

/// What moves a run's robots (`[sim] kind`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SimKind {
    /// `hnav-sim`: HNAV's differential-drive physics, Hall ticks and ground truth.
    #[default]
    Hnav,
    /// Robots outside HNAV (Gazebo, Webots, real robots) through ROS 2: `hnav-ros2 --robots`
    /// takes the sim's place, sends each agent's wheel commands out as `cmd_vel` and turns
    /// the robots' `joint_states` (or `odom`) into odometry. Realtime only; the world is the
    /// outside's, so no `[sensing]` and no `[[events]]`.
    Ros2,
}

impl SimKind {
    /// The name in scenario files: `"hnav"` or `"ros2"`.
    pub fn name(self) -> &'static str {
        match self {
            SimKind::Hnav => "hnav",
            SimKind::Ros2 => "ros2",
        }
    }
}

impl Default for SimParams {
    fn default() -> Self {
        SimParams {
            step_ms: 1,
            odometry_hz: 100,
            clock: ClockMode::Lockstep,
            seed: 0,
            slip_std: 0.0,
            watchdog_ms: 100,
            slip_hold_s: 0.010,
            lockstep_deadline_ms: 0,
            kind: SimKind::Hnav,
        }
    }
}

impl SimParams {
    /// Physics steps in one control period (one odometry period, `1 / odometry_hz`), rounded
    /// to whole steps and at least one: what the sim steps between two odometry readings.
    pub fn steps_per_control_period(&self) -> u64 {
        let step_s = f64::from(self.step_ms) * 1e-3;
        let period_s = 1.0 / f64::from(self.odometry_hz.max(1));
        ((period_s / step_s).round() as u64).max(1)
    }

    /// The control period in seconds of simulated time: one decision round in lockstep.
    pub fn control_period_s(&self) -> f64 {
        self.steps_per_control_period() as f64 * f64::from(self.step_ms) * 1e-3
    }

    /// How many lockstep rounds `seconds` of simulated time hold (rounded up, at least one):
    /// the round after which a lockstep run with that time limit ends.
    pub fn rounds_in(&self, seconds: f64) -> u64 {
        // The epsilon keeps 1.5 s of 10 ms periods at 150 rounds, not 151 from a rounding
        // error of the division.
        ((seconds / self.control_period_s() - 1e-9).ceil() as u64).max(1)
    }
}

/// When the consensus log is flushed to disk (`[coordinator] fsync`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FsyncPolicy {
    /// fsync every record before its commit is published (durable, the default).
    #[default]
    EveryRecord,
    /// fsync groups of records; a crash may lose the last few.
    Batched,
    /// Never fsync (benchmarks only).
    None,
}

/// The rules of the decision round (`[coordinator] rules`).
///
/// The default is [`Rules::Lacam`], the only rules measured to bring every robot home on the
/// MAPF benchmark at every size (`docs/explanation/mapf-benchmark.md`); the seeds' reproductions name
/// [`Rules::Dissertation`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Rules {
    /// The dissertation's conflict types (a)-(d) with priority `1 / speed` and hybrid
    /// replanning: the reproduction mode.
    Dissertation,
    /// Priority inheritance with backtracking (PIBT, Okumura et al.): the coordinator may move
    /// an agent out of a higher-priority agent's way, and priorities rise with waiting.
    Pibt,
    /// PIBT made complete: the coordinator plans every robot's moves at once with LaCAM
    /// (Okumura, AAAI 2023) and executes the plan as an action dependency graph, falling back
    /// to online PIBT when a search fails. The default.
    #[default]
    Lacam,
}

impl Rules {
    /// Every set of rules, in the order of their codes.
    pub const ALL: [Rules; 3] = [Rules::Dissertation, Rules::Pibt, Rules::Lacam];

    /// The name used in scenario files: `"dissertation"`, `"pibt"` or `"lacam"`.
    pub fn name(self) -> &'static str {
        match self {
            Rules::Dissertation => "dissertation",
            Rules::Pibt => "pibt",
            Rules::Lacam => "lacam",
        }
    }
}

/// Which planner drives an agent (`[[agents]] planner`). Every planner runs under the same
/// coordinator, conflict rules and consensus log; they differ in how the agent picks its
/// candidate step.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Planner {
    /// The dissertation's Hopfield neural map climbed by the path constructor.
    #[default]
    Hnav,
    /// Seed 003's particle swarm with virtual obstacles; the robot follows the swarm's route.
    Pso,
    /// Seed 004's genetic algorithm for the route and its fuzzy controller on the wheels.
    GaFuzzy,
}

impl Planner {
    /// Every planner, in the order of their wire codes.
    pub const ALL: [Planner; 3] = [Planner::Hnav, Planner::Pso, Planner::GaFuzzy];

    /// The name used in scenario files: `"hnav"`, `"pso"` or `"ga-fuzzy"`.
    pub fn name(self) -> &'static str {
        match self {
            Planner::Hnav => "hnav",
            Planner::Pso => "pso",
            Planner::GaFuzzy => "ga-fuzzy",
        }
    }
}

/// Coordinator parameters (`[coordinator]`).
#[derive(Clone, PartialEq, Debug, Serialize)]
pub struct CoordinatorParams {
    /// How long a round waits for candidates; missing agents count as standing still.
    pub round_deadline_ms: u32,
    /// Log durability policy.
    pub fsync: FsyncPolicy,
    /// Rounds an agent may stay blocked before the coordinator replans it globally.
    pub replan_after_rounds: u32,
    /// Limit of the whole run in seconds: wall-clock in realtime; in lockstep seconds of
    /// simulated time, counted in rounds ([`SimParams::rounds_in`]).
    pub time_limit_s: f64,
    /// The rules of the decision round.
    pub rules: Rules,
    /// Coordinator replicas agreeing on every round by Raft: 1 (no replication, a single
    /// coordinator and its log), 3 or 5. Not in the scenario hash: replicas decide the same
    /// rounds as one coordinator.
    pub replicas: u32,
    /// The Raft leader's heartbeat interval, the replicas' tick.
    pub raft_heartbeat_ms: u32,
    /// Time without a leader's heartbeat after which a follower stands for election (Raft
    /// randomises it in `[election_ms, 2 * election_ms)`); a multiple of the heartbeat.
    pub election_ms: u32,
    /// Committed Raft entries after which a replica takes a snapshot of the applied state
    /// and compacts its log behind it; 0 never. Not in the scenario hash: it changes what a
    /// replica keeps on disk, not what is decided.
    pub snapshot_entries: u64,
}

impl CoordinatorParams {
    /// The cluster sizes `replicas` may take: 1 (none), or an odd number of voters that
    /// survives losing one (3) or two (5).
    pub const REPLICAS: [u32; 3] = [1, 3, 5];

    /// Raft's election timeout in ticks of `raft_heartbeat_ms`.
    pub fn election_ticks(&self) -> usize {
        (self.election_ms / self.raft_heartbeat_ms.max(1)) as usize
    }
}

impl Default for CoordinatorParams {
    fn default() -> Self {
        CoordinatorParams {
            round_deadline_ms: 50,
            fsync: FsyncPolicy::EveryRecord,
            replan_after_rounds: 3,
            time_limit_s: 120.0,
            rules: Rules::Lacam,
            replicas: 1,
            // Suited to one host: a lost leader is replaced within 0.5 to 1 s, and a replica
            // stalled by a busy 2-core machine for less than 0.5 s deposes nobody.
            raft_heartbeat_ms: 50,
            election_ms: 500,
            // About 100 s of rounds at the default 10 ms period: a short run never compacts.
            snapshot_entries: 10_000,
        }
    }
}

/// Run parameters of the supervisor (`[run]`). They decide whether a run gets going, not what
/// it does, so the scenario hash leaves them out.
#[derive(Clone, Copy, PartialEq, Debug, Serialize)]
pub struct RunParams {
    /// How long the processes get to come up, in seconds; `None` for the default that scales
    /// with the map ([`default_startup_timeout_s`]).
    pub startup_timeout_s: Option<f64>,
    /// Robots hosted by one `hnav-agent` process (`agents_per_process`, default 1: one
    /// process per robot, the dissertation's model). Robots `k*K .. (k+1)*K` share process
    /// `k`: one node, one waiter, one commit subscriber; each keeps its own topics, state
    /// and checkpoint. It changes how the run is laid out in processes, not what it decides.
    pub agents_per_process: u32,
}

impl Default for RunParams {
    fn default() -> Self {
        RunParams {
            startup_timeout_s: None,
            agents_per_process: 1,
        }
    }
}

impl RunParams {
    /// Largest `startup_timeout_s` accepted: one day.
    pub const MAX_STARTUP_TIMEOUT_S: f64 = 86_400.0;
    /// Largest `agents_per_process` accepted: the robots one process's node can hold ports
    /// for (each robot opens about ten services; iceoryx2's node has no hard cap, but a
    /// process of thousands of robots is one failure domain too many).
    pub const MAX_AGENTS_PER_PROCESS: u32 = 256;

    /// The agent processes of a run of `agents` robots: each one's first robot and how many
    /// it hosts, in order.
    pub fn agent_processes(&self, agents: usize) -> impl Iterator<Item = (u32, u32)> {
        let k = self.agents_per_process.max(1);
        let n = u32::try_from(agents).unwrap_or(u32::MAX);
        (0..n.div_ceil(k)).map(move |p| (p * k, k.min(n - p * k)))
    }

    /// The first robot of the process that hosts robot `agent`.
    pub fn process_of(&self, agent: u32) -> u32 {
        let k = self.agents_per_process.max(1);
        agent - agent % k
    }
}

/// Neuron updates per second one core is assumed to manage while an agent builds its neural
/// map toward its goal: half of what `hnav-agent` (the workspace's default build) measured on
/// the shared 2-core VM, 2.0-2.3e7 on empty 512, 1024 and 2048 cells square maps with the goal
/// in a corner (2.0 s, 17.3 s and 145 s), for margin against a busier machine.
const ASSUMED_UPDATES_PER_S: f64 = 1e7;

/// The start-up timeout of a run of `agents` agents on a `width` x `height` map with `cores`
/// cores, in seconds: 60 s for spawning and loading, plus the time the agents need to build
/// their neural maps at an assumed 1e7 neuron updates per second per core, capped at
/// [`RunParams::MAX_STARTUP_TIMEOUT_S`].
///
/// A build toward a goal in a corner sweeps about `max(width, height)` times over a box that
/// grows to the whole map, about `width * height * max(width, height) / 3` updates; the agents
/// build at once, `ceil(agents / cores)` to a core.
pub fn default_startup_timeout_s(width: u32, height: u32, agents: usize, cores: usize) -> f64 {
    let (w, h) = (f64::from(width), f64::from(height));
    let updates = w * h * w.max(h) / 3.0;
    let per_core = agents.max(1).div_ceil(cores.max(1)) as f64;
    (60.0 + updates * per_core / ASSUMED_UPDATES_PER_S).min(RunParams::MAX_STARTUP_TIMEOUT_S)
}

/// When the supervisor restarts a process of a role.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RestartPolicy {
    /// Never restart.
    Never,
    /// Restart after an abnormal exit (non-zero status or a signal).
    #[default]
    OnFailure,
    /// Restart after any exit before the run ends.
    Always,
}

/// Restart rule of one role.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Serialize)]
pub struct RestartRule {
    /// When to restart.
    pub policy: RestartPolicy,
    /// Restarts allowed over the whole run.
    pub max_restarts: u32,
    /// Delay before a restart in milliseconds.
    pub backoff_ms: u64,
}

impl RestartRule {
    /// `policy` with the default cap (3) and backoff (100 ms).
    pub const fn with_policy(policy: RestartPolicy) -> Self {
        RestartRule {
            policy,
            max_restarts: 3,
            backoff_ms: 100,
        }
    }
}

/// Restart rules per role (`[restart]`). Every role is restarted on failure by default: an
/// agent resumes from its checkpoint, the coordinator from the consensus log, the simulator
/// from its ground-truth checkpoint (`DIR/sim.ckpt.{0,1}`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Serialize)]
pub struct RestartConfig {
    /// Rule for agent processes.
    pub agent: RestartRule,
    /// Rule for the coordinator.
    pub coordinator: RestartRule,
    /// Rule for the simulator.
    pub sim: RestartRule,
    /// What an agent gone for good (not restarted) does to the run.
    pub on_give_up: GiveUpAction,
}

/// What happens to a run when an agent exits and is not restarted (`[restart] on_give_up`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GiveUpAction {
    /// Its robot stands for the rest of the run (an obstacle to the others, its goal not
    /// reached); the run ends once every other robot is at its goal or cannot reach it.
    #[default]
    Stand,
    /// The run stops at once, as one that cannot go on.
    Stop,
}

impl Default for RestartConfig {
    fn default() -> Self {
        RestartConfig {
            agent: RestartRule::with_policy(RestartPolicy::OnFailure),
            coordinator: RestartRule::with_policy(RestartPolicy::OnFailure),
            sim: RestartRule::with_policy(RestartPolicy::OnFailure),
            on_give_up: GiveUpAction::Stand,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_consistent() {
        let r = RobotParams::default();
        assert_eq!(r.ticks_per_rev, 42.0);
        assert!(
            2.0 * r.body_radius_m <= r.cell_size_m,
            "default body fits in a cell"
        );
        // 20 rad/s * 21 mm / 16 cm.
        assert!((r.max_speed_cells_s() - 2.625).abs() < 1e-9);
        assert_eq!(
            RestartConfig::default().sim.policy,
            RestartPolicy::OnFailure
        );
        assert_eq!(SimParams::default().clock, ClockMode::Lockstep);
        assert_eq!(CoordinatorParams::default().fsync, FsyncPolicy::EveryRecord);
    }

    /// The lockstep time limit in rounds: 10 ms periods by default, rounded up, at least one.
    #[test]
    fn a_time_limit_counts_control_periods() {
        let sim = SimParams::default();
        assert_eq!(sim.steps_per_control_period(), 10);
        assert!((sim.control_period_s() - 0.01).abs() < 1e-12);
        assert_eq!(sim.rounds_in(1.5), 150);
        assert_eq!(sim.rounds_in(300.0), 30_000);
        assert_eq!(sim.rounds_in(0.015), 2);
        assert_eq!(sim.rounds_in(1e-6), 1);
        let coarse = SimParams {
            step_ms: 4,
            odometry_hz: 30,
            ..sim
        };
        // 33.3 ms rounds to 8 steps of 4 ms: 32 ms periods.
        assert_eq!(coarse.steps_per_control_period(), 8);
        assert_eq!(coarse.rounds_in(1.0), 32);
    }

    #[test]
    fn the_default_startup_timeout_grows_with_the_map_and_the_agents_per_core() {
        // A small map costs nothing beyond the base.
        assert!((default_startup_timeout_s(32, 32, 4, 2) - 60.0).abs() < 0.01);
        // 1024 x 1024, 2 agents on 2 cores: 3.6e8 updates, 36 s on top (17.3 s measured).
        let one = default_startup_timeout_s(1024, 1024, 2, 2);
        assert!((one - 95.79).abs() < 0.01, "{one}");
        // Twice the agents per core, twice the build time; the long side counts.
        let two = default_startup_timeout_s(1024, 1024, 4, 2);
        assert!((two - 60.0 - 2.0 * (one - 60.0)).abs() < 1e-9, "{two}");
        assert_eq!(
            default_startup_timeout_s(1024, 16, 1, 1),
            default_startup_timeout_s(16, 1024, 1, 1)
        );
        // 5000 x 5000 (the map that did not come up within 60 s): 70 minutes of building.
        let big = default_startup_timeout_s(5000, 5000, 1, 2);
        assert!((big - 4226.67).abs() < 0.01, "{big}");
        // Zero cores or agents count as one; the cap holds for absurd maps.
        assert_eq!(
            default_startup_timeout_s(64, 64, 0, 0),
            default_startup_timeout_s(64, 64, 1, 1)
        );
        assert_eq!(
            default_startup_timeout_s(u32::MAX, u32::MAX, 1000, 1),
            RunParams::MAX_STARTUP_TIMEOUT_S
        );
    }

    #[test]
    fn clock_modes_parse_what_they_print() {
        for m in [ClockMode::Lockstep, ClockMode::Realtime] {
            assert_eq!(m.to_string().parse::<ClockMode>(), Ok(m));
        }
        let e = "fast".parse::<ClockMode>().unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown mode \"fast\": expected lockstep or realtime"
        );
    }
}
