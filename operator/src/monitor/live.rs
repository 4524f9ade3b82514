//! The live feed: a running swarm read the way any client reads it.
//!
//! The run is found in the run registry `hnav ps` and `hnav kill` read ([`find_run`]), and
//! its scenario is loaded from the command line the supervisor recorded there, checked
//! against the scenario hash of the run's log header when there is one. The feed opens one
//! subscriber on each of `truth`, `commit`, `progress` and `lifecycle` with the run's QoS
//! (every one keeps room for observers, see `topics`) and never publishes. It reads with
//! non-blocking receives when the viewer asks ([`Feed::pump`]): the topics are "latest"
//! services without back-pressure, so a slow viewer loses the oldest samples and never
//! holds up a publisher. Between pumps it sleeps on its lifecycle receiver with a deadline
//! ([`SingleWaiter`](hnav_runtime::transport::SingleWaiter)), woken early only by a lifecycle
//! event (a death, a restart, `Stop`) or a termination signal.
//!
//! Progress and lifecycle are drained before ground truth and commits: a `done` or a `Stop`
//! seen in a pump then comes with every pose the sim published before it. The registry is
//! looked at once a second, for the health rows and to notice a supervisor that is gone.

use std::path::Path;
use std::time::{Duration, Instant};

use super::feed::RunInfo;
use super::feed::{Feed, FeedError, RunEnd, Update, Waited};
use super::health::{HealthRow, HealthSampler};
use crate::supervisor::registry::LiveRunError;
use crate::supervisor::registry::{RunRecord, RunRegistry};
use hnav_runtime::consensus_log::reader::LogReader;
use hnav_runtime::consensus_log::record::Record;
use hnav_runtime::msg::{CommitView, Lifecycle, MoverPlace, MoversHeader, Progress, TruthView};
use hnav_runtime::topics::{self, CommitReceiver, TruthReceiver, ViewsReceiver};
use hnav_runtime::transport::{Receiver, RunId, SliceReceiver, Transport, TransportError, Wake};

/// How often the registry and `/proc` are read for the health rows.
pub const HEALTH_PERIOD: Duration = Duration::from_secs(1);

/// The live run `arg` names in `registry`: a run id, or the run directory of one (as its
/// path, from here); with no `arg`, the only live run.
pub fn find_run(registry: &RunRegistry, arg: Option<&str>) -> Result<RunRecord, FeedError> {
    let Some(arg) = arg else {
        let live: Vec<RunRecord> = registry
            .list_runs()
            .into_iter()
            .filter(|e| !e.stale)
            .map(|e| e.record)
            .collect();
        return match <[RunRecord; 1]>::try_from(live) {
            Ok([only]) => Ok(only),
            Err(live) if live.is_empty() => Err(FeedError::NoRuns {
                dir: registry.dir().to_path_buf(),
            }),
            Err(live) => Err(FeedError::SeveralRuns {
                runs: live
                    .iter()
                    .map(|r| format!("{} ({})", r.run_id, r.dir.display()))
                    .collect(),
            }),
        };
    };
    match registry.find_live(arg) {
        Ok((_, record)) => return Ok(record),
        Err(LiveRunError::UnknownRun { .. } | LiveRunError::RunId(_)) => {}
        Err(e) => return Err(e.into()),
    }
    let wanted = Path::new(arg).canonicalize().ok();
    let found = registry.list_runs().into_iter().find(|e| {
        let dir = e
            .record
            .parsed_process_args()
            .and_then(|a| a.dir)
            .unwrap_or_else(|| e.record.dir.clone());
        wanted.is_some() && dir.canonicalize().ok() == wanted
    });
    match found {
        Some(e) => {
            let id = e.record.run().map_err(LiveRunError::from)?;
            Ok(registry.find_live_id(&id)?)
        }
        None => Err(FeedError::NotFound {
            run: arg.to_string(),
            dir: registry.dir().to_path_buf(),
        }),
    }
}

/// A live run's topics, read without back-pressure. See the [module docs](self).
pub struct LiveFeed {
    info: RunInfo,
    registry: RunRegistry,
    run: RunId,
    truth: TruthReceiver,
    commit: CommitReceiver,
    progress: Receiver<Progress>,
    life: Receiver<Lifecycle>,
    /// Each robot's view, with `[sensing]`.
    views: Vec<ViewsReceiver>,
    /// The movers' places, in a run with movers.
    movers: Option<SliceReceiver<MoverPlace, MoversHeader>>,
    sampler: HealthSampler,
    rows: Vec<HealthRow>,
    next_health: Instant,
    ended: bool,
    // Declared last: the receivers above are dropped before the node they belong to.
    transport: Transport,
}

