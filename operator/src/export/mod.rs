//! `hnav log export DIR --mcap out.mcap`: a run as an MCAP file that Foxglove Studio opens.
//!
//! Every channel's messages are JSON (message encoding `json`) with a JSON schema (schema
//! encoding `jsonschema`, [`schemas`]). The channels the live Foxglove view shows
//! ([`channels::shown`](crate::channels::shown): `/map`, `/scene`, `/robots/<i>/truth`,
//! `/robots/<i>/stats`, `/log`) are written with the same schemas and from the same fold
//! ([`SceneFold`](crate::channels::scene::SceneFold)), so a recorded run looks as a live one
//! did; the others are the export's own. Log time is simulated time: `round x control
//! period` for what comes from the consensus log (a lockstep round `r` is decided once `r`
//! periods have been simulated), the samples' own `t_ns` for the recording.
//!
//! | topic | schema | from | one message per |
//! |---|---|---|---|
//! | `/map` | `foxglove.Grid` | the scenario (`invocation.json`) | the run (field `occupied`, 1 = wall), and again at each close or open of its `[[events]]` |
//! | `/map/shared` | `foxglove.Grid` | the scenario and `log/` (with `[sensing]`) | the coordinator's map at the start and after each map-change record |
//! | `/map/sensed` | `foxglove.Grid` | the scenario and the trajectories (with `[sensing]`) | the floor the robots' sensors see (`occupied` 1), once a second of sim time |
//! | `/movers/<k>` | `foxglove.PoseInFrame` | the trajectories (a run with movers) | mover `k`'s place at each sampling time |
//! | `/scene` | `foxglove.SceneUpdate` | `recording/trajectories.bin` and `log/` | ground-truth sampling time: robots, goals, routes, conflicts |
//! | `/robots/<i>/truth` | `foxglove.PoseInFrame` | `recording/trajectories.bin` | ground-truth sample of robot `i` |
//! | `/robots/<i>/stats` | `hnav.RobotStats` | `recording/trajectories.bin` | ground-truth sampling time: robot `i`'s speed |
//! | `/log` | `foxglove.Log` | `log/` | decision worth a line, process down, restarted or lost (as live) |
//! | `/robots/<i>/estimate` | `foxglove.PoseInFrame` | `recording/trajectories.bin` | dead-reckoned sample of robot `i` |
//! | `/robots/<i>/neural_map` | `foxglove.Grid` | `recording/maps.bin` | snapshot of agent `i` (fields `activation`, `log10_activation`) |
//! | `/commits` | `hnav.CommittedCells` | `log/` | round: the cells its commit gave |
//! | `/decisions` | `hnav.Decision` | `log/` | decision of every round |
//! | `/replans` | `hnav.Replan` | `log/` | replan record |
//! | `/lifecycle` | `hnav.Lifecycle` | `log/` | process down, restarted or lost (field `cell`: an agent's robot's cell then) |
//!
//! Poses and grids are in one frame, `map`: metres, x along columns, y along rows (the sim's
//! frame; cell `(x, y)` spans `[x c, (x + 1) c) x [y c, (y + 1) c)`), z up. A missing
//! recording file, or a scenario that cannot be loaded, leaves its channels out and is
//! reported in [`ExportReport::notes`]; a damaged file is an error naming it and the offset.

mod scene;
mod world;

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use crate::channels::messages::{cell, decision_message, neural_map_message, pose_message, stamp};
pub use crate::channels::schemas;
pub use crate::channels::FRAME;
use crate::invocation::Invocation;
use crate::recording::{self, MapReader, PoseSource, RecordingError, TrajectoryReader};
use hnav_runtime::consensus_log::{read_decided, LogError, Record, RunHeader};
use hnav_runtime::msg::{LifecycleEvent, Role, Verdict, NO_CELL};
use hnav_runtime::scenario::Scenario;

/// The control period assumed when the run's scenario cannot be loaded (the default
/// `[sim]`: 100 Hz odometry, 1 ms steps).
pub const DEFAULT_PERIOD_NS: u64 = 10_000_000;
/// The cell size assumed without the scenario and the trajectory file (the default
/// `[robot] cell_size_m`).
pub const DEFAULT_CELL_SIZE_M: f64 = 0.16;

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The consensus log cannot be read (names the file and offset).
    #[error(transparent)]
    Log(#[from] LogError),
    /// The log has no header.
    #[error("{}: the log has no run header", dir.display())]
    NoHeader {
        /// The log directory.
        dir: PathBuf,
    },
    /// A recording file is damaged (names the file and offset).
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The output cannot be written.
    #[error("{}: cannot write the MCAP file: {problem}", path.display())]
    Write {
        /// The output file.
        path: PathBuf,
        /// What went wrong.
        problem: String,
    },
}

