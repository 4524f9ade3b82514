//! The recorder: a thread of the supervisor that writes the run's recording
//! ([`crate::recording`]) into `DIR/recording/` while the run goes on.
//!
//! It has its own iceoryx2 node ("recorder") and subscribers: `truth` (notified; its deep
//! buffer, [`topics::truth_qos`], keeps the messages of a burst), `estimate` (depth 1, not
//! notified: read whenever truth wakes the thread), in a run with movers `movers` (read as
//! `estimate` is, with truth's deep buffer), and, with `[record] maps`, every
//! `map/<i>`. It blocks in a [`Waiter`](hnav_runtime::transport::Waiter) on those and on a stop pipe
//! that [`Recorder::finish`] closes; every subscription is "latest", so a slow recorder
//! loses samples (counted) and never holds a publisher back. What is kept is decided by
//! simulated time ([`sampler`]), so the same lockstep run records the same samples. Nothing
//! it does reaches the swarm: it publishes nothing.

pub mod sampler;

use std::os::fd::{AsRawFd, FromRawFd, IntoRawFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::thread::JoinHandle;
use std::time::Duration;

use iceoryx2_bb_posix::file_descriptor::{FileDescriptor, FileDescriptorBased};
use iceoryx2_bb_posix::file_descriptor_set::SynchronousMultiplexing;
use serde::Serialize;

use crate::recording::{
    self, MapWriter, PoseSample, PoseSource, RecordingError, TrajectoryHeader, TrajectoryWriter,
};
use hnav_runtime::msg::{Estimate, MapHeader, MoverPlace, MoversHeader, Pose, TruthView};
use hnav_runtime::scenario::Scenario;
use hnav_runtime::topics::{self, TruthReceiver};
use hnav_runtime::transport::{Receiver, RunId, SliceReceiver, Transport, TransportError};
use sampler::{MapAction, MapThrottle, TruthSampler};

use super::exit_fd::poll_readable;

/// How long [`Recorder::start`] waits for the thread's subscribers.
const READY_TIMEOUT: Duration = Duration::from_secs(30);

/// What the recorder wrote: the summary's `recording` entry.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RecordingSummary {
    /// The recording's directory.
    pub dir: PathBuf,
    /// Ground-truth samples written (one per robot and sampling time).
    pub truth_samples: u64,
    /// Dead-reckoned samples written.
    pub estimate_samples: u64,
    /// Neural-map snapshots written.
    pub map_snapshots: u64,
    /// Samples and snapshots dropped by the size caps (`[record] max_mb`).
    pub dropped: u64,
    /// Ground-truth messages the recorder never saw (gaps in the periods it received).
    pub missed: u64,
    /// Estimate sampling times (per agent) passed with no estimate seen: on a busy machine
    /// an agent's newer estimate overwrote the one the recorder had not read yet.
    pub estimates_missed: u64,
    /// Simulated times (ns since Start) at which the sim's collision count rose.
    pub collisions_at_ns: Vec<u64>,
    /// Why the recording stopped early, if it did (it never stops the run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// Why the recorder could not start.
#[derive(Debug, thiserror::Error)]
pub enum RecorderError {
    /// A file of the recording.
    #[error(transparent)]
    File(#[from] RecordingError),
    /// Its node or subscribers.
    #[error("recorder: {0}")]
    Transport(#[from] TransportError),
    /// The stop pipe or the thread.
    #[error("recorder: {0}")]
    Os(#[from] std::io::Error),
    /// The thread ended before it was subscribed.
    #[error("recorder: the recording thread ended before it was ready")]
    Gone,
}

/// The read end of the stop pipe: readable (end of file) once the write end is closed.
#[derive(Debug)]
struct StopFd(FileDescriptor);

impl FileDescriptorBased for StopFd {
    fn file_descriptor(&self) -> &FileDescriptor {
        &self.0
    }
}

impl SynchronousMultiplexing for StopFd {}

impl StopFd {
    fn closed(&self) -> bool {
        // SAFETY: only read for poll(2); the descriptor stays owned by `self.0`.
        let raw = unsafe { self.0.native_handle() };
        matches!(poll_readable(&[raw], Some(Duration::ZERO)), Ok(r) if r[0])
    }
}

/// The running recorder; [`Recorder::finish`] ends it.
pub struct Recorder {
    stop: Option<OwnedFd>,
    thread: Option<JoinHandle<RecordingSummary>>,
}

impl Recorder {
    /// Creates `dir/recording/`, starts the thread and returns once it is subscribed (so it
    /// sees the run from its first truth message).
    pub fn start(run: &RunId, scenario: &Scenario, dir: &Path) -> Result<Recorder, RecorderError> {
        let out = dir.join(recording::DIR);
        std::fs::create_dir_all(&out).map_err(|source| RecordingError::Io {
            path: out.clone(),
            source,
        })?;
        let files = Files::create(scenario, &out)?;
        let (read, write) = pipe()?;
        let (ready_tx, ready_rx) = mpsc::channel();
        let run = run.clone();
        let agents = scenario.agents.len();
        let maps = scenario.record.maps;
        let movers = scenario.movers().next().is_some();
        let grid_len = scenario.map.grid.len();
        let thread = std::thread::Builder::new()
            .name("hnav-recorder".into())
            .spawn(move || {
                let mut summary = RecordingSummary {
                    dir: out,
                    ..RecordingSummary::default()
                };
                let mut rec = match Live::open(&run, agents, movers, maps) {
                    Ok(live) => {
                        let _ = ready_tx.send(Ok(()));
                        Thread::new(files, agents, grid_len, live)
                    }
                    Err(e) => {
                        let _ = ready_tx.send(Err(e));
                        return summary;
                    }
                };
                if let Err(e) = rec.run(&read) {
                    summary.error = Some(e);
                }
                rec.close(&mut summary);
                summary
            })?;
        match ready_rx.recv_timeout(READY_TIMEOUT) {
            Ok(Ok(())) => Ok(Recorder {
                stop: Some(write),
                thread: Some(thread),
            }),
            Ok(Err(e)) => {
                let _ = thread.join();
                Err(e.into())
            }
            Err(_) => {
                drop(write);
                let _ = thread.join();
                Err(RecorderError::Gone)
            }
        }
    }

    /// Stops the thread after a last look at the topics, flushes the files and returns what
    /// was written.
    pub fn finish(mut self) -> RecordingSummary {
        self.stop.take();
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(s)) => s,
            _ => RecordingSummary {
                error: Some("the recording thread panicked".into()),
                ..RecordingSummary::default()
            },
        }
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        self.stop.take();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn pipe() -> std::io::Result<(StopFd, OwnedFd)> {
    let mut ends = [0 as libc::c_int; 2];
    // SAFETY: `ends` is a valid array of two c_ints for pipe2 to fill.
    if unsafe { libc::pipe2(ends.as_mut_ptr(), libc::O_CLOEXEC) } != 0 {
        return Err(std::io::Error::last_os_error());
    }
    // SAFETY: pipe2 succeeded, so both are fresh open descriptors owned by nobody else.
    let (read, write) = unsafe { (OwnedFd::from_raw_fd(ends[0]), OwnedFd::from_raw_fd(ends[1])) };
    debug_assert!(read.as_raw_fd() >= 0);
    // SAFETY: `into_raw_fd` released ownership of the read end, which the StopFd now takes.
    let fd = unsafe { FileDescriptor::new_unchecked(read.into_raw_fd()) };
    Ok((StopFd(fd), write))
}

/// The recording's writers.
struct Files {
    trajectories: TrajectoryWriter,
    maps: Option<MapWriter>,
    max_bytes: u64,
    rate_hz: u16,
}

impl Files {
    fn create(scenario: &Scenario, out: &Path) -> Result<Self, RecordingError> {
        let g = &scenario.map.grid;
        let header = TrajectoryHeader {
            robots: u16::try_from(scenario.agents.len()).unwrap_or(u16::MAX),
            rate_hz: scenario.record.trajectory_hz,
            cell_size_m: scenario.robot.cell_size_m as f32,
            width: g.width(),
            height: g.height(),
            truncated: false,
            control_period_us: (scenario.sim.control_period_s() * 1e6).round() as u32,
            movers: u16::try_from(scenario.movers().count()).unwrap_or(u16::MAX),
        };
        let max_bytes = scenario.record.max_bytes();
        let trajectories =
            TrajectoryWriter::create(&out.join(recording::TRAJECTORIES), header, max_bytes)?;
        let maps = if scenario.record.maps {
            Some(MapWriter::create(&out.join(recording::MAPS), max_bytes)?)
        } else {
            None
        };
        Ok(Files {
            trajectories,
            maps,
            max_bytes,
            rate_hz: scenario.record.trajectory_hz,
        })
    }
}

/// The thread's subscribers.
struct Live {
    transport: Transport,
    truth: TruthReceiver,
    estimate: Receiver<Estimate>,
    /// The movers' places (a run with movers): read whenever truth wakes the thread.
    movers: Option<SliceReceiver<MoverPlace, MoversHeader>>,
    maps: Vec<SliceReceiver<f32, MapHeader>>,
}

impl Live {
    fn open(run: &RunId, agents: usize, movers: bool, maps: bool) -> Result<Self, TransportError> {
        // Signals are the supervisor's business: it ends the run and then this thread.
        let transport = Transport::builder(run)
            .node_name("recorder")
            .handle_signals(false)
            .create()?;
        let truth = transport.slice_receiver(topics::TRUTH, topics::truth_qos())?;
        let estimate = transport.receiver(topics::ESTIMATE, topics::estimate_qos(agents))?;
        let movers = movers
            .then(|| transport.slice_receiver(topics::MOVERS, topics::truth_qos()))
            .transpose()?;
        let maps = if maps {
            (0..agents)
                .map(|i| transport.slice_receiver(&topics::map(i), topics::state_qos()))
                .collect::<Result<Vec<_>, _>>()?
        } else {
            Vec::new()
        };
        Ok(Live {
            transport,
            truth,
            estimate,
            movers,
            maps,
        })
    }
}

/// A snapshot held back by the throttle, to be written at the end.
struct Held {
    t_ns: u64,
    header: MapHeader,
    values: Vec<f32>,
}

/// The thread: its subscribers and what it writes.
struct Thread {
    live: Live,
    state: State,
}

/// What the thread writes and counts.
struct State {
    files: Files,
    truth: TruthSampler,
    estimates: Vec<sampler::SimClock>,
    /// The movers' sampling (all movers of one message at a time).
    movers: sampler::SimClock,
    throttle: MapThrottle,
    held: Vec<Held>,
    /// The latest simulated time seen on truth: the time stamp of a snapshot.
    now_ns: u64,
    truth_samples: u64,
    estimate_samples: u64,
    /// Snapshots refused to keep room for every agent's last one.
    maps_dropped: u64,
}

impl Thread {
    fn new(files: Files, agents: usize, grid_len: usize, live: Live) -> Self {
        let rate = files.rate_hz;
        let held_len = if live.maps.is_empty() { 0 } else { grid_len };
        Thread {
            state: State {
                truth: TruthSampler::new(rate),
                estimates: vec![sampler::SimClock::new(rate); agents],
                movers: sampler::SimClock::new(rate),
                throttle: MapThrottle::new(agents),
                held: (0..agents)
                    .map(|_| Held {
                        t_ns: 0,
                        header: MapHeader::default(),
                        values: Vec::with_capacity(held_len),
                    })
                    .collect(),
                files,
                now_ns: 0,
                truth_samples: 0,
                estimate_samples: 0,
                maps_dropped: 0,
            },
            live,
        }
    }

    /// Records until the stop pipe is closed, then takes a last look.
    fn run(&mut self, stop: &StopFd) -> Result<(), String> {
        let Thread { live, state } = self;
        let waiter = live.transport.waiter().map_err(|e| e.to_string())?;
        let _truth = waiter.attach(&live.truth).map_err(|e| e.to_string())?;
        let _maps = live
            .maps
            .iter()
            .map(|m| waiter.attach(m))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| e.to_string())?;
        let _stop = waiter.attach_fd(stop).map_err(|e| e.to_string())?;
        loop {
            let stopping = stop.closed();
            state.drain(live).map_err(|e| e.to_string())?;
            if stopping {
                return Ok(());
            }
            waiter.wait(None).map_err(|e| e.to_string())?;
        }
    }

    fn close(self, summary: &mut RecordingSummary) {
        self.state.close(summary);
    }
}

impl State {
    fn drain(&mut self, live: &Live) -> Result<(), RecorderError> {
        let State {
            files,
            truth,
            estimates,
            movers,
            throttle,
            held,
            now_ns,
            truth_samples,
            estimate_samples,
            maps_dropped,
        } = self;
        let mut failed = None;
        live.truth.drain_pending(|h, poses| {
            let t = TruthView::new(h, poses);
            *now_ns = (*now_ns).max(t.sim_time_ns());
            if failed.is_some() || !truth.take(t.sim_time_ns(), t.period(), t.collisions()) {
                return;
            }
            for (i, p) in t.poses().iter().enumerate() {
                let s = sample(t.sim_time_ns(), i, PoseSource::Truth, p);
                match files.trajectories.push(&s) {
                    Ok(true) => *truth_samples += 1,
                    Ok(false) => {}
                    Err(e) => failed = Some(e),
                }
            }
        })?;
        live.estimate.drain(|e| {
            let i = e.agent as usize;
            if failed.is_some() || !estimates.get_mut(i).is_some_and(|c| c.take(e.sim_time_ns)) {
                return;
            }
            match files
                .trajectories
                .push(&sample(e.sim_time_ns, i, PoseSource::Estimate, &e.pose))
            {
                Ok(true) => *estimate_samples += 1,
                Ok(false) => {}
                Err(err) => failed = Some(err),
            }
        })?;
        if let Some(rx) = &live.movers {
            rx.drain_pending(|h, places| {
                if failed.is_some() || !movers.take(h.sim_time_ns) {
                    return;
                }
                for m in places {
                    let s = sample(h.sim_time_ns, m.mover as usize, PoseSource::Mover, &m.pose);
                    if let Err(e) = files.trajectories.push(&s) {
                        failed = Some(e);
                    }
                }
            })?;
        }
        if let Some(e) = failed {
            return Err(e.into());
        }
        let Some(writer) = files.maps.as_mut() else {
            return Ok(());
        };
        let agents = live.maps.len();
        for m in &live.maps {
            m.drain_pending(|h, values| {
                if failed.is_some() {
                    return;
                }
                let i = h.agent as usize;
                let cells = h.width as usize * h.height as usize;
                if values.len() != cells {
                    return;
                }
                match throttle.on_snapshot(i, *now_ns) {
                    Some(MapAction::Write) => {
                        // Room is kept for every agent's last snapshot, written at the end.
                        let frame = 8 + recording::maps::BODY_HEADER_LEN as u64 + 4 * cells as u64;
                        let room = writer.written().bytes + frame * (agents as u64 + 1);
                        if room > files.max_bytes {
                            *maps_dropped += 1;
                            if let Some(slot) = held.get_mut(i) {
                                hold(slot, *now_ns, h, values);
                            }
                            throttle.defer(i);
                            return;
                        }
                        if let Err(e) = writer.push(*now_ns, h, values) {
                            failed = Some(e);
                        }
                    }
                    Some(MapAction::Hold) => {
                        if let Some(slot) = held.get_mut(i) {
                            hold(slot, *now_ns, h, values);
                        }
                    }
                    None => {}
                }
            })?;
        }
        match failed {
            Some(e) => Err(e.into()),
            None => Ok(()),
        }
    }

    /// Writes the held last snapshots and flushes both files into `summary`.
    fn close(self, summary: &mut RecordingSummary) {
        let State {
            files,
            mut throttle,
            held,
            truth,
            truth_samples,
            estimate_samples,
            maps_dropped,
            estimates,
            ..
        } = self;
        let mut note = |e: RecordingError| {
            summary.error.get_or_insert_with(|| e.to_string());
        };
        if let Some(mut writer) = files.maps {
            let pending: Vec<usize> = throttle.pending().collect();
            for i in pending {
                let h = &held[i];
                if let Err(e) = writer.push(h.t_ns, &h.header, &h.values) {
                    note(e);
                }
                throttle.flushed(i);
            }
            match writer.finish() {
                Ok(w) => {
                    summary.map_snapshots = w.records;
                    summary.dropped += w.dropped + maps_dropped;
                }
                Err(e) => note(e),
            }
        }
        match files.trajectories.finish() {
            Ok(w) => summary.dropped += w.dropped,
            Err(e) => note(e),
        }
        summary.truth_samples = truth_samples;
        summary.estimate_samples = estimate_samples;
        summary.missed = truth.missed;
        summary.estimates_missed = estimates.iter().map(|c| c.skipped).sum();
        summary.collisions_at_ns = truth.collisions_at_ns;
    }
}

/// Keeps a copy of a snapshot in `slot` (its buffer was sized for the map once).
fn hold(slot: &mut Held, t_ns: u64, header: &MapHeader, values: &[f32]) {
    slot.t_ns = t_ns;
    slot.header = *header;
    slot.values.clear();
    slot.values.extend_from_slice(values);
}

fn sample(t_ns: u64, robot: usize, source: PoseSource, p: &Pose) -> PoseSample {
    PoseSample {
        t_ns,
        robot: u16::try_from(robot).unwrap_or(u16::MAX),
        source,
        x_m: p.x_m as f32,
        y_m: p.y_m as f32,
        theta_rad: p.theta_rad as f32,
    }
}