impl LiveFeed {
    /// Opens the feed of the live run `arg` names in `registry` ([`find_run`]).
    pub fn open(registry: &RunRegistry, arg: Option<&str>) -> Result<LiveFeed, FeedError> {
        let record = find_run(registry, arg)?;
        let run_id = record.run_id.clone();
        let args = record
            .parsed_process_args()
            .ok_or_else(|| FeedError::NoScenario {
                run: run_id.clone(),
            })?;
        let scenario = args.scenario().map_err(|source| FeedError::Scenario {
            run: run_id.clone(),
            source,
        })?;
        let log = args.dir.as_deref().unwrap_or(&record.dir).join("log");
        if let Some(logged) = logged_scenario_hash(&log) {
            let now = scenario.scenario_hash();
            if now != logged {
                return Err(FeedError::ScenarioChanged {
                    run: run_id,
                    path: args.scenario,
                    now,
                    logged,
                });
            }
        }
        let transport_err = |source: TransportError| FeedError::Transport {
            run: run_id.clone(),
            source,
        };
        let run = record.run().map_err(transport_err)?;
        let transport = Transport::builder(&run)
            .node_name("hnav-top")
            .create()
            .map_err(transport_err)?;
        let n = scenario.agents.len();
        let open = || -> Result<_, TransportError> {
            Ok((
                transport.slice_receiver(topics::TRUTH, topics::state_qos())?,
                transport.slice_receiver(topics::COMMIT, topics::commit_qos(n))?,
                transport.receiver::<Progress>(topics::PROGRESS, topics::progress_qos())?,
                transport.receiver::<Lifecycle>(topics::LIFECYCLE, topics::lifecycle_qos(n))?,
            ))
        };
        let (truth, commit, progress, life) = open().map_err(transport_err)?;
        let views = match scenario.sensing {
            Some(_) => (scenario.run.agent_processes(n))
                .map(|(first, _)| {
                    transport.slice_receiver(&topics::view(first as usize), topics::state_qos())
                })
                .collect::<Result<Vec<_>, _>>()
                .map_err(transport_err)?,
            None => Vec::new(),
        };
        let movers = (scenario.movers().next().is_some())
            .then(|| transport.slice_receiver(topics::MOVERS, topics::truth_qos()))
            .transpose()
            .map_err(transport_err)?;
        Ok(LiveFeed {
            info: RunInfo::of(&run_id, &scenario),
            registry: registry.clone(),
            run,
            truth,
            commit,
            progress,
            life,
            views,
            movers,
            sampler: HealthSampler::new(),
            rows: Vec::new(),
            next_health: Instant::now(),
            ended: false,
            transport,
        })
    }

    fn err(&self, source: TransportError) -> FeedError {
        FeedError::Transport {
            run: self.run.as_str().to_string(),
            source,
        }
    }

    /// Samples the health rows when they are due; `Some` when the supervisor is gone.
    fn health(&mut self, apply: &mut dyn FnMut(Update<'_>)) -> Option<RunEnd> {
        let now = Instant::now();
        if now < self.next_health {
            return None;
        }
        self.next_health = now + HEALTH_PERIOD;
        match self.registry.find_live_id(&self.run) {
            Ok(record) => {
                self.sampler.sample(&record, now, &mut self.rows);
                apply(Update::Health(&self.rows));
                None
            }
            Err(LiveRunError::UnknownRun { .. } | LiveRunError::DeadRun { .. }) => {
                Some(RunEnd::SupervisorGone)
            }
            Err(e) => {
                tracing::warn!("run registry: {e}");
                None
            }
        }
    }
}

impl Feed for LiveFeed {
    fn info(&self) -> &RunInfo {
        &self.info
    }

    fn wait(&mut self, until: Instant) -> Result<Waited, FeedError> {
        if self.ended {
            return Ok(Waited::Ready);
        }
        // The lifecycle is the one source the feed sleeps on (the rest is read at `until`).
        let wake = self.transport.single_waiter(&self.life).wait(Some(until));
        Ok(match wake.map_err(|e| self.err(e))? {
            Wake::Stop => Waited::Stop,
            Wake::Data | Wake::TimedOut => Waited::Ready,
        })
    }

