//! `hnav-bench round`: the decision round's latency against a real `hnav-coordinator`, and
//! (`--faults`) fault-detection and rejoin latency.
//!
//! ## Round latency
//!
//! For each swarm size and fsync policy: a scenario (an open 36 x 36 map, the agents of
//! `layout`, `[coordinator] fsync`, lockstep clock) is written to a temporary directory,
//! the real `hnav-coordinator` next to this executable is started on it, and this process
//! plays the supervisor's start-up handshake and all N agents: one candidate publisher and
//! one commit subscriber per agent, as each real agent has.
//!
//! A round: every agent's candidate is sent through its own publisher; the clock starts just
//! before the N-th `send` (publish + notify) is called; it stops when the last of the N commit
//! subscribers has taken commit r, all N blocking in one `Waiter` (no polling, no sleeps).
//! The time therefore includes: the last candidate's publish and notification, the
//! coordinator's wake-up and reading of the candidates, the
//! conflict resolution (`layout`'s rounds have real crossing conflicts, no global
//! replans), encoding and appending the round to the consensus log plus its `fdatasync`
//! under `every-record`, publishing the commit to N subscribers and notifying N listeners,
//! and this thread's wake-up and N takes. It excludes the agents' own work (neural map,
//! wheel control), and the N subscribers are served by one thread instead of N processes.
//! The commit is published only after its log record is written, so fsync sits on the path.
//!
//! **Stalls.** A round without any commit for 1 s is poked: a lifecycle event the coordinator
//! ignores wakes it, and the round then completes at once: every candidate had arrived but
//! the coordinator had not been woken (a lost wake-up on the candidates topic's event
//! service). Such rounds are counted in the `stalled` column and left out of the percentiles;
//! in a real lockstep run nothing would wake the coordinator and the swarm would hang.
//!
//! ## Faults
//!
//! See `faults`: SIGKILL -> exit-descriptor wake-up -> `Down` published -> `Down` taken by
//! another thread; `Restarted` -> the restarted agent's first decision.

mod faults;
mod layout;
mod observers;
mod report;
mod session;
mod swarm;

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;

use hnav_runtime::scenario::FsyncPolicy;

use observers::Observers;
use report::{Dist, RoundPoint};
use session::CoordinatorSetup;
use swarm::keep_going;

pub use layout::MAX_AGENTS;

/// Measured rounds per point by default.
pub const ROUNDS_FULL: u64 = 2000;
/// Measured rounds per point with `--quick`.
pub const ROUNDS_QUICK: u64 = 300;

/// The command line of `hnav-bench round`.
#[derive(Debug, Args)]
pub struct RoundArgs {
    /// Swarm sizes (comma-separated, 1 to 256 agents).
    #[arg(long, value_delimiter = ',', value_name = "N",
          default_values_t = [1usize, 8, 32, 128, 256], conflicts_with = "faults")]
    pub agents: Vec<usize>,
    /// Measured rounds per point [default: 2000, 300 with --quick].
    #[arg(long, value_name = "N", conflicts_with = "faults")]
    pub rounds: Option<u64>,
    /// Warm-up rounds per point, not measured.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 100,
        conflicts_with = "faults"
    )]
    pub warmup: u64,
    /// 300 measured rounds per point instead of 2000.
    #[arg(long)]
    pub quick: bool,
    /// The coordinator's fsync policies (every-record, batched, none; comma-separated).
    #[arg(long, value_delimiter = ',', value_name = "POLICY",
          default_values = ["every-record", "none"], value_parser = parse_fsync)]
    pub fsync: Vec<FsyncPolicy>,
    /// Coordinator cluster sizes (comma-separated: 1 = one coordinator, 3 or 5 = Raft
    /// replicas; the leader commits a round once a majority has it durable).
    #[arg(long, value_delimiter = ',', value_name = "N", default_values_t = [1u32],
          value_parser = parse_replicas, conflicts_with = "faults")]
    pub replicas: Vec<u32>,
    /// The observers each point runs with, one row each (comma-separated): none, ros2 (the
    /// `hnav run --ros2` publisher beside the run), foxglove (the `--foxglove` live view),
    /// ros2+foxglove. `none,ros2+foxglove` measures what both add, in one run.
    #[arg(long, value_delimiter = ',', value_name = "SET", default_values = ["none"],
          value_parser = Observers::parse, conflicts_with = "faults")]
    pub observers: Vec<Observers>,
    /// Robots per agent process, one row each (comma-separated): 1 is one process per
    /// robot (the default), 16 is `[run] agents_per_process = 16`: 128 agents then have 8
    /// commit subscribers, each process sending its robots' candidates with one wake-up.
    #[arg(long, value_delimiter = ',', value_name = "K", default_values_t = [1usize],
          conflicts_with = "faults")]
    pub agents_per_process: Vec<usize>,
    /// One JSON object per line instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Also write DIR/round.csv (or DIR/faults.csv); DIR is created if missing.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Measure fault detection (SIGKILL -> Down) and rejoin (Restarted -> decision) instead.
    #[arg(long)]
    pub faults: bool,
    /// Trials per fault measurement.
    #[arg(long, value_name = "N", default_value_t = 50, requires = "faults")]
    pub trials: usize,
}

