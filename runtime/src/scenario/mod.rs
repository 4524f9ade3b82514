//! Scenarios: the TOML description of a run, validated with file/line errors.
//!
//! A walk-through of the format is `docs/tutorials/write-a-scenario.md`; every key, what it
//! decides and its default, `docs/reference/scenario.md`. [`KEYS`] lists every key, and a
//! test holds the block below, that page and the tutorial to it.
//!
//! # Format
//!
//! ```toml
//! name = "demo"                        # required; names the output directory
//! allow_unreachable = false            # optional, top level: run even if a goal cannot be
//!                                      # reached from its start (default: refuse the scenario)
//!
//! [map]                                # exactly one of `file` and `rows`
//! file = "../maps/random-32-32-10.map" # MovingAI .map, relative to the scenario file
//! # rows = ["....", ".@@.", "....", "...."]   # or inline MovingAI rows (. G S passable, @ O T W blocked)
//! corner_cutting = false               # may a diagonal pass a blocked corner? default false
//!
//! [robot]                              # all optional; s-bot-like defaults shown
//! wheel_radius_m = 0.021
//! axle_track_m = 0.10
//! body_radius_m = 0.058                # the body must fit in a cell (2 r <= cell_size_m)
//! max_wheel_speed_rad_s = 20.0
//! max_wheel_accel_rad_s2 = 200.0
//! motor_lag_s = 0.02                   # first-order motor time constant, >= 0
//! pole_pairs = 7                       # ticks_per_rev = 6 * pole_pairs * gear_ratio = 42 ...
//! gear_ratio = 1.0
//! # ticks_per_rev = 42                 # ... or give it directly (not together with the two above)
//! cell_size_m = 0.16
//!
//! [sim]
//! step_ms = 1                          # physics step
//! odometry_hz = 100                    # Hall tick messages; at most one per step
//! clock = "lockstep"                   # or "realtime"
//! seed = 0
//! slip_std = 0.0                       # relative wheel slip, in [0, 0.5)
//! slip_hold_s = 0.01                   # > 0; a drawn slip factor holds this long
//! watchdog_ms = 100                    # wheels brake when commands are older
//! lockstep_deadline_ms = 0             # lockstep: how long to wait for a missing wheel command
//!                                      # before that robot counts as down and brakes;
//!                                      # 0 = wait indefinitely (down only when its agent
//!                                      # process dies or leaves), > 0 = fallback for hung agents
//! kind = "hnav"                        # or "ros2": robots outside HNAV, through ROS 2
//!
//! [coordinator]
//! round_deadline_ms = 50
//! fsync = "every-record"               # or "batched", "none"
//! replan_after_rounds = 3
//! time_limit_s = 120.0                 # lockstep: simulated time, in rounds; realtime: wall clock
//! rules = "lacam"                      # or "dissertation" (the seeds' reproductions), "pibt": docs/explanation/conflict-rules.md
//! replicas = 1                         # 1, 3 or 5 coordinator replicas agreeing by Raft; not in the hash
//! raft_heartbeat_ms = 50               # the replicas' tick
//! election_ms = 500                    # at least 3 heartbeats; Raft randomises it up to twice that
//! snapshot_entries = 10000             # a replica compacts its log after this many entries; 0 never
//!
//! [restart]                            # per role; default for each role as shown
//! agent = { policy = "on-failure", max_restarts = 3, backoff_ms = 100 }
//! coordinator = { policy = "on-failure" }
//! sim = { policy = "on-failure" }      # policies: "never", "on-failure", "always"
//! on_give_up = "stand"                 # an agent not restarted: its robot stands and the run
//!                                      # ends once the others are settled; "stop": at once
//!
//! [run]
//! startup_timeout_s = 60.0             # how long the processes get to come up; default
//!                                      # 60 s plus the agents' neural-map builds, scaled
//!                                      # with the map (params::default_startup_timeout_s)
//! agents_per_process = 1               # robots per hnav-agent process, in [1, 256]; robots
//!                                      # k*K..(k+1)*K share process k (default 1: one each)
//!
//! [health]                             # hang detection (docs/explanation/hangs.md); not in the hash
//! heartbeat_ms = 50                    # every process beats this often, in [1, 60000]
//! agent_hang_ms = 1000                 # silence before a process is declared hung, in
//! coordinator_hang_ms = 2000           # [2 * heartbeat_ms, 3600000]; the agents' default
//! sim_hang_ms = 1000                   # grows with the map (health::default_agent_hang_ms)
//!
//! [record]                             # the run's recording (docs/reference/logs-and-
//! trajectory_hz = 20                   # recordings.md); not in the hash. Pose samples per
//! max_mb = 64                          # simulated second (0: every truth message), the
//! maps = true                          # cap of each file in MiB, neural-map snapshots
//!
//! [localisation]                       # the sim's map-based pose fix that bounds the agents'
//! rate_hz = 1.0                        # dead-reckoning drift; fixes per simulated second
//! std_m = 0.002                        # (0 = none, at most odometry_hz) and the noise of a
//! std_deg = 0.5                        # fix's position (m) and heading (degrees)
//!
//! [[agents]]                           # one table per robot, numbered from 0
//! start = [0, 0]                       # [x, y]: x = column, y = row, origin top-left
//! goal = [31, 31]
//! speed = 1.0                          # cells/s, > 0, default 1.0, within the wheels' limit
//! priority = 2.0                       # optional, > 0; default 1 / speed
//! start_heading_deg = 90.0             # optional, in [-360, 360]; default 0 = facing +x (towards
//!                                      # larger columns); 90 faces +y (towards larger rows)
//! planner = "hnav"                     # or "pso" (seed 003) or "ga-fuzzy" (seed 004):
//!                                      # docs/explanation/conflict-rules.md
//!
//! [[faults]]                           # optional fault plan (more on the command line:
//!                                      # `hnav run --kill/--term/--freeze`, [`fault_arg`])
//! at_round = 10                        # exactly one of at_round and at_s (seconds after
//!                                      # Start; in lockstep the round of that simulated time)
//! # at_s = 1.5                         # ... or the time instead of the round
//! action = "kill"                      # or "freeze": SIGSTOP, then SIGCONT after for_s
//! role = "agent"                       # or "coordinator", "sim"
//! index = 0                            # agent number (always with role = "agent"); with role =
//!                                      # "coordinator", a replica, 1 to replicas
//! signal = "KILL"                      # kill only: or "TERM"; default "KILL"
//! # for_s = 0.3                        # freeze only: seconds stopped; omitted = never continued
//!
//! [tasks]                              # optional: goals that keep coming (lifelong; [`tasks`]);
//! stream = "seeded"                    # the run then ends by time_limit_s. Or "list":
//! seed = 7                             # seeded only; default the [sim] seed
//! # [[tasks.goals]]                    # list only (`goals`): a robot's goals after its goal,
//! # agent = 0                          # cycled; a robot without an entry keeps its one goal
//! # cells = [[5, 3], [0, 0]]
//!
//! [[events]]                           # optional: the world changes ([`events`]); one
//! at_round = 120                       # change each, at a round or at_s
//! close = [[5, 3]]                     # cells become obstacles; or one of:
//! # close_rect = [[4, 2], [5, 3]]      # a rectangle, corners included
//! # open = [[5, 3]]                    # free again (or a wall of the map opened);
//! # open_rect = [[4, 2], [5, 3]]       # open_rect likewise
//! # mover = "forklift"                 # a moving obstacle (a person, a forklift) along
//! # path = [[1, 1], [1, 8]]            # legs along rows or columns, speed in cells/s,
//! # speed = 0.5                        # back and forth with repeat = true
//! # repeat = true
//! # yields = true                      # waits for robots in its way (default)
//!
//! [sensing]                            # optional: robots sense the world ([`sensing`]);
//! range = 5                            # cells seen in line of sight, in [1, 15]
//! known_map = true                     # false: only the walls seen so far are known
//! repair = "auto"                      # neural-map repair: "auto", "partial", "rebuild"
//! all_knowing = false                  # true: also told every close/open as it happens
//!
//! [ros2]                               # optional: the run as ROS 2 topics over rmw_zenoh
//! domain_id = 0                        # ([`ros2`], docs/reference/ros2.md), as with `hnav
//! namespace = "fleet"                  # run --ros2`; the robots' topics' prefix; the Zenoh
//! router = "tcp/localhost:7447"        # router (started by `hnav run` if none answers)
//! odometry = "joint_states"            # kind = "ros2": or "odom", the robots' motion
//! wheel_joints = ["left_wheel_joint", "right_wheel_joint"]  # kind = "ros2"
//! silence_s = 1.0                      # kind = "ros2": a robot not heard this long is down
//! ```
//!
//! Unknown keys are errors (a typo must not silently fall back to a default). Every semantic
//! error names the file and line and has its own [`ScenarioError`] variant: a speed that is
//! not positive, a start or goal outside the map or on an obstacle, two agents sharing a start
//! or a goal, no agents, more than [`MAX_AGENTS`](crate::msg::MAX_AGENTS) agents, a goal that
//! cannot be reached from its start (unless `allow_unreachable = true`), both or neither of `map.file`/`map.rows`, a fault naming a missing
//! agent, and malformed map files (wrapping [`crate::grid::GridError`]).
//!
//! # Example
//!
//! ```
//! use hnav_runtime::scenario::Scenario;
//! use hnav_runtime::grid::Cell;
//!
//! let text = r#"
//! name = "tiny"
//! [map]
//! rows = ["....",
//!         ".@@.",
//!         "...."]
//! [[agents]]
//! start = [0, 0]
//! goal = [3, 2]
//! [[agents]]
//! start = [3, 0]
//! goal = [0, 2]
//! speed = 0.5
//! "#;
//! let s = Scenario::from_str(text, "<inline>", std::path::Path::new(".")).unwrap();
//! assert_eq!(s.agents.len(), 2);
//! assert_eq!(s.agents[1].goal, Cell::new(0, 2));
//! assert_eq!(s.agents[1].effective_priority(), 2.0);
//! assert_eq!(s.map.grid.blocked_count(), 2);
//!
//! let bad = text.replace("speed = 0.5", "speed = -1");
//! let err = Scenario::from_str(&bad, "demo.toml", std::path::Path::new(".")).unwrap_err();
//! assert_eq!(err.to_string(), "demo.toml:13: agent 1 speed must be a positive number of cells/s, got -1");
//! ```

