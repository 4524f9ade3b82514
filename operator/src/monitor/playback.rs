//! The playback feed: a finished run's recording shown in the live view at a chosen speed
//! (`hnav log replay DIR --speed X`).
//!
//! Everything comes from the run directory, so a run can be looked at after its scenario
//! file has changed or moved: the map from `map.map`, starts, goals and the clock mode from
//! the consensus log's header, poses from `recording/trajectories.bin`, decisions and process
//! events from the log, the collision count from `summary.json`. What only the scenario holds
//! comes from the scenario `invocation.json` names, if it still hashes as the log's header
//! says (otherwise the map stays as it started and no sensed area is shown): the world's
//! closes and opens, applied at their time, and the sensor range, with which each robot's
//! view is rebuilt from its recorded pose and the recorded movers
//! ([`crate::recording::world::RecordedWorld`]). The feed yields the same
//! [`Update`]s as the live one, so the state and the view are the same code:
//!
//! - **Ground truth**: one [`Truth`] per sampling time of the recording (all robots' samples
//!   of one time folded into one message); the collision count is the number of the
//!   summary's collision times up to then.
//! - **Commits**: each round record rebuilt with [`RoundRecord::write_commit`](hnav_runtime::consensus_log::record::RoundRecord::write_commit), placed at
//!   `round x control period` of simulated time (the period is in the trajectory header). In
//!   lockstep that is exact: round r and period r are the same instant (see the agent's
//!   process docs). In realtime a round closes at most once a period, when every candidate is
//!   in or its deadline passed, so a coordinator that fell behind shows its decisions a
//!   little early; the log holds no time to do better.
//! - **Progress**: the tally of the decisions so far ([`Tally`]), after every commit.
//! - **Lifecycle**: the log's process events, at their round.
//! - **End**: at the log's end record, with its reason; a log without one (a run killed
//!   with its supervisor) ends as stopped once both streams are read.
//!
//! Pacing: simulated time runs at `speed` times the wall clock from the first
//! [`Feed::wait`]; [`Feed::wait`] sleeps until the next event is due or the caller's
//! deadline, whichever is first, and then looks at iceoryx2's termination flag (SIGINT,
//! SIGTERM), so the viewer's loop never spins. There are no process-health rows: no process
//! of the run is alive.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use iceoryx2_bb_posix::signal::SignalHandler;

use super::feed::{world_steps, RunInfo};
use super::feed::{Feed, FeedError, RunEnd, Update, Waited};
use crate::invocation::Invocation;
use crate::recording::world::RecordedWorld;
use crate::recording::{self, PoseSample, PoseSource, TrajectoryReader};
use crate::report::MAP_FILE;
use hnav_runtime::consensus_log::read_decided;
use hnav_runtime::consensus_log::record::{EndReason, Record, RunHeader};
use hnav_runtime::consensus_log::tally::Tally;
use hnav_runtime::grid::movingai::read_map_file;
use hnav_runtime::msg::{Commit, Lifecycle, Pose, Progress, Truth, View};

/// The slowest and fastest playback speeds `--speed` takes.
pub const SPEEDS: std::ops::RangeInclusive<f64> = 0.01..=10_000.0;

/// A recorded run played back at a chosen speed. See the [module docs](self).
pub struct PlaybackFeed {
    info: RunInfo,
    speed: f64,
    period_ns: u64,
    started: Option<Instant>,
    trajectories: TrajectoryReader,
    /// The next ground-truth sample, read ahead to know when a time's samples are complete.
    pending: Option<PoseSample>,
    truth: Truth,
    /// The map with the scenario's changes, the movers, and the views rebuilt from them.
    world: RecordedWorld,
    view: View,
    collisions_at: Vec<u64>,
    records: std::vec::IntoIter<Record>,
    next: Option<Record>,
    tally: Tally,
    commit: Commit,
    agents: u32,
    ended: bool,
}

