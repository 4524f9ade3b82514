//! Where the view's data comes from: the [`Feed`] trait and what it yields.

use std::path::PathBuf;
use std::time::Instant;

use super::health::HealthRow;
pub use crate::recording::world::{world_steps, WorldStep};
use crate::supervisor::registry::LiveRunError;
use hnav_runtime::grid::Grid;
use hnav_runtime::msg::{CommitView, Lifecycle, MoverPlace, Pose, Progress, TruthView, View};
use hnav_runtime::scenario::{Scenario, ScenarioError};
use hnav_runtime::transport::TransportError;

/// The static picture of a run: what does not change while it runs.
#[derive(Debug, Clone)]
pub struct RunInfo {
    /// The run id.
    pub run_id: String,
    /// `lockstep` or `realtime`.
    pub mode: String,
    /// The conflict rules the run runs (`lacam`, `pibt`, `dissertation`); empty when not
    /// known.
    pub rules: String,
    /// The map.
    pub grid: Grid,
    /// Each agent's start cell (0-based row-major index, as in the messages).
    pub starts: Vec<u32>,
    /// Each agent's goal cell (0-based row-major index).
    pub goals: Vec<u32>,
    /// Side of a cell in metres, to place ground-truth poses.
    pub cell_size_m: f64,
    /// The scenario's closes and opens (`[[events]]`), in time order: the view's map follows
    /// them as the sim's time passes them.
    pub changes: Vec<WorldStep>,
    /// The robots' sensor range, cells (`[sensing] range`), when they sense.
    pub sensor_range: Option<u32>,
}

impl RunInfo {
    /// The picture of `scenario` run as `run_id`.
    pub fn of(run_id: &str, scenario: &Scenario) -> RunInfo {
        let grid = scenario.map.grid.clone();
        // Messages name cells by their 0-based row-major index, not the 1-based cell id.
        let id = |c| u32::try_from(grid.index(c)).unwrap_or(hnav_runtime::msg::NO_CELL);
        RunInfo {
            run_id: run_id.to_string(),
            mode: scenario.sim.clock.to_string(),
            rules: scenario.coordinator.rules.name().to_string(),
            starts: scenario.agents.iter().map(|a| id(a.start)).collect(),
            goals: scenario.agents.iter().map(|a| id(a.goal)).collect(),
            cell_size_m: scenario.robot.cell_size_m,
            changes: world_steps(scenario, &grid),
            sensor_range: scenario.sensing.map(|s| s.range),
            grid,
        }
    }

    /// The cell (0-based row-major index) of a ground-truth pose, if it is on the map.
    pub fn cell_of(&self, pose: &Pose) -> Option<u32> {
        let (x, y) = (
            (pose.x_m / self.cell_size_m).floor(),
            (pose.y_m / self.cell_size_m).floor(),
        );
        let (w, h) = (f64::from(self.grid.width()), f64::from(self.grid.height()));
        (x >= 0.0 && y >= 0.0 && x < w && y < h).then(|| y as u32 * self.grid.width() + x as u32)
    }
}

/// How a run's view came to its end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunEnd {
    /// The coordinator reported every agent at its goal (or unable to reach it).
    AllAtGoal,
    /// The coordinator committed the last round of a lockstep run's time limit.
    TimeLimit,
    /// The supervisor published `Stop` (its own end, a signal, a run that cannot go on).
    Stopped,
    /// The supervisor is gone: the registry no longer lists the run, or its pid died.
    SupervisorGone,
}

impl RunEnd {
    /// In words, for the status line.
    pub fn describe(self) -> &'static str {
        match self {
            RunEnd::AllAtGoal => "every robot at its goal",
            RunEnd::TimeLimit => "time limit reached",
            RunEnd::Stopped => "stopped by the supervisor",
            RunEnd::SupervisorGone => "the supervisor is gone",
        }
    }
}