mod agents;
mod build;
mod build_params;
pub mod error;
pub mod events;
pub mod fault_arg;
mod hash;
pub mod health;
pub(crate) mod lines;
pub mod localisation;
pub mod params;
mod raw;
pub mod record;
pub mod report;
pub mod ros2;
pub mod sensing;
pub mod tasks;
mod validate;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use error::{Loc, ScenarioError};
pub use events::{EventSpec, MoverSpec, WorldChange};
pub use health::HealthParams;
pub use localisation::LocalisationParams;
pub use params::{
    default_startup_timeout_s, ClockMode, ClockModeError, CoordinatorParams, FsyncPolicy,
    GiveUpAction, Planner, RestartConfig, RestartPolicy, RestartRule, RobotParams, Rules,
    RunParams, SimKind, SimParams,
};
pub use raw::KEYS;
pub use record::RecordParams;
pub use report::{default_out_dir, ScenarioReport};
pub use ros2::{OdometrySource, Ros2Params};
pub use sensing::{RepairRule, SensingParams};
pub use tasks::{StreamKind, TaskStream, TasksSpec};

use crate::grid::{Cell, CornerCutting, Grid};

/// The map of a scenario.
#[derive(Clone, PartialEq, Debug)]
pub struct MapSpec {
    /// The occupancy grid.
    pub grid: Grid,
    /// The map file (resolved against the scenario's directory), `None` for inline rows.
    pub file: Option<PathBuf>,
    /// The diagonal rule for planning and conflict checks.
    pub corner_cutting: CornerCutting,
}