    fn pump(&mut self, apply: &mut dyn FnMut(Update<'_>)) -> Result<(), FeedError> {
        if self.ended {
            return Ok(());
        }
        let mut end = None;
        let progress = self.progress.drain_pending(|p| {
            match p.done {
                Progress::ALL_AT_GOAL => end = end.or(Some(RunEnd::AllAtGoal)),
                Progress::TIME_LIMIT => end = end.or(Some(RunEnd::TimeLimit)),
                _ => {}
            }
            apply(Update::Progress(p));
        });
        progress.map_err(|e| self.err(e))?;
        let life = self.life.drain_pending(|l| {
            if l.event == hnav_runtime::msg::LifecycleEvent::Stop as u8 {
                end = end.or(Some(RunEnd::Stopped));
            }
            apply(Update::Lifecycle(l));
        });
        life.map_err(|e| self.err(e))?;
        let truth = (self.truth).drain_pending(|h, p| apply(Update::Truth(TruthView::new(h, p))));
        truth.map_err(|e| self.err(e))?;
        let commits =
            (self.commit).drain_pending(|h, d| apply(Update::Commit(CommitView::new(h, d))));
        commits.map_err(|e| self.err(e))?;
        for rx in &self.views {
            // The newest sample is what the process's robots see now; older ones are gone
            // already. Handed on in place.
            let newest = rx.take_newest().map_err(|e| self.err(e))?;
            for v in newest.iter().flat_map(|s| s.payload()) {
                apply(Update::View(v));
            }
        }
        if let Some(rx) = &self.movers {
            // Only the newest sample counts; it is handed on in place.
            if let Some(sample) = &rx.take_newest().map_err(|e| self.err(e))? {
                apply(Update::Movers(sample.payload()));
            }
        }
        if end.is_none() {
            end = self.health(apply);
        }
        if let Some(why) = end {
            self.ended = true;
            apply(Update::Ended(why));
        }
        Ok(())
    }
}

impl std::fmt::Debug for LiveFeed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LiveFeed")
            .field("run", &self.run.as_str())
            .field("node", &self.transport.node().name())
            .field("ended", &self.ended)
            .finish_non_exhaustive()
    }
}

/// The scenario hash in the header of the log in `dir`, if it has one yet.
fn logged_scenario_hash(dir: &Path) -> Option<u64> {
    let mut reader = LogReader::open(dir).ok()?;
    match reader.next_record().ok()?? {
        (_, Record::Header(h)) => Some(h.scenario_hash),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::launch::ProcessArgs;

    /// Registers run `id` in `dir` with this process as its supervisor.
    fn register(registry: &RunRegistry, id: &str, dir: &Path) {
        let mut record = registry.new_record(&RunId::new(id).unwrap(), dir);
        record.set_process_args(&ProcessArgs {
            dir: Some(dir.to_path_buf()),
            ..ProcessArgs::new(id, "demo.toml")
        });
        record.write().unwrap();
    }

    #[test]
    fn a_run_is_found_by_id_by_directory_or_as_the_only_one() {
        let tmp = tempfile::tempdir().unwrap();
        let registry = RunRegistry::at(tmp.path().join("runs"));
        let found = |arg| find_run(&registry, arg).map(|r| r.run_id);
        let e = found(None).unwrap_err().to_string();
        assert!(e.starts_with("no live run in the run registry"), "{e}");
        let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
        std::fs::create_dir_all(&a).unwrap();
        std::fs::create_dir_all(&b).unwrap();
        register(&registry, "top-a", &a);
        assert_eq!(found(None).unwrap(), "top-a");
        register(&registry, "top-b", &b);
        let e = found(None).unwrap_err().to_string();
        assert!(
            e.starts_with("2 live runs, name one (`hnav top RUN`): "),
            "{e}"
        );
        assert!(e.contains("top-a (") && e.contains("top-b ("), "{e}");
        assert_eq!(found(Some("top-b")).unwrap(), "top-b");
        assert_eq!(found(Some(b.to_str().unwrap())).unwrap(), "top-b");
        let e = found(Some("top-c")).unwrap_err().to_string();
        assert!(
            e.starts_with("no live run `top-c` (neither a run id nor"),
            "{e}"
        );
    }
}