impl PlaybackFeed {
    /// Opens the recording of the run in `dir` (a run directory `hnav run` wrote), to be
    /// played at `speed` times real time.
    pub fn open(dir: &Path, speed: f64) -> Result<PlaybackFeed, FeedError> {
        let bad = |problem: String| FeedError::Playback {
            path: dir.to_path_buf(),
            problem,
        };
        if !(speed.is_finite() && SPEEDS.contains(&speed)) {
            return Err(bad(format!(
                "speed {speed}: it must lie between {} and {}",
                SPEEDS.start(),
                SPEEDS.end()
            )));
        }
        let log = read_decided(dir.join("log")).map_err(|e| bad(e.to_string()))?;
        let mut records = log.records.into_iter();
        let Some(Record::Header(header)) = records.next() else {
            return Err(bad(
                "the consensus log does not start with its header".into()
            ));
        };
        let path = dir.join(recording::DIR).join(recording::TRAJECTORIES);
        let trajectories = TrajectoryReader::open(&path)?;
        let th = *trajectories.header();
        if th.control_period_us == 0 {
            return Err(bad(format!(
                "{}: the recording does not say the run's control period (written by an \
                 older hnav), so its rounds cannot be placed in time",
                path.display()
            )));
        }
        if usize::from(th.robots) != header.agents.len()
            || (th.width, th.height) != (header.width, header.height)
        {
            return Err(bad(format!(
                "{}: the recording is of {} robots on {} x {} cells, the log of {} agents on {} x {}",
                path.display(),
                th.robots,
                th.width,
                th.height,
                header.agents.len(),
                header.width,
                header.height
            )));
        }
        let info = run_info(dir, &header, f64::from(th.cell_size_m), speed)?;
        let mut truth = Truth {
            poses: vec![Pose::default(); usize::from(th.robots)],
            ..Truth::default()
        };
        for (pose, a) in truth.poses.iter_mut().zip(&header.agents) {
            *pose = cell_centre(a.start, header.width, th.cell_size_m);
        }
        let world = RecordedWorld::new(info.grid.clone(), info.changes.clone(), info.cell_size_m);
        Ok(PlaybackFeed {
            world,
            view: View::default(),
            info,
            speed,
            period_ns: u64::from(th.control_period_us) * 1_000,
            started: None,
            trajectories,
            pending: None,
            truth,
            collisions_at: collision_times(&dir.join("summary.json"))?,
            records,
            next: None,
            tally: Tally::from_header(&header),
            commit: Commit::default(),
            agents: header.agents.len() as u32,
            ended: false,
        })
    }

    /// Simulated time now, ns; the clock starts at the first call.
    fn sim_now(&mut self) -> u64 {
        let started = *self.started.get_or_insert_with(Instant::now);
        (started.elapsed().as_secs_f64() * self.speed * 1e9) as u64
    }

    /// When the next ground-truth time is, reading ahead past estimates.
    fn next_truth_time(&mut self) -> Result<Option<u64>, FeedError> {
        while self.pending.is_none() {
            match self.trajectories.next_sample()? {
                Some(s) if s.source == PoseSource::Truth => self.pending = Some(s),
                // The recorder writes a time's movers after its truth, so they are read
                // here, ahead of the next time's truth, and shown with their own time's.
                Some(s) if s.source == PoseSource::Mover => {
                    self.world.place_mover(u32::from(s.robot), s.pose());
                }
                Some(_) => {}
                None => return Ok(None),
            }
        }
        Ok(self.pending.map(|s| s.t_ns))
    }

    /// When the next log record is due (`None` when the log is read).
    fn next_record_time(&mut self) -> Option<u64> {
        if self.next.is_none() {
            self.next = self
                .records
                .find(|r| matches!(r, Record::Round(_) | Record::Lifecycle(_) | Record::End(_)));
        }
        let round = self.next.as_ref()?.round()?;
        Some(round.saturating_mul(self.period_ns))
    }

    /// The time of the next event of either stream.
    fn next_event_time(&mut self) -> Result<Option<u64>, FeedError> {
        let truth = self.next_truth_time()?;
        Ok(match (truth, self.next_record_time()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        })
    }