fn parse_fsync(s: &str) -> Result<FsyncPolicy, String> {
    match s {
        "every-record" => Ok(FsyncPolicy::EveryRecord),
        "batched" => Ok(FsyncPolicy::Batched),
        "none" => Ok(FsyncPolicy::None),
        other => Err(format!(
            "unknown fsync policy {other:?}: expected every-record, batched or none"
        )),
    }
}

fn parse_replicas(s: &str) -> Result<u32, String> {
    match s {
        "1" => Ok(1),
        "3" => Ok(3),
        "5" => Ok(5),
        other => Err(format!(
            "{other:?} replicas: a coordinator cluster has 1, 3 or 5 members"
        )),
    }
}

/// Runs `hnav-bench round` with `args`, printing as it goes.
pub fn main(args: RoundArgs) -> Result<()> {
    if let Some(&n) = args.agents.iter().find(|&&n| n == 0 || n > MAX_AGENTS) {
        bail!("--agents {n}: each swarm size must be 1 to {MAX_AGENTS}");
    }
    if args.fsync.is_empty() {
        bail!("--fsync needs at least one policy");
    }
    if args.observers.is_empty() {
        bail!("--observers needs at least one set");
    }
    if args.replicas.is_empty() {
        bail!("--replicas needs at least one cluster size");
    }
    let max = hnav_runtime::scenario::RunParams::MAX_AGENTS_PER_PROCESS as usize;
    if let Some(k) = args.agents_per_process.iter().find(|&&k| k == 0 || k > max) {
        bail!("--agents-per-process {k}: must be 1 to {max}");
    }
    if args.rounds == Some(0) {
        bail!("--rounds must be at least 1");
    }
    if args.trials == 0 {
        bail!("--trials must be at least 1");
    }
    let program = session::coordinator_binary()?;
    if args.faults {
        faults_cmd(&args, &program)
    } else {
        round_cmd(&args, &program)
    }
}

fn round_cmd(args: &RoundArgs, program: &std::path::Path) -> Result<()> {
    let rounds = args.rounds.unwrap_or(if args.quick {
        ROUNDS_QUICK
    } else {
        ROUNDS_FULL
    });
    if args.fsync.iter().any(|&f| f != FsyncPolicy::None) {
        // The floor of every-record: what one append + fdatasync costs on the log's disk.
        let d = fdatasync_baseline()?;
        let dir = std::env::temp_dir();
        if args.json {
            hnav_runtime::outln!(
                "{}",
                serde_json::json!({
                    "bench": "fdatasync",
                    "dir": dir.display().to_string(),
                    "p50_us": report::us1(d.p50_ns),
                    "p99_us": report::us1(d.p99_ns),
                    "max_us": report::us1(d.max_ns),
                    "n": d.n,
                })
            );
        } else {
            hnav_runtime::outln!(
                "raw 1 KiB append + fdatasync in {}: p50 {:.1} µs, p99 {:.1} µs, max {:.1} µs \
                 ({} samples)",
                dir.display(),
                d.p50_ns as f64 / 1e3,
                d.p99_ns as f64 / 1e3,
                d.max_ns as f64 / 1e3,
                d.n
            );
        }
    }
    if !args.json {
        hnav_runtime::outln!(
            "decision round: last of N candidates sent -> commit taken by all N agents' \
             subscribers"
        );
        hnav_runtime::outln!("{}", report::round_header());
    }
    let mut points = Vec::new();
    for &agents in &args.agents {
        for &fsync in &args.fsync {
            let rows = (args.replicas.iter()).flat_map(|r| {
                (args.observers.iter())
                    .flat_map(move |o| (args.agents_per_process.iter()).map(move |k| (*r, *o, *k)))
            });
            for (replicas, observers, per_process) in rows {
                hnav_runtime::errln!(
                    "round: {agents} agents ({per_process} per process), fsync {}, \
                     {replicas} coordinator(s), observers {}: {} warm-up + {rounds} measured \
                     rounds",
                    layout::fsync_name(fsync),
                    observers.name(),
                    args.warmup
                );
                let setup = CoordinatorSetup {
                    fsync,
                    replicas,
                    observers,
                    per_process,
                };
                let point = measure_point(program, agents, setup, args.warmup, rounds)?;
                if args.json {
                    hnav_runtime::outln!("{}", point.json());
                } else {
                    hnav_runtime::outln!("{}", point.row());
                }
                points.push(point);
            }
        }
    }
    if !args.json {
        hnav_runtime::outln!(
            "(p50/p99/max: from just before the N-th candidate's send to the N-th commit \
             taken; 1st: to the first commit taken, i.e. without the fan-out to N subscribers; \
             includes \
             the coordinator's wake-up, conflict resolution, consensus-log append and its \
             fdatasync under every-record (log in {}), the commit's publish + N notifications, \
             one thread taking the N commits; with 3 or 5 replicas also the leader's Raft \
             round trip (append to the followers over shared memory, each follower's durable \
             append, the majority's acknowledgement) before the commit is published; \
             excludes the agents' planning. stalled: rounds \
             with no commit for 1 s that completed only when an unrelated lifecycle event woke \
             the coordinator (lost wake-up); left out of the percentiles)",
            std::env::temp_dir().display()
        );
    }
    if let Some(dir) = &args.out {
        let path = report::write_round_csv(dir, &points)?;
        hnav_runtime::errln!("wrote {}", path.display());
    }
    Ok(())
}