/// One robot's task.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct AgentSpec {
    /// Start cell.
    pub start: Cell,
    /// Goal cell.
    pub goal: Cell,
    /// Cruise speed in cells/s.
    pub speed: f64,
    /// Conflict priority if given (higher wins); see [`AgentSpec::effective_priority`].
    pub priority: Option<f64>,
    /// Heading of the robot at its start cell's centre, degrees counter-clockwise from the
    /// sim frame's +x axis (towards larger columns); 90 faces +y, towards larger rows (down
    /// the map as printed, since row 0 is the top). Default 0; within [-360, 360].
    pub start_heading_deg: f64,
    /// The planner that drives this agent; default [`Planner::Hnav`].
    pub planner: Planner,
}

impl AgentSpec {
    /// Speed of agents that do not give one.
    pub const DEFAULT_SPEED: f64 = 1.0;

    /// Largest `|start_heading_deg|` accepted.
    pub const MAX_START_HEADING_DEG: f64 = 360.0;

    /// [`AgentSpec::start_heading_deg`] in radians, as the simulator uses it.
    pub fn start_heading_rad(&self) -> f64 {
        self.start_heading_deg.to_radians()
    }

    /// The priority used in conflicts: the given one, else the dissertation's `P = 1 / speed`.
    pub fn effective_priority(&self) -> f64 {
        self.priority.unwrap_or(1.0 / self.speed)
    }
}

