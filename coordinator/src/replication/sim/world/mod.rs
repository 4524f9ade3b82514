//! The scheduler ([`run`]): one seeded run of a simulated cluster. It owns time: a queue of
//! events (ticks, message deliveries, the nemesis's actions and their ends, restarts, the
//! heal), taken in time order, ties in the order they were queued, so that a seed and a
//! schedule give the same run every time.
//!
//! A run starts every replica at time 0, lets the nemesis act in its window, heals
//! everything at [`HEAL`], and then waits for the liveness it promises: a record proposed
//! after the heal acknowledged within [`LIVENESS`], and every replica caught up with it
//! within [`CATCH_UP`] more. It stops at the first violation.
//!
//! | file | what it adds to the run |
//! |---|---|
//! | `calls` | a call into a replica and what follows it: messages sent, entries applied, the coordinator's proposals and acknowledgements, crashes and restarts |
//! | `faults` | the nemesis's actions, their ends, and the heal |

mod calls;
mod faults;

use std::cmp::Ordering;
use std::collections::{BTreeMap, BinaryHeap};
use std::path::{Path, PathBuf};

use raft::eraftpb::Message;

use super::super::peer::ReplicaConfig;
use super::checker::{Checker, Property, Violation};
use super::clock::Time;
use super::disk::SimDisk;
use super::nemesis::{schedule, Event, Nemesis, NetFault};
use super::network::Network;
use super::node::Node;
use super::rng::Rng;

/// Microseconds between a replica's ticks: the coordinator's default `raft_heartbeat_ms`.
pub const TICK_US: u64 = 50_000;

/// Ticks to an election: the coordinator's default `election_ms` over `raft_heartbeat_ms`.
pub const ELECTION_TICKS: usize = 10;

/// Committed entries after which a replica snapshots and compacts its journal: small, so
/// that compaction, and a leader's snapshot sent to a replica left behind, happen under the
/// nemeses of every run.
pub const SNAPSHOT_ENTRIES: u64 = 8;

/// When every fault ends.
pub const HEAL: Time = Time::ms(6_000);

/// The bound on liveness: after the heal, a record proposed then is acknowledged within
/// this long.
pub const LIVENESS: u64 = 10_000_000;

/// After that commit, every replica has handed it out within this long.
pub const CATCH_UP: u64 = 5_000_000;

/// A deliberate bug, to show that the checker finds one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Sabotage {
    /// None: the real code as it is.
    #[default]
    None,
    /// The simulated disk's fsync reports success and makes nothing durable, so that a
    /// power loss takes acknowledged votes and entries.
    LyingFsync,
    /// The simulated coordinator acknowledges a record when it proposes it, before a
    /// majority holds it.
    EarlyAck,
    /// A deposed leader carries on with the state it decided instead of restarting from
    /// its journal.
    StaleLeader,
}

impl Sabotage {
    /// Every deliberate bug.
    pub const ALL: [Sabotage; 3] = [
        Sabotage::LyingFsync,
        Sabotage::EarlyAck,
        Sabotage::StaleLeader,
    ];

    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Sabotage::None => "none",
            Sabotage::LyingFsync => "lying-fsync",
            Sabotage::EarlyAck => "early-ack",
            Sabotage::StaleLeader => "stale-leader",
        }
    }

    /// The bug named `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        Sabotage::ALL.into_iter().find(|s| s.name() == name)
    }
}

/// What to run.
#[derive(Clone, Debug)]
pub struct Config {
    /// The seed every random draw comes from.
    pub seed: u64,
    /// The nemesis whose schedule is drawn (and whose row the run counts in).
    pub nemesis: Nemesis,
    /// Replicas, 3 or 5; `None` draws them from the seed.
    pub replicas: Option<u64>,
    /// The schedule to run instead of the drawn one (a replay, or shrinking).
    pub schedule: Option<Vec<Event>>,
    /// A deliberate bug.
    pub sabotage: Sabotage,
    /// Keep a log of the run's notable events.
    pub trace: bool,
}

impl Config {
    /// Seed `seed` under `nemesis`, everything else drawn.
    pub fn new(seed: u64, nemesis: Nemesis) -> Self {
        Config {
            seed,
            nemesis,
            replicas: None,
            schedule: None,
            sabotage: Sabotage::None,
            trace: false,
        }
    }

    /// The number of replicas: as given, or 3 or 5 drawn from the seed.
    pub fn replicas(&self) -> u64 {
        self.replicas
            .unwrap_or_else(|| Rng::new(self.seed, 1).pick(&[3, 5]))
    }

    /// The schedule: as given, or drawn from the seed.
    pub fn schedule(&self) -> Vec<Event> {
        match &self.schedule {
            Some(s) => s.clone(),
            None => schedule(self.nemesis, self.replicas(), &mut Rng::new(self.seed, 2)),
        }
    }
}