/// One thing a feed learned. Borrowed: a live feed hands out the payload in shared memory,
/// without a copy.
#[derive(Debug, Clone, Copy)]
pub enum Update<'a> {
    /// Ground truth: every robot's pose, the collisions so far.
    Truth(TruthView<'a>),
    /// One round's decisions.
    Commit(CommitView<'a>),
    /// The coordinator's tally.
    Progress(&'a Progress),
    /// A process came up, went down, was restarted or lost; `Stop`.
    Lifecycle(&'a Lifecycle),
    /// The run's processes now.
    Health(&'a [HealthRow]),
    /// What a robot's range sensor sees now (`[sensing]`).
    View(&'a View),
    /// Where the moving obstacles on the floor are now (a run with movers).
    Movers(&'a [MoverPlace]),
    /// The run is over; nothing follows.
    Ended(RunEnd),
}

/// What [`Feed::wait`] returned for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Waited {
    /// New updates may be there, or the deadline passed: pump.
    Ready,
    /// SIGINT or SIGTERM: the viewer should end.
    Stop,
}

/// A source of what the view shows. See the [module docs](super) for the seam.
pub trait Feed {
    /// The run's static picture, known before any update.
    fn info(&self) -> &RunInfo;

    /// Blocks until updates may be there, `until` passes or the process is asked to stop.
    /// Never busy: a live feed sleeps in its `Waiter`.
    fn wait(&mut self, until: Instant) -> Result<Waited, FeedError>;

    /// Hands every update available now to `apply`, in the order the view should fold them,
    /// without blocking. After it has yielded [`Update::Ended`] it yields nothing more.
    fn pump(&mut self, apply: &mut dyn FnMut(Update<'_>)) -> Result<(), FeedError>;
}

/// Why a feed could not be opened or read.
#[derive(Debug, thiserror::Error)]
pub enum FeedError {
    /// The registry holds no live run.
    #[error("no live run in the run registry {} (`hnav run` starts one)", dir.display())]
    NoRuns {
        /// The registry directory.
        dir: PathBuf,
    },
    /// More than one live run, and none named.
    #[error("{} live runs, name one (`hnav top RUN`): {}", runs.len(), runs.join(", "))]
    SeveralRuns {
        /// `id (dir)` of each.
        runs: Vec<String>,
    },
    /// No live run has this id or directory.
    #[error("no live run `{run}` (neither a run id nor the directory of one) in the run registry {} (`hnav ps` lists the live runs)", dir.display())]
    NotFound {
        /// The argument.
        run: String,
        /// The registry directory.
        dir: PathBuf,
    },
    /// The run named is unknown or dead.
    #[error(transparent)]
    Lookup(#[from] LiveRunError),
    /// The registry entry does not say which scenario the run's processes run.
    #[error("run `{run}` does not name its scenario in the run registry (a supervisor older than `hnav top`)")]
    NoScenario {
        /// The run id.
        run: String,
    },
    /// The run's scenario cannot be loaded any more.
    #[error("run `{run}`: {source}")]
    Scenario {
        /// The run id.
        run: String,
        /// Why.
        source: ScenarioError,
    },
    /// The scenario file was changed after the run started.
    #[error("run `{run}`: {} is not the scenario the run started with (its hash is {now:016x}, the run's log says {logged:016x})", path.display())]
    ScenarioChanged {
        /// The run id.
        run: String,
        /// The scenario file.
        path: PathBuf,
        /// Its hash now.
        now: u64,
        /// The hash in the run's log header.
        logged: u64,
    },
    /// A run directory that cannot be played back (its log, map or summary), or a speed out
    /// of range.
    #[error("{}: {problem}", path.display())]
    Playback {
        /// The run directory, or the file at fault.
        path: PathBuf,
        /// What is wrong.
        problem: String,
    },
    /// The recording's trajectories could not be read.
    #[error(transparent)]
    Recording(#[from] crate::recording::RecordingError),
    /// The run's topics could not be opened or read.
    #[error("run `{run}`: {source}")]
    Transport {
        /// The run id.
        run: String,
        /// Why.
        source: TransportError,
    },
}