/// What a fault does.
#[derive(Clone, Copy, PartialEq, Debug)]
pub enum FaultAction {
    /// Send the process this signal.
    Kill(FaultSignal),
    /// SIGSTOP the process, then SIGCONT it after `for_s` seconds of wall-clock time
    /// (`None`: never continued; hang detection is then what ends the freeze).
    Freeze {
        /// How long it stays stopped.
        for_s: Option<f64>,
    },
}

/// When a fault fires.
#[derive(Clone, Copy, PartialEq, Debug)]
pub enum FaultTime {
    /// Once this decision round is committed (in lockstep exactly then, the run holding
    /// there until the fault is done).
    Round(u64),
    /// This long after `Start`: in realtime on the supervisor's wall clock; in lockstep at
    /// the round that much simulated time takes ([`SimParams::rounds_in`]), so that it is
    /// as exact and reproducible as a round.
    Seconds(f64),
}

/// Which process a fault hits.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum FaultTarget {
    /// The agent with this number.
    Agent(usize),
    /// The coordinator; with replicas, the Raft leader when the fault fires.
    Coordinator,
    /// Coordinator replica `id` (1-based) of a run with replicas, leader or not.
    Replica(u32),
    /// The simulator.
    Sim,
}

/// The signal a kill fault sends.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, Serialize, Deserialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum FaultSignal {
    /// SIGKILL: no chance to clean up (the interesting case).
    #[default]
    Kill,
    /// SIGTERM: a polite stop.
    Term,
}

/// One planned fault, from the scenario's `[[faults]]` or the command line
/// ([`fault_arg`]).
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct FaultSpec {
    /// When it fires.
    pub at: FaultTime,
    /// What it does.
    pub action: FaultAction,
    /// To whom.
    pub target: FaultTarget,
}

impl FaultSpec {
    /// The round a lockstep run fires it at: its round, or the round its seconds of
    /// simulated time take.
    pub fn lockstep_round(&self, sim: &SimParams) -> u64 {
        match self.at {
            FaultTime::Round(r) => r,
            FaultTime::Seconds(s) => sim.rounds_in(s),
        }
    }
}

/// A validated scenario. See the [module docs](self) for the file format.
///
/// Fields are public for convenience; after changing them in code, call
/// [`Scenario::validate`] to re-check the agent and fault rules.
#[derive(Clone, PartialEq, Debug)]
pub struct Scenario {
    /// The scenario's name.
    pub name: String,
    /// The file it was read from (as given), or `"<inline>"`.
    pub source_name: String,
    /// The map and its corner-cutting rule.
    pub map: MapSpec,
    /// Robot geometry and limits.
    pub robot: RobotParams,
    /// Simulator parameters.
    pub sim: SimParams,
    /// Coordinator parameters.
    pub coordinator: CoordinatorParams,
    /// Restart rules per role.
    pub restart: RestartConfig,
    /// The supervisor's run parameters.
    pub run: RunParams,
    /// Heartbeats and hang deadlines (`[health]`).
    pub health: HealthParams,
    /// What the recorder keeps (`[record]`).
    pub record: RecordParams,
    /// The sim's localisation fix that bounds the agents' drift (`[localisation]`).
    pub localisation: LocalisationParams,
    /// The robots, numbered from 0.
    pub agents: Vec<AgentSpec>,
    /// The fault plan.
    pub faults: Vec<FaultSpec>,
    /// Whether a goal that cannot be reached from its start is accepted (the agent then
    /// reports it in the run) instead of refused ([`ScenarioError::UnreachableGoal`]).
    pub allow_unreachable: bool,
    /// Goals that keep coming (`[tasks]`): a lifelong run, ended by time; `None` for a run
    /// that ends once every robot stands on its goal.
    pub tasks: Option<TasksSpec>,
    /// How the world changes during the run (`[[events]]`), in time order.
    pub events: Vec<EventSpec>,
    /// What the robots sense of the world after `Start` (`[sensing]`); `None`: nothing, they
    /// plan on the scenario's map.
    pub sensing: Option<SensingParams>,
    /// How the run is published as ROS 2 topics (`[ros2]`); `None`: only with `hnav run
    /// --ros2`, with the defaults.
    pub ros2: Option<Ros2Params>,
}