/// 200 appends of 1 KiB, each followed by `fdatasync`, in a file of the temporary directory
/// (where the benchmark's consensus logs live).
fn fdatasync_baseline() -> Result<Dist> {
    use std::io::Write;
    let path = std::env::temp_dir().join(format!(
        "hnav-bench-fdatasync-{}",
        hnav_runtime::transport::RunId::unique("f").as_str()
    ));
    let measured = (|| -> Result<Vec<u64>> {
        let mut f = std::fs::File::create(&path)?;
        let block = [0x5au8; 1024];
        let mut ns = Vec::with_capacity(200);
        for _ in 0..200 {
            f.write_all(&block)?;
            let t = std::time::Instant::now();
            f.sync_data()?;
            ns.push(u64::try_from(t.elapsed().as_nanos()).unwrap_or(u64::MAX));
        }
        Ok(ns)
    })();
    let _ = std::fs::remove_file(&path);
    let ns = measured.with_context(|| format!("fdatasync baseline in {}", path.display()))?;
    Dist::from_ns(&ns)
}

/// Runs one coordinator (or cluster) for `agents` agents, plays `warmup` + `rounds` rounds.
fn measure_point(
    program: &std::path::Path,
    agents: usize,
    setup: CoordinatorSetup,
    warmup: u64,
    rounds: u64,
) -> Result<RoundPoint> {
    let ns = |d: std::time::Duration| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX);
    let (all, first, stalled) =
        session::with_coordinator(program, agents, setup, |session, swarm| {
            let (coordinator, life) = (session.coordinators(), session.lifecycle());
            if warmup > 0 {
                swarm.play(coordinator, life, warmup, |_| Ok(()), keep_going)?;
            }
            let mut all = Vec::with_capacity(rounds as usize);
            let mut first = Vec::with_capacity(rounds as usize);
            let mut stalled = 0;
            swarm.play(
                coordinator,
                life,
                rounds,
                |_| Ok(()),
                |obs| {
                    if obs.stalled {
                        stalled += 1;
                    } else {
                        all.push(ns(obs.all_in - obs.sent));
                        first.push(ns(obs.first_in - obs.sent));
                    }
                    keep_going(obs)
                },
            )?;
            Ok((all, first, stalled))
        })?;
    Ok(RoundPoint {
        agents,
        fsync: setup.fsync,
        replicas: setup.replicas,
        observers: setup.observers,
        per_process: setup.per_process,
        dist: Dist::from_ns(&all)?,
        first: Dist::from_ns(&first)?,
        stalled,
    })
}

fn faults_cmd(args: &RoundArgs, program: &std::path::Path) -> Result<()> {
    if !args.json {
        hnav_runtime::outln!("{}", report::fault_header());
    }
    let points = faults::run(program, args.trials, &args.fsync, |p| {
        if args.json {
            hnav_runtime::outln!("{}", p.json());
        } else {
            hnav_runtime::outln!("{}", p.row());
        }
    })?;
    if !args.json {
        hnav_runtime::outln!(
            "(a)/(b) from just before kill(2) of `sleep 60` spawned by the supervisor's Child; \
             (b1) includes waitpid and the publish; the dead node's iceoryx2 clean-up is not \
             included. (c) from publishing Restarted (the agent's ports already open) to its \
             subscriber taking the first commit with its decision: includes the coordinator \
             logging the lifecycle record and the round; excludes the restarted process's \
             start-up and the restart backoff."
        );
    }
    if let Some(dir) = &args.out {
        let path = report::write_fault_csv(dir, &points)?;
        hnav_runtime::errln!("wrote {}", path.display());
    }
    Ok(())
}