/// What an export wrote.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExportReport {
    /// Per topic: its schema's name and how many messages it got.
    pub channels: BTreeMap<String, (String, u64)>,
    /// What was missing or assumed (missing recording files, torn tails, no scenario).
    pub notes: Vec<String>,
}

impl ExportReport {
    /// Messages in all channels.
    pub fn messages(&self) -> u64 {
        self.channels.values().map(|c| c.1).sum()
    }
}

/// What the export knows of the run beyond its log.
struct RunInfo {
    header: RunHeader,
    period_ns: u64,
    cell_size_m: f64,
    scenario: Option<Scenario>,
}

/// Writes the run in `run_dir` (holding `log/`, maybe `recording/` and `invocation.json`)
/// to the MCAP file `out`.
pub fn export_mcap(run_dir: &Path, out: &Path) -> Result<ExportReport, ExportError> {
    let log_dir = run_dir.join("log");
    let decided = read_decided(&log_dir)?;
    let records = decided.records;
    let header = match records.first() {
        Some(Record::Header(h)) => h.clone(),
        _ => return Err(ExportError::NoHeader { dir: log_dir }),
    };
    let mut report = ExportReport::default();
    if let Some(c) = &decided.compacted {
        report.notes.push(format!(
            "{}: compacted behind a snapshot; the decisions start after round {}",
            decided.dir.display(),
            c.round
        ));
    }
    let info = run_info(run_dir, header, &mut report.notes);
    let write_err = |e: &dyn std::fmt::Display| ExportError::Write {
        path: out.to_path_buf(),
        problem: e.to_string(),
    };
    let file = File::create(out).map_err(|e| write_err(&e))?;
    let mut w = Mcap::new(BufWriter::new(file)).map_err(|e| write_err(&e))?;
    let written = write_all(&mut w, run_dir, &records, &info, &mut report.notes)
        .and_then(|()| w.finish().map_err(|e| write_err(&e)));
    match written {
        Ok(counts) => report.channels = counts,
        Err(e) => {
            // No half-written file that looks like an export.
            let _ = std::fs::remove_file(out);
            return Err(match e {
                ExportError::Write { problem, .. } => write_err(&problem),
                other => other,
            });
        }
    }
    Ok(report)
}

/// The period and cell size of the run: from its scenario when `invocation.json` names one
/// that still hashes as the log's header says, else the defaults (noted).
fn run_info(run_dir: &Path, header: RunHeader, notes: &mut Vec<String>) -> RunInfo {
    let scenario = Invocation::logged_scenario(run_dir, header.scenario_hash);
    match scenario {
        Ok(s) => RunInfo {
            period_ns: s.sim.steps_per_control_period() * u64::from(s.sim.step_ms) * 1_000_000,
            cell_size_m: s.robot.cell_size_m,
            scenario: Some(s),
            header,
        },
        Err(why) => {
            notes.push(format!(
                "no scenario ({why}): no /map channel; rounds timed at {} ms, cells of {} m",
                DEFAULT_PERIOD_NS / 1_000_000,
                DEFAULT_CELL_SIZE_M
            ));
            RunInfo {
                header,
                period_ns: DEFAULT_PERIOD_NS,
                cell_size_m: DEFAULT_CELL_SIZE_M,
                scenario: None,
            }
        }
    }
}