    /// Folds every sample of time `t` into the truth message and yields it.
    fn emit_truth(&mut self, t: u64, apply: &mut dyn FnMut(Update<'_>)) -> Result<(), FeedError> {
        while let Some(s) = self.pending.filter(|s| s.t_ns == t) {
            if let Some(p) = self.truth.poses.get_mut(usize::from(s.robot)) {
                *p = s.pose();
            }
            self.pending = None;
            self.next_truth_time()?;
        }
        self.truth.sim_time_ns = t;
        self.truth.period += 1;
        let seen = self.collisions_at.partition_point(|&c| c <= t);
        self.truth.collisions = u32::try_from(seen).unwrap_or(u32::MAX);
        apply(Update::Truth(self.truth.view()));
        self.world.advance(t);
        if !self.world.movers().is_empty() {
            apply(Update::Movers(self.world.movers()));
        }
        if let Some(range) = self.info.sensor_range {
            for (i, pose) in self.truth.poses().iter().enumerate() {
                self.world
                    .fill_view(i as u32, pose, range, t, &mut self.view);
                self.view.period = self.truth.period;
                apply(Update::View(&self.view));
            }
        }
        Ok(())
    }

    /// Yields the next log record; `true` when it was the end record.
    fn emit_record(&mut self, apply: &mut dyn FnMut(Update<'_>)) -> bool {
        match self.next.take() {
            Some(Record::Round(r)) => {
                r.write_commit(&mut self.commit);
                apply(Update::Commit(self.commit.view()));
                self.tally.fold_round(&r);
                apply(Update::Progress(&self.progress(r.round, 0)));
            }
            Some(Record::Lifecycle(l)) => {
                let event = Lifecycle {
                    time_ns: 0,
                    pid: 0,
                    index: l.index,
                    role: l.role,
                    event: l.event,
                    reason: 0,
                    reserved: 0,
                    restarts: l.restarts,
                };
                apply(Update::Lifecycle(&event));
            }
            Some(Record::End(e)) => {
                let done = match end_of(e.reason) {
                    RunEnd::AllAtGoal => Progress::ALL_AT_GOAL,
                    RunEnd::TimeLimit => Progress::TIME_LIMIT,
                    _ => 0,
                };
                let mut p = self.progress(e.round, done);
                p.at_goal = e.at_goal;
                apply(Update::Progress(&p));
                apply(Update::Ended(end_of(e.reason)));
                return true;
            }
            _ => {}
        }
        false
    }

    fn progress(&self, round: u64, done: u8) -> Progress {
        Progress {
            round,
            agents: self.agents,
            at_goal: 0,
            conflicts: self.tally.conflicts(),
            replans: self.tally.replans(),
            done,
            leader: 0,
            reserved: [0; 6],
        }
    }
}

impl Feed for PlaybackFeed {
    fn info(&self) -> &RunInfo {
        &self.info
    }

    fn wait(&mut self, until: Instant) -> Result<Waited, FeedError> {
        let now_sim = self.sim_now();
        let due = match (self.ended, self.next_event_time()?) {
            (false, Some(t)) if t > now_sim => {
                let wall = Duration::from_secs_f64((t - now_sim) as f64 / 1e9 / self.speed);
                Instant::now() + wall
            }
            (false, Some(_)) => return Ok(Waited::Ready),
            _ => until,
        };
        if let Some(left) = due.min(until).checked_duration_since(Instant::now()) {
            std::thread::sleep(left);
        }
        Ok(if SignalHandler::termination_requested() {
            Waited::Stop
        } else {
            Waited::Ready
        })
    }

    fn pump(&mut self, apply: &mut dyn FnMut(Update<'_>)) -> Result<(), FeedError> {
        if self.ended {
            return Ok(());
        }
        let now = self.sim_now();
        loop {
            let truth = self.next_truth_time()?;
            let record = self.next_record_time();
            match (truth, record) {
                // Ties go to ground truth: a round's poses are shown before its decisions.
                (Some(t), r) if t <= now && r.is_none_or(|r| t <= r) => {
                    self.emit_truth(t, apply)?
                }
                (_, Some(r)) if r <= now => {
                    if self.emit_record(apply) {
                        self.ended = true;
                        return Ok(());
                    }
                }
                (None, None) => {
                    self.ended = true;
                    apply(Update::Ended(RunEnd::Stopped));
                    return Ok(());
                }
                _ => return Ok(()),
            }
        }
    }
}

impl std::fmt::Debug for PlaybackFeed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PlaybackFeed")
            .field("run", &self.info.run_id)
            .field("speed", &self.speed)
            .field("ended", &self.ended)
            .finish_non_exhaustive()
    }
}

/// How the view words a logged end.
fn end_of(reason: EndReason) -> RunEnd {
    match reason {
        EndReason::AllAtGoal | EndReason::AllAtGoalOrUnreachable | EndReason::AllAtGoalOrLost => {
            RunEnd::AllAtGoal
        }
        EndReason::TimeLimit => RunEnd::TimeLimit,
        EndReason::Stopped => RunEnd::Stopped,
    }
}

/// The run's static picture from its directory alone.
fn run_info(
    dir: &Path,
    header: &RunHeader,
    cell_size_m: f64,
    speed: f64,
) -> Result<RunInfo, FeedError> {
    let map = dir.join(MAP_FILE);
    let grid = read_map_file(&map).map_err(|e| FeedError::Playback {
        path: dir.to_path_buf(),
        problem: e.to_string(),
    })?;
    if (grid.width(), grid.height()) != (header.width, header.height) {
        return Err(FeedError::Playback {
            path: dir.to_path_buf(),
            problem: format!(
                "{}: the map is {} x {} cells, the log's run {} x {}",
                map.display(),
                grid.width(),
                grid.height(),
                header.width,
                header.height
            ),
        });
    }
    // What only the scenario holds (its changes, the sensor range), if it is still the run's.
    let scenario = Invocation::logged_scenario(dir, header.scenario_hash).ok();
    let changes = scenario
        .as_ref()
        .map_or_else(Vec::new, |s| world_steps(s, &grid));
    let name = dir
        .canonicalize()
        .ok()
        .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| dir.display().to_string());
    Ok(RunInfo {
        run_id: name,
        mode: format!("{} playback x{speed}", header.clock),
        rules: rules_of(&dir.join("summary.json")),
        grid,
        starts: header.agents.iter().map(|a| a.start).collect(),
        goals: header.agents.iter().map(|a| a.goal).collect(),
        cell_size_m,
        changes,
        sensor_range: scenario.and_then(|s| s.sensing.map(|s| s.range)),
    })
}

/// The centre of row-major cell `c`, where a robot stands before its first sample.
fn cell_centre(c: u32, width: u32, cell_size_m: f32) -> Pose {
    let w = width.max(1);
    let cs = f64::from(cell_size_m);
    Pose {
        x_m: (f64::from(c % w) + 0.5) * cs,
        y_m: (f64::from(c / w) + 0.5) * cs,
        theta_rad: 0.0,
    }
}

/// The simulated times at which the collision count rose (`summary.json`'s
/// `recording.collisions_at_ns`), sorted; none when the summary is absent.
/// The rules a run ran, as its summary says; empty when it does not.
fn rules_of(summary: &Path) -> String {
    std::fs::read_to_string(summary)
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v.get("rules").and_then(|r| r.as_str()).map(str::to_string))
        .unwrap_or_default()
}

fn collision_times(path: &PathBuf) -> Result<Vec<u64>, FeedError> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => {
            return Err(FeedError::Playback {
                path: path.clone(),
                problem: e.to_string(),
            })
        }
    };
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| FeedError::Playback {
        path: path.clone(),
        problem: format!("not JSON: {e}"),
    })?;
    let mut times = crate::report::data::collisions_at_ns(&v);
    times.sort_unstable();
    Ok(times)
}
