//! A sweep ([`sweep`]): seeds `first..first + seeds`, seed `s` under the nemesis
//! `nemeses[s % len]`, on `jobs` threads; a table per nemesis of runs, faults injected,
//! commits, violations and the slowest recovery after the heal; every failure with its
//! seed and its schedule shrunk to the shortest that still fails.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use super::nemesis::{text, Nemesis};
use super::shrink::shrink;
use super::world::{run, Config, Outcome, Sabotage};

/// What to sweep.
#[derive(Clone, Debug)]
pub struct Sweep {
    /// The first seed.
    pub first: u64,
    /// How many seeds.
    pub seeds: u64,
    /// The nemeses, taken in turn by seed.
    pub nemeses: Vec<Nemesis>,
    /// Replicas, 3 or 5; `None` draws them per seed.
    pub replicas: Option<u64>,
    /// A deliberate bug, to show the checker finds it.
    pub sabotage: Sabotage,
    /// Threads.
    pub jobs: usize,
}

/// One nemesis's row.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Row {
    /// Runs.
    pub runs: u64,
    /// Faults injected, over all runs.
    pub faults: u64,
    /// Leaders elected, over all runs.
    pub elections: u64,
    /// Processes that exited or died, over all runs.
    pub crashes: u64,
    /// Records acknowledged, over all runs.
    pub commits: u64,
    /// Snapshots installed from a leader, over all runs.
    pub installs: u64,
    /// Runs that broke a property.
    pub violations: u64,
    /// The slowest recovery after the heal, in microseconds.
    pub slowest_recovery: u64,
}

/// A run that broke a property, and its schedule shrunk.
#[derive(Clone, Debug)]
pub struct Failure {
    /// The run as the sweep made it.
    pub outcome: Outcome,
    /// The shortest schedule found that still fails the same way, re-run with a log.
    pub shrunk: Outcome,
}

impl Failure {
    /// The command that replays the shrunk run.
    pub fn command(&self) -> String {
        let c = &self.shrunk.config;
        let mut cmd = format!(
            "hnav-bench raft-sim --first {} --seeds 1 --nemesis {} --replicas {} --trace '{}'",
            c.seed,
            c.nemesis.name(),
            c.replicas(),
            text(&self.shrunk.schedule)
        );
        if c.sabotage != Sabotage::None {
            cmd += &format!(" --sabotage {}", c.sabotage.name());
        }
        cmd
    }
}

/// What a sweep found.
#[derive(Clone, Debug)]
pub struct Report {
    /// Per nemesis, in the sweep's order.
    pub rows: Vec<(Nemesis, Row)>,
    /// Failures, the first few shrunk.
    pub failures: Vec<Failure>,
    /// Failing seeds beyond those.
    pub more_failures: Vec<u64>,
    /// Wall time.
    pub elapsed: Duration,
}

/// Failures shrunk and shown in full; later ones are listed by seed.
const SHRUNK: usize = 5;