impl Scenario {
    /// Reads and validates a scenario file; a map `file` is resolved against its directory.
    pub fn load(path: impl AsRef<Path>) -> Result<Scenario, ScenarioError> {
        let path = path.as_ref();
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ScenarioError::Io {
            source_name: name.clone(),
            message: e.to_string(),
        })?;
        let base = path.parent().unwrap_or_else(|| Path::new("."));
        Scenario::from_str(&text, &name, base)
    }

    /// Parses and validates scenario text. `source_name` is used in errors; a map `file` is
    /// resolved against `base_dir`.
    pub fn from_str(
        text: &str,
        source_name: &str,
        base_dir: &Path,
    ) -> Result<Scenario, ScenarioError> {
        build::parse(text, source_name, base_dir)
    }

    /// Re-checks the agent and fault rules (errors carry no line numbers).
    pub fn validate(&self) -> Result<(), ScenarioError> {
        validate::revalidate(self)
    }

    /// The moving obstacles of `[[events]]`, in the order they appear (the sim's mover
    /// index: the `movers` topic, a contact with mover `k`).
    pub fn movers(&self) -> impl Iterator<Item = &MoverSpec> + '_ {
        self.events.iter().filter_map(|e| match &e.change {
            WorldChange::Mover(m) => Some(m),
            _ => None,
        })
    }

    /// A stable FNV-1a 64 hash of the scenario's content, for the consensus log's run header.
    /// Covers the map cells, corner cutting, every parameter section, the agents and the
    /// faults; not the name or file paths. See [`Fnv1a64`](crate::hash::Fnv1a64) and the
    /// `hash` module source for the exact encoding.
    pub fn scenario_hash(&self) -> u64 {
        hash::scenario_hash(self)
    }

    /// How long the run's processes get to come up: `[run] startup_timeout_s`, else
    /// [`default_startup_timeout_s`] for this map, these agents and this machine's cores.
    /// The supervisor's start-up handshake and each process's wait for `Start` use it.
    pub fn startup_timeout(&self) -> std::time::Duration {
        let secs = self.run.startup_timeout_s.unwrap_or_else(|| {
            let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
            let g = &self.map.grid;
            default_startup_timeout_s(g.width(), g.height(), self.agents.len(), cores)
        });
        std::time::Duration::from_secs_f64(secs)
    }

    /// How often every process of the run beats (`[health] heartbeat_ms`).
    pub fn heartbeat(&self) -> std::time::Duration {
        self.health.heartbeat()
    }

    /// How long a process of `role` may stay silent before the supervisor declares it hung:
    /// `[health] <role>_hang_ms`, for agents by default growing with the map
    /// ([`health::default_agent_hang_ms`]).
    pub fn hang_deadline(&self, role: crate::msg::Role) -> std::time::Duration {
        let g = &self.map.grid;
        health::hang_deadline(
            &self.health,
            role,
            (g.width(), g.height()),
            self.agents.len(),
        )
    }

    /// A copy with exactly `n` agents: the first `n` if there are enough, otherwise all of
    /// them plus agents with seeded random starts and goals (free, distinct starts, distinct
    /// goals, start != goal, goal reachable under the map's corner-cutting rule; speed 1,
    /// default priority). Same scenario and seed, same agents, on every platform.
    ///
    /// Fails with [`ScenarioError::InvalidParameter`] (`--agents`) for `n == 0`,
    /// [`ScenarioError::FaultAgentOutOfRange`] if a fault targets a dropped agent, and
    /// [`ScenarioError::NotEnoughFreeCells`] if the map cannot hold `n` agents.
    pub fn with_agent_count(&self, n: usize, seed: u64) -> Result<Scenario, ScenarioError> {
        agents::with_agent_count(self, n, seed)
    }
}

#[cfg(test)]
mod test_support;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_events;
#[cfg(test)]
mod tests_faults;
#[cfg(test)]
mod tests_generate;
#[cfg(test)]
mod tests_keys;
#[cfg(test)]
mod tests_run;
