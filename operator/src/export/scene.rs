//! The channels the live view shows too (`/scene`, `/robots/<i>/stats`, `/log`), from the
//! recording and the log through the live view's own [`SceneFold`]: ground truth of one
//! sampling time folded as one [`Truth`], each round record as its [`Commit`], each
//! lifecycle record as its event, all in time order (a record at `round x period`, before
//! the truth of the same time, as a live run publishes a commit before its robots move).

use std::io::{Seek, Write};
use std::path::Path;

use super::{ExportError, Mcap, RunInfo};
use crate::channels::scene::{Picture, SceneFold};
use crate::channels::{self, Message};
use crate::recording::world::RecordedWorld;
use crate::recording::{PoseSource, TrajectoryReader};
use hnav_runtime::consensus_log::Record;
use hnav_runtime::grid::Grid;
use hnav_runtime::msg::{Commit, Pose, Truth};

/// Writes the channels [`channels::shown`] lists that come from the fold, from the
/// trajectories at `path` and `records`.
pub(super) fn write(
    w: &mut Mcap<impl Write + Seek>,
    path: &Path,
    records: &[Record],
    info: &RunInfo,
    cell_m: f64,
) -> Result<(), ExportError> {
    let header = &info.header;
    let grid = match &info.scenario {
        Some(s) => s.map.grid.clone(),
        None => Grid::new(header.width, header.height).map_err(|e| ExportError::Write {
            path: path.to_path_buf(),
            problem: e.to_string(),
        })?,
    };
    let goals = header.agents.iter().map(|a| a.goal).collect();
    let mut folding = Folding {
        fold: SceneFold::new(Picture {
            grid,
            goals,
            cell_m,
        }),
        records,
        next: 0,
        period_ns: info.period_ns,
        commit: Commit::default(),
    };
    let mut r = TrajectoryReader::open(path)?;
    let mut truth = Truth {
        poses: vec![Pose::default(); usize::from(r.header().robots)],
        ..Truth::default()
    };
    let mut at: Option<u64> = None;
    // The recorder writes a time's movers after its truth: they are in before it is folded.
    let mut world = RecordedWorld::new(folding.fold.picture().grid.clone(), Vec::new(), cell_m);
    while let Some(s) = r.next_sample()? {
        if s.source == PoseSource::Mover {
            world.place_mover(u32::from(s.robot), s.pose());
            folding.fold.movers(world.movers());
            continue;
        }
        if s.source != PoseSource::Truth {
            continue;
        }
        if at.is_some_and(|t| t != s.t_ns) {
            folding.truth(w, &mut truth)?;
        }
        at = Some(s.t_ns);
        truth.sim_time_ns = s.t_ns;
        if let Some(p) = truth.poses.get_mut(usize::from(s.robot)) {
            *p = s.pose();
        }
    }
    if at.is_some() {
        folding.truth(w, &mut truth)?;
    }
    folding.records_until(w, u64::MAX)
}

struct Folding<'a> {
    fold: SceneFold,
    records: &'a [Record],
    next: usize,
    period_ns: u64,
    commit: Commit,
}

impl Folding<'_> {
    /// Folds the records up to `truth`'s time, then `truth`.
    fn truth(
        &mut self,
        w: &mut Mcap<impl Write + Seek>,
        truth: &mut Truth,
    ) -> Result<(), ExportError> {
        self.records_until(w, truth.sim_time_ns)?;
        for m in self.fold.truth(truth.view()) {
            put(w, &m)?;
        }
        Ok(())
    }

    /// Folds the records of rounds decided at or before `t_ns`.
    fn records_until(
        &mut self,
        w: &mut Mcap<impl Write + Seek>,
        t_ns: u64,
    ) -> Result<(), ExportError> {
        while let Some(r) = self.records.get(self.next) {
            let Some(round) = r.round() else {
                self.next += 1;
                continue;
            };
            let t = round.saturating_mul(self.period_ns);
            if t > t_ns {
                break;
            }
            self.next += 1;
            match r {
                Record::Round(rec) => {
                    rec.write_commit(&mut self.commit);
                    for m in self.fold.commit(t, self.commit.view()) {
                        put(w, &m)?;
                    }
                }
                Record::Lifecycle(l) => {
                    if let Some(m) = self.fold.lifecycle(t, l.role, l.index, l.event) {
                        put(w, &m)?;
                    }
                }
                _ => {}
            }
        }
        Ok(())
    }
}

fn put(w: &mut Mcap<impl Write + Seek>, m: &Message) -> Result<(), ExportError> {
    w.message(&m.topic, m.schema, m.t_ns, &m.body)
}

/// Registers every channel of [`channels::shown`] for `robots`, so an export lists what the
/// live view advertises even where a channel got no message.
pub(super) fn register(w: &mut Mcap<impl Write + Seek>, robots: usize) -> Result<(), ExportError> {
    for c in channels::shown(robots) {
        w.channel(&c.topic, c.schema)?;
    }
    Ok(())
}