/// Runs the sweep with its journals under `scratch`; `progress` hears the count of runs
/// done now and then.
pub fn sweep(
    s: &Sweep,
    scratch: &Path,
    progress: &(dyn Fn(u64) + Sync),
) -> std::io::Result<Report> {
    let started = Instant::now();
    let next = AtomicU64::new(0);
    let rows = Mutex::new(vec![Row::default(); s.nemeses.len()]);
    let failed = Mutex::new(Vec::new());
    let error = Mutex::new(None);
    std::thread::scope(|scope| {
        for _ in 0..s.jobs.max(1) {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                if k >= s.seeds {
                    return;
                }
                let seed = s.first + k;
                let which = (seed % s.nemeses.len() as u64) as usize;
                let config = Config {
                    replicas: s.replicas,
                    sabotage: s.sabotage,
                    ..Config::new(seed, s.nemeses[which])
                };
                let outcome = match run(&config, scratch) {
                    Ok(o) => o,
                    Err(e) => {
                        *error.lock().expect("no thread panics holding it") = Some(e);
                        return;
                    }
                };
                {
                    let mut rows = rows.lock().expect("no thread panics holding it");
                    let row = &mut rows[which];
                    row.runs += 1;
                    row.faults += outcome.faults;
                    row.elections += outcome.elections;
                    row.crashes += outcome.crashes;
                    row.commits += outcome.commits;
                    row.installs += outcome.installs;
                    row.violations += u64::from(outcome.violation.is_some());
                    row.slowest_recovery = row
                        .slowest_recovery
                        .max(outcome.recovered_after.unwrap_or(0));
                }
                if outcome.violation.is_some() {
                    failed
                        .lock()
                        .expect("no thread panics holding it")
                        .push(outcome);
                }
                if (k + 1).is_multiple_of(1000) {
                    progress(k + 1);
                }
            });
        }
    });
    if let Some(e) = error.into_inner().expect("no thread panicked") {
        return Err(e);
    }
    let mut failed = failed.into_inner().expect("no thread panicked");
    failed.sort_by_key(|o| o.config.seed);
    let more_failures = failed.iter().skip(SHRUNK).map(|o| o.config.seed).collect();
    let mut failures = Vec::new();
    for outcome in failed.into_iter().take(SHRUNK) {
        failures.push(shrunk(outcome, scratch)?);
    }
    let rows = rows.into_inner().expect("no thread panicked");
    Ok(Report {
        rows: s.nemeses.iter().copied().zip(rows).collect(),
        failures,
        more_failures,
        elapsed: started.elapsed(),
    })
}

/// `outcome`'s schedule shrunk to the shortest that fails with the same property, re-run
/// with its log.
pub fn shrunk(outcome: Outcome, scratch: &Path) -> std::io::Result<Failure> {
    let property = outcome.violation.as_ref().map(|v| v.property);
    let base = Config {
        replicas: Some(outcome.config.replicas()),
        ..outcome.config.clone()
    };
    let mut error = None;
    let events = shrink(&outcome.schedule, |events| {
        let config = Config {
            schedule: Some(events.to_vec()),
            ..base.clone()
        };
        match run(&config, scratch) {
            Ok(o) => o.violation.map(|v| v.property) == property,
            Err(e) => {
                error = Some(e);
                false
            }
        }
    });
    if let Some(e) = error {
        return Err(e);
    }
    let config = Config {
        schedule: Some(events),
        trace: true,
        ..base
    };
    let shrunk = run(&config, scratch)?;
    Ok(Failure { outcome, shrunk })
}

fn row(out: &mut String, name: &str, r: &Row) {
    let _ = writeln!(
        out,
        "| {name} | {} | {} | {} | {} | {} | {} | {} | {:.2} s |",
        r.runs,
        r.faults,
        r.elections,
        r.crashes,
        r.commits,
        r.installs,
        r.violations,
        r.slowest_recovery as f64 / 1e6
    );
}

impl Report {
    /// The table, in markdown.
    pub fn table(&self) -> String {
        let mut out = String::from(
            "| nemesis | runs | faults injected | leaders elected | processes crashed | commits | snapshots installed | violations | slowest recovery after the heal |\n\
             |---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        );
        let mut total = Row::default();
        for (n, r) in &self.rows {
            row(&mut out, n.name(), r);
            total.runs += r.runs;
            total.faults += r.faults;
            total.elections += r.elections;
            total.crashes += r.crashes;
            total.commits += r.commits;
            total.installs += r.installs;
            total.violations += r.violations;
            total.slowest_recovery = total.slowest_recovery.max(r.slowest_recovery);
        }
        row(&mut out, "**all**", &total);
        out
    }

    /// Runs that broke a property.
    pub fn violations(&self) -> u64 {
        self.rows.iter().map(|(_, r)| r.violations).sum()
    }
}
