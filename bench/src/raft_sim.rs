//! `hnav-bench raft-sim`: the deterministic simulation of the coordinator's replicated log
//! (`hnav_coordinator::replication::sim`) over a sweep of seeds, or one seed replayed with
//! a given schedule. Prints the table per nemesis (runs, faults injected, commits,
//! violations, slowest recovery after the heal) and, for each failure, its seed, the
//! shortest schedule that still fails, the command that replays it, and the tail of that
//! run's log.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;

use hnav_coordinator::replication::sim::{
    parse, run, shrunk, sweep, text, Config, Failure, Nemesis, Sabotage, Sweep,
};

/// The command line of `hnav-bench raft-sim`.
#[derive(Debug, Args)]
pub struct RaftSimArgs {
    /// How many seeds.
    #[arg(long, value_name = "N", default_value_t = 1000)]
    pub seeds: u64,
    /// The first seed.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub first: u64,
    /// The nemeses (comma-separated), taken in turn by seed: seed S runs under the
    /// (S mod count)th [default: all].
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub nemesis: Vec<Nemesis>,
    /// Replicas, 3 or 5 [default: drawn per seed].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(3..=5))]
    pub replicas: Option<u64>,
    /// Threads.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub jobs: usize,
    /// Replay seed `--first` with this schedule (as a failure prints it) instead of the
    /// drawn one, and print its log.
    #[arg(long, value_name = "SCHEDULE")]
    pub trace: Option<String>,
    /// A deliberate bug, to see the checker find it: `lying-fsync` (the simulated fsync
    /// makes nothing durable), `early-ack` (a record acknowledged when proposed) or
    /// `stale-leader` (a deposed leader carries on instead of restarting).
    #[arg(long, value_name = "BUG")]
    pub sabotage: Option<String>,
    /// Where the runs' journals go [default: /dev/shm, else the system's temp directory].
    #[arg(long, value_name = "DIR")]
    pub scratch: Option<PathBuf>,
}

/// Runs `hnav-bench raft-sim`.
pub fn main(args: RaftSimArgs) -> Result<()> {
    let nemeses = if args.nemesis.is_empty() {
        Nemesis::ALL.to_vec()
    } else {
        args.nemesis.clone()
    };
    let sabotage = match args.sabotage.as_deref() {
        None => Sabotage::None,
        Some(name) => Sabotage::from_name(name).with_context(|| {
            format!("--sabotage {name}: one of lying-fsync, early-ack, stale-leader")
        })?,
    };
    let scratch = match &args.scratch {
        Some(d) => tempfile::tempdir_in(d),
        None => tempfile::tempdir_in("/dev/shm").or_else(|_| tempfile::tempdir()),
    }
    .context("a scratch directory for the runs' journals")?;
    if let Some(trace) = &args.trace {
        return replay(&args, nemeses[0], sabotage, trace, scratch.path());
    }
    let s = Sweep {
        first: args.first,
        seeds: args.seeds,
        nemeses,
        replicas: args.replicas,
        sabotage,
        jobs: args.jobs,
    };
    let report = sweep(&s, scratch.path(), &|done| {
        hnav_runtime::errln!("{done} of {} seeds", s.seeds);
    })
    .context("the sweep's scratch directory")?;
    hnav_runtime::out!("{}", report.table());
    hnav_runtime::outln!(
        "{} seeds ({} to {}), {:.1} s on {} thread(s), {:.2} ms a seed",
        s.seeds,
        s.first,
        s.first + s.seeds.saturating_sub(1),
        report.elapsed.as_secs_f64(),
        s.jobs,
        report.elapsed.as_secs_f64() * 1e3 * s.jobs as f64 / s.seeds.max(1) as f64
    );
    for f in &report.failures {
        print_failure(f);
    }
    if !report.more_failures.is_empty() {
        hnav_runtime::outln!("more failing seeds: {:?}", report.more_failures);
    }
    match report.violations() {
        0 => Ok(()),
        n => bail!("{n} of {} runs broke a property", s.seeds),
    }
}

/// One seed with `trace` as its schedule; a failure shrunk further.
fn replay(
    args: &RaftSimArgs,
    nemesis: Nemesis,
    sabotage: Sabotage,
    trace: &str,
    scratch: &std::path::Path,
) -> Result<()> {
    let mut config = Config {
        replicas: args.replicas,
        sabotage,
        trace: true,
        ..Config::new(args.first, nemesis)
    };
    let schedule = parse(trace, config.replicas()).context("--trace")?;
    config.schedule = Some(schedule);
    let outcome = run(&config, scratch)?;
    for line in &outcome.log {
        hnav_runtime::outln!("{line}");
    }
    hnav_runtime::outln!(
        "seed {} ({} replicas): {} faults, {} commits, recovered {} after the heal",
        config.seed,
        config.replicas(),
        outcome.faults,
        outcome.commits,
        outcome
            .recovered_after
            .map_or("never".into(), |us| format!("{:.2} s", us as f64 / 1e6))
    );
    match &outcome.violation {
        None => Ok(()),
        Some(v) => {
            let v = v.clone();
            print_failure(&shrunk(outcome, scratch)?);
            bail!("{v}")
        }
    }
}

/// Lines of a failing run's log shown.
const TAIL: usize = 40;

fn print_failure(f: &Failure) {
    let c = &f.outcome.config;
    let v = f
        .outcome
        .violation
        .as_ref()
        .expect("a failure has a violation");
    hnav_runtime::outln!(
        "\nFAILED seed {} ({}, {} replicas): {v}",
        c.seed,
        c.nemesis.name(),
        c.replicas()
    );
    hnav_runtime::outln!("  schedule: {}", text(&f.outcome.schedule));
    match &f.shrunk.violation {
        Some(sv) => {
            hnav_runtime::outln!(
                "  shortest schedule that fails: {}",
                text(&f.shrunk.schedule)
            );
            hnav_runtime::outln!("  it fails with: {sv}");
        }
        None => hnav_runtime::outln!("  (the shrunk schedule no longer fails with its log on)"),
    }
    hnav_runtime::outln!("  replay: {}", f.command());
    let log = &f.shrunk.log;
    hnav_runtime::outln!("  its last {} events:", TAIL.min(log.len()));
    for line in &log[log.len().saturating_sub(TAIL)..] {
        hnav_runtime::outln!("    {line}");
    }
}