/// How a run went.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Its configuration.
    pub config: Config,
    /// The schedule it ran.
    pub schedule: Vec<Event>,
    /// Faults injected: actions that hit something, disk faults fired, messages the
    /// network dropped, duplicated, delayed or reordered.
    pub faults: u64,
    /// Records acknowledged (proposed, committed, and seen committed by the leader).
    pub commits: u64,
    /// Leaders elected (terms that had one).
    pub elections: u64,
    /// Processes that exited or died (killed, deposed, a failed write or fsync, a power
    /// loss).
    pub crashes: u64,
    /// Snapshots a replica installed from its leader (it was too far behind for entries).
    pub installs: u64,
    /// The first violation.
    pub violation: Option<Violation>,
    /// From the heal to the first commit of a record proposed after it, in microseconds.
    pub recovered_after: Option<u64>,
    /// When the run ended.
    pub end: Time,
    /// The notable events, if traced.
    pub log: Vec<String>,
}

#[derive(Debug)]
enum Ev {
    Tick(usize),
    Deliver(Message),
    Wake(usize, u32),
    Restart(usize),
    Fault(usize),
    End(u64),
    Heal,
}

struct Queued {
    at: Time,
    seq: u64,
    ev: Ev,
}

impl PartialEq for Queued {
    fn eq(&self, other: &Self) -> bool {
        (self.at, self.seq) == (other.at, other.seq)
    }
}

impl Eq for Queued {}