fn write_all(
    w: &mut Mcap<impl Write + Seek>,
    run_dir: &Path,
    records: &[Record],
    info: &RunInfo,
    notes: &mut Vec<String>,
) -> Result<(), ExportError> {
    if let Some(s) = &info.scenario {
        let cell_m = info.cell_size_m;
        w.message(
            "/map",
            schemas::GRID,
            0,
            &crate::channels::messages::occupancy(&s.map.grid, 0, cell_m),
        )?;
        for (t, msg) in world::truth(s, cell_m) {
            w.message("/map", schemas::GRID, t, &msg)?;
        }
        if s.sensing.is_some() {
            for (t, msg) in world::shared(&s.map.grid, records, info.period_ns, cell_m) {
                w.message("/map/shared", schemas::GRID, t, &msg)?;
            }
        }
    }
    let rec_dir = run_dir.join(recording::DIR);
    let trajectories = rec_dir.join(recording::TRAJECTORIES);
    let mut cell_size = info.cell_size_m;
    if trajectories.exists() {
        let mut r = TrajectoryReader::open(&trajectories)?;
        cell_size = f64::from(r.header().cell_size_m);
        scene::register(w, usize::from(r.header().robots))?;
        for i in 0..r.header().robots {
            w.channel(&format!("/robots/{i}/estimate"), schemas::POSE_IN_FRAME)?;
        }
        for k in 0..r.header().movers {
            w.channel(&format!("/movers/{k}"), schemas::POSE_IN_FRAME)?;
        }
        while let Some(s) = r.next_sample()? {
            let topic = match s.source {
                PoseSource::Truth => format!("/robots/{}/truth", s.robot),
                PoseSource::Estimate => format!("/robots/{}/estimate", s.robot),
                PoseSource::Mover => format!("/movers/{}", s.robot),
            };
            w.message(&topic, schemas::POSE_IN_FRAME, s.t_ns, &pose_message(&s))?;
        }
        if r.torn_tail() > 0 {
            notes.push(format!(
                "{}: a torn tail of {} bytes skipped",
                trajectories.display(),
                r.torn_tail()
            ));
        }
        scene::write(w, &trajectories, records, info, cell_size)?;
        if let Some((s, range)) = (info.scenario.as_ref()).and_then(|s| Some((s, s.sensing?.range)))
        {
            for (t, msg) in world::sensed(s, range, &trajectories, cell_size)? {
                w.message("/map/sensed", schemas::GRID, t, &msg)?;
            }
        }
    } else {
        notes.push(format!(
            "{} missing: no /scene, /robots/<i>/truth, /robots/<i>/stats, /robots/<i>/estimate and /log channels",
            trajectories.display()
        ));
    }
    let maps = rec_dir.join(recording::MAPS);
    if maps.exists() {
        let mut r = MapReader::open(&maps)?;
        for i in 0..info.header.agents.len() {
            w.channel(&format!("/robots/{i}/neural_map"), schemas::GRID)?;
        }
        while let Some(snap) = r.next_snapshot()? {
            let topic = format!("/robots/{}/neural_map", snap.header.agent);
            w.message(
                &topic,
                schemas::GRID,
                snap.t_ns,
                &neural_map_message(&snap, cell_size),
            )?;
        }
        if r.torn_tail() > 0 {
            notes.push(format!(
                "{}: a torn tail of {} bytes skipped",
                maps.display(),
                r.torn_tail()
            ));
        }
    } else {
        notes.push(format!(
            "{} missing: no /robots/<i>/neural_map channels",
            maps.display()
        ));
    }
    log_channels(w, records, info)
}

/// `/commits`, `/decisions`, `/replans` and `/lifecycle`, from the consensus log.
fn log_channels(
    w: &mut Mcap<impl Write + Seek>,
    records: &[Record],
    info: &RunInfo,
) -> Result<(), ExportError> {
    let width = info.header.width;
    for (topic, schema) in [
        ("/commits", schemas::COMMITTED_CELLS),
        ("/decisions", schemas::DECISION),
        ("/replans", schemas::REPLAN),
        ("/lifecycle", schemas::LIFECYCLE),
    ] {
        w.channel(topic, schema)?;
    }
    // Each robot's cell (its start, then its last accepted move), for the lifecycle events.
    let mut at: Vec<u32> = info.header.agents.iter().map(|a| a.start).collect();
    for r in records {
        let Some(round) = r.round() else { continue };
        let t = round.saturating_mul(info.period_ns);
        match r {
            Record::Round(rec) => {
                let cells: Vec<Value> = rec
                    .decisions
                    .iter()
                    .filter(|d| d.cell != NO_CELL)
                    .map(|d| json!({"agent": d.agent, "cell": cell(d.cell, width)}))
                    .collect();
                let commit = json!({"timestamp": stamp(t), "round": round, "cells": cells});
                w.message("/commits", schemas::COMMITTED_CELLS, t, &commit)?;
                for d in &rec.decisions {
                    if Verdict::from_u8(d.verdict) == Some(Verdict::Accept) {
                        if let Some(c) = at.get_mut(d.agent as usize) {
                            *c = d.cell;
                        }
                    }
                    w.message(
                        "/decisions",
                        schemas::DECISION,
                        t,
                        &decision_message(t, round, d, width),
                    )?;
                }
            }
            Record::Replan(p) => {
                let msg = json!({
                    "timestamp": stamp(t),
                    "round": round,
                    "agent": p.agent,
                    "planner": p.planner,
                    "found": p.found,
                    "waypoints": p.waypoints.iter().map(|&c| cell(c, width)).collect::<Vec<_>>(),
                });
                w.message("/replans", schemas::REPLAN, t, &msg)?;
            }
            Record::Lifecycle(l) => {
                let role = Role::from_u8(l.role);
                let agent_cell = (role == Some(Role::Agent))
                    .then(|| at.get(l.index as usize).copied())
                    .flatten();
                let msg = json!({
                    "timestamp": stamp(t),
                    "round": round,
                    "process": role.map_or_else(|| l.role.to_string(), |r| r.node_name(l.index)),
                    "role": role.map_or_else(|| l.role.to_string(), |r| r.name().to_string()),
                    "index": l.index,
                    "event": LifecycleEvent::from_u8(l.event).map_or_else(|| l.event.to_string(), |e| e.name().to_string()),
                    "restarts": l.restarts,
                    "cell": agent_cell.map_or(Value::Null, |c| cell(c, width)),
                });
                w.message("/lifecycle", schemas::LIFECYCLE, t, &msg)?;
            }
            _ => {}
        }
    }
    Ok(())
}

/// The MCAP writer with one schema per name, one channel per topic and a count per channel.
struct Mcap<W: Write + Seek> {
    writer: mcap::Writer<W>,
    schemas: BTreeMap<&'static str, u16>,
    channels: BTreeMap<String, u16>,
    sequences: BTreeMap<u16, u32>,
    counts: BTreeMap<String, (String, u64)>,
}

impl<W: Write + Seek> Mcap<W> {
    fn new(out: W) -> mcap::McapResult<Self> {
        let writer = mcap::WriteOptions::new()
            .compression(None)
            .profile("")
            .library(concat!("hnav ", env!("CARGO_PKG_VERSION")))
            .create(out)?;
        Ok(Mcap {
            writer,
            schemas: BTreeMap::new(),
            channels: BTreeMap::new(),
            sequences: BTreeMap::new(),
            counts: BTreeMap::new(),
        })
    }

    fn error(e: mcap::McapError) -> ExportError {
        ExportError::Write {
            path: PathBuf::new(),
            problem: e.to_string(),
        }
    }

    /// The channel of `topic` (made, with its schema, on first use).
    fn channel(&mut self, topic: &str, schema: &'static str) -> Result<u16, ExportError> {
        if let Some(&id) = self.channels.get(topic) {
            return Ok(id);
        }
        let schema_id = match self.schemas.get(schema) {
            Some(&id) => id,
            None => {
                let id = self
                    .writer
                    .add_schema(schema, "jsonschema", &schemas::schema(schema))
                    .map_err(Self::error)?;
                self.schemas.insert(schema, id);
                id
            }
        };
        let id = self
            .writer
            .add_channel(schema_id, topic, "json", &BTreeMap::new())
            .map_err(Self::error)?;
        self.channels.insert(topic.to_string(), id);
        self.counts
            .insert(topic.to_string(), (schema.to_string(), 0));
        Ok(id)
    }

    fn message(
        &mut self,
        topic: &str,
        schema: &'static str,
        t_ns: u64,
        msg: &Value,
    ) -> Result<(), ExportError> {
        let channel_id = self.channel(topic, schema)?;
        let seq = self.sequences.entry(channel_id).or_insert(0);
        *seq += 1;
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: *seq,
            log_time: t_ns,
            publish_time: t_ns,
        };
        let data = serde_json::to_vec(msg).map_err(|e| ExportError::Write {
            path: PathBuf::new(),
            problem: e.to_string(),
        })?;
        self.writer
            .write_to_known_channel(&header, &data)
            .map_err(Self::error)?;
        if let Some(c) = self.counts.get_mut(topic) {
            c.1 += 1;
        }
        Ok(())
    }

    /// Writes the summary and footer, flushes the file and returns the counts.
    fn finish(mut self) -> Result<BTreeMap<String, (String, u64)>, String> {
        self.writer.finish().map_err(|e| e.to_string())?;
        self.writer
            .into_inner()
            .flush()
            .map_err(|e| e.to_string())?;
        Ok(self.counts)
    }
}