impl PartialOrd for Queued {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Queued {
    /// Reversed: the heap's top is the earliest event.
    fn cmp(&self, other: &Self) -> Ordering {
        (other.at, other.seq).cmp(&(self.at, self.seq))
    }
}

/// What an episode of the nemesis undoes when it ends.
#[derive(Debug)]
enum Undo {
    Links(Vec<(u64, u64)>),
    Net,
    Resume(usize),
    ClockNormal(usize),
}

/// The state of one run.
struct World {
    now: Time,
    queue: BinaryHeap<Queued>,
    seq: u64,
    nodes: Vec<Node>,
    network: Network,
    checker: Checker,
    schedule: Vec<Event>,
    episodes: BTreeMap<u64, Undo>,
    nets: BTreeMap<u64, NetFault>,
    next_episode: u64,
    rng: Rng,
    faults: u64,
    crashes: u64,
    installs: u64,
    sabotage: Sabotage,
    next_record: u64,
    healed: bool,
    /// When a record proposed after the heal was acknowledged, and its index.
    recovered: Option<(Time, u64)>,
    log: Option<Vec<String>>,
}

/// Runs `config` with its journals under `scratch` (removed again afterwards). The
/// replicas' own log lines (a torn tail cut, Raft's warnings) are dropped: a run's notable
/// events are in its trace.
pub fn run(config: &Config, scratch: &Path) -> std::io::Result<Outcome> {
    let quiet = tracing::subscriber::NoSubscriber::default();
    tracing::subscriber::with_default(quiet, || run_quietly(config, scratch))
}

fn run_quietly(config: &Config, scratch: &Path) -> std::io::Result<Outcome> {
    let dir = Scratch::new(scratch.join(format!(
        "raft-sim-{}-{}",
        config.seed,
        config.nemesis.name()
    )))?;
    let n = config.replicas();
    let nodes = (1..=n)
        .map(|id| {
            let rc = ReplicaConfig {
                election_ticks: ELECTION_TICKS,
                heartbeat_ticks: 1,
                snapshot_entries: SNAPSHOT_ENTRIES,
                ..ReplicaConfig::cluster(id, n)
            };
            let lying = config.sabotage == Sabotage::LyingFsync;
            let disk = SimDisk::new(Rng::new(config.seed, 100 + id), lying);
            let rng = Rng::new(config.seed, 200 + id);
            Node::new(rc, dir.0.join(id.to_string()), disk, TICK_US, rng)
        })
        .collect();
    let mut w = World {
        now: Time::default(),
        queue: BinaryHeap::new(),
        seq: 0,
        nodes,
        network: Network::new(n as usize, Rng::new(config.seed, 3)),
        checker: Checker::new(n as usize),
        schedule: config.schedule(),
        episodes: BTreeMap::new(),
        nets: BTreeMap::new(),
        next_episode: 0,
        rng: Rng::new(config.seed, 4),
        faults: 0,
        crashes: 0,
        installs: 0,
        sabotage: config.sabotage,
        next_record: 0,
        healed: false,
        recovered: None,
        log: config.trace.then(Vec::new),
    };
    w.run();
    let disk_faults: u64 = w.nodes.iter().map(|n| n.disk().faults()).sum();
    Ok(Outcome {
        config: config.clone(),
        schedule: w.schedule,
        faults: w.faults + w.network.tally().total() + disk_faults,
        commits: w.checker.acknowledged(),
        elections: w.checker.elections(),
        crashes: w.crashes,
        installs: w.installs,
        violation: w.checker.violation().cloned(),
        recovered_after: w.recovered.map(|(t, _)| t.0 - HEAL.0),
        end: w.now,
        log: w.log.unwrap_or_default(),
    })
}

/// The run's directory, removed when the run is over.
struct Scratch(PathBuf);

impl Scratch {
    fn new(path: PathBuf) -> std::io::Result<Self> {
        if path.exists() {
            std::fs::remove_dir_all(&path)?;
        }
        std::fs::create_dir_all(&path)?;
        Ok(Scratch(path))
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

impl World {
    fn push(&mut self, at: Time, ev: Ev) {
        self.seq += 1;
        self.queue.push(Queued {
            at,
            seq: self.seq,
            ev,
        });
    }

    fn note(&mut self, line: impl FnOnce() -> String) {
        if let Some(log) = &mut self.log {
            log.push(format!("{} {}", self.now, line()));
        }
    }

    fn run(&mut self) {
        for i in 0..self.nodes.len() {
            self.push(Time::default(), Ev::Restart(i));
        }
        for i in 0..self.schedule.len() {
            self.push(self.schedule[i].at, Ev::Fault(i));
        }
        self.push(HEAL, Ev::Heal);
        while let Some(q) = self.queue.pop() {
            self.now = q.at;
            if self.overdue() {
                break;
            }
            self.dispatch(q.ev);
            if self.checker.violation().is_some() || self.caught_up() {
                break;
            }
        }
        if self.checker.violation().is_none() {
            self.finish();
        }
        if let Some(v) = self.checker.violation().cloned() {
            self.note(|| format!("VIOLATION {v}"));
        }
    }

    fn dispatch(&mut self, ev: Ev) {
        match ev {
            Ev::Tick(i) => self.tick(i),
            Ev::Deliver(m) => self.deliver(m),
            Ev::Wake(i, incarnation) => {
                if self.nodes[i].incarnations == incarnation {
                    self.wake(i);
                }
            }
            Ev::Restart(i) => self.restart(i),
            Ev::Fault(k) => {
                let action = self.schedule[k].action.clone();
                self.apply(action);
            }
            Ev::End(e) => self.end(e),
            Ev::Heal => self.heal(),
        }
    }

    fn tick(&mut self, i: usize) {
        if !self.nodes[i].clock.is_due(self.now) {
            return;
        }
        self.tick_now(i);
        let node = &mut self.nodes[i];
        if node.running() {
            if let Some(next) = node.clock.ticked(self.now) {
                self.push(next, Ev::Tick(i));
            }
        }
    }

    fn deliver(&mut self, m: Message) {
        let i = m.to as usize - 1;
        if self.network.is_cut(m.from, m.to) || self.nodes[i].process.is_none() {
            return;
        }
        if self.nodes[i].paused {
            self.nodes[i].hold(m);
            return;
        }
        self.step(i, m);
    }

    /// Whether a liveness bound has passed unmet (a violation if so).
    fn overdue(&mut self) -> bool {
        let late = match self.recovered {
            None if self.now.0 > HEAL.0 + LIVENESS => Some(format!(
                "no record proposed after the heal at {HEAL} was committed within {} s",
                LIVENESS / 1_000_000
            )),
            Some((t, index)) if self.now.0 > t.0 + CATCH_UP => {
                let behind: Vec<String> = self
                    .nodes
                    .iter()
                    .filter(|n| n.process.is_none() || self.checker.handed(n.id) < index)
                    .map(|n| format!("{} at {}", n.id, self.checker.handed(n.id)))
                    .collect();
                Some(format!(
                    "replicas not caught up with index {index} {} s after its commit: {}",
                    CATCH_UP / 1_000_000,
                    behind.join(", ")
                ))
            }
            _ => None,
        };
        let Some(detail) = late else {
            return false;
        };
        self.checker.fail(self.now, Property::Liveness, detail);
        true
    }

    /// Whether the run is done: recovered after the heal, and every replica has handed
    /// out the record that showed it.
    fn caught_up(&self) -> bool {
        let Some((_, index)) = self.recovered else {
            return false;
        };
        self.nodes
            .iter()
            .all(|n| n.process.is_some() && self.checker.handed(n.id) >= index)
    }

    /// The end: the logs compared, the acknowledged records and the applied ones checked.
    fn finish(&mut self) {
        self.check_logs();
        let pending: Vec<(u64, Option<Vec<u8>>)> = self
            .nodes
            .iter()
            .filter_map(|n| {
                let p = n.process.as_ref()?;
                Some((n.id, p.outstanding.as_ref().map(|(d, _)| d.clone())))
            })
            .collect();
        self.checker.finish(self.now, &pending);
    }

    fn check_logs(&mut self) {
        let logs: Vec<_> = self
            .nodes
            .iter()
            .filter_map(|n| Some((n.id, n.log()?)))
            .collect();
        self.checker.logs(self.now, &logs);
    }
}
