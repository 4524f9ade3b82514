//! One instance run: its scenario written, `hnav run` as a child (as the chaos campaign runs
//! it, [`crate::swarm_run`]), its processes' memory sampled while it runs, then the numbers
//! read from `summary.json` and the consensus log and checked against each other.

use std::path::Path;
use std::time::{Duration, Instant};

use hnav_operator::supervisor::child::{Child, ExitInfo, Signal};
use hnav_runtime::consensus_log::{read_log, EndReason, Record, Tally};
use hnav_runtime::transport::{purge_run, RunId};

use super::instance::{Instance, RunSettings};
use super::memory::Sampler;
use super::report::Row;
use crate::swarm_run::{hnav_run_spec, read_summary, run_files, verify_log};

/// How often the processes' memory is sampled while a run goes on.
const SAMPLE_EVERY: Duration = Duration::from_secs(2);
/// How often it is sampled until the run's processes are in the registry: a short run (8
/// agents, lockstep, 1.5 s) ended between a first sample taken before they were spawned and
/// the next one 2 s later, and its row had no agent's memory at all.
const FIRST_SAMPLE_EVERY: Duration = Duration::from_millis(50);
/// How long `hnav run` gets to stop its processes and write its summary after a SIGINT:
/// its stop grace (3 s, twice) and the summary, with room for a slow stop of hundreds of
/// processes on a loaded machine.
const STOP_TIMEOUT: Duration = Duration::from_secs(120);

/// Where the runs take their programs and put their files.
#[derive(Debug, Clone, Copy)]
pub struct RunPlace<'a> {
    /// The directory holding `hnav` and the process binaries.
    pub bin_dir: &'a Path,
    /// The run's own directory (scenario, output, registry, `hnav run`'s output).
    pub dir: &'a Path,
    /// The wall-clock cap of the run, start-up included: past it the run is stopped (SIGINT,
    /// as Ctrl-C would) and reported `stopped`.
    pub wall_limit: Duration,
}

/// Runs `instance` under `settings` and returns its row. An error is a problem of the
/// harness or the run's files (the run could not start, no summary, an unreadable log, the
/// summary and the log disagree), never a run that merely ended badly: that is in the row.
pub fn run_instance(
    instance: &Instance<'_>,
    settings: &RunSettings,
    place: &RunPlace<'_>,
) -> Result<Row, String> {
    let dir = place.dir;
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let scenario = dir.join("scenario.toml");
    std::fs::write(&scenario, instance.scenario_toml(settings))
        .map_err(|e| format!("{}: {e}", scenario.display()))?;
    let run = RunId::unique("mapf");
    let out = dir.join("out");
    let registry = dir.join("runs");
    let hnav = place.bin_dir.join("hnav");
    let spec = hnav_run_spec(
        &hnav,
        &scenario,
        &run,
        &out,
        &settings.mode,
        &registry,
        dir.join("hnav-run.log"),
    );
    let started = Instant::now();
    let child = Child::spawn(&spec).map_err(|e| e.to_string())?;
    let mut sampler = Sampler::default();
    let mut capped = false;
    let exit = loop {
        let every = if sampler.sample(child.pid(), &registry, &run) {
            SAMPLE_EVERY
        } else {
            FIRST_SAMPLE_EVERY
        };
        if let Some(exit) = child.wait(Some(every)) {
            break exit;
        }
        if !capped && started.elapsed() >= place.wall_limit {
            capped = true;
            let _ = child.signal(Signal::SIGINT);
            if let Some(exit) = child.wait(Some(STOP_TIMEOUT)) {
                break exit;
            }
            let _ = child.signal_group(Signal::SIGKILL);
            break child.wait(Some(STOP_TIMEOUT)).unwrap_or(ExitInfo::Lost);
        }
    };
    let wall = started.elapsed();
    if !run_files(&run).is_empty() {
        let _ = purge_run(&run);
    }
    let mut row = Row::new(instance, settings, sampler.finish());
    row.wall_s = wall.as_secs_f64();
    row.exit = exit.to_string();
    row.wall_capped = capped;
    match read_results(&hnav, &out, &mut row) {
        Ok(()) => {}
        // A run the cap stopped may have been killed before it wrote its summary; its row
        // still has the memory and the wall time, and says why the rest is missing.
        Err(e) if capped => {
            row.end = "killed at the wall cap".into();
            row.agreement = format!("not checked: {e}");
        }
        Err(e) => {
            return Err(format!(
                "{} agents, {}: {e} (hnav run: {exit}; its output is in {})",
                instance.agents(),
                settings.rules.as_deref().unwrap_or("dissertation"),
                dir.join("hnav-run.log").display()
            ))
        }
    }
    Ok(row)
}

/// Fills `row` from `summary.json` and the log in `out`, and checks that they agree.
fn read_results(hnav: &Path, out: &Path, row: &mut Row) -> Result<(), String> {
    let summary = read_summary(out)?;
    let agents = summary["agents"]
        .as_array()
        .ok_or("summary.json has no agents")?;
    row.at_goal = agents.iter().filter(|a| a["reached_goal"] == true).count();
    row.collisions = summary["collisions"].as_u64().unwrap_or(u64::MAX);
    row.end = summary["end"].as_str().unwrap_or("").to_string();
    let sum = |k: &str| agents.iter().filter_map(|a| a[k].as_f64()).sum::<f64>();
    row.energy_j = sum("energy_j");
    row.energy_budget_j = sum("energy_budget_j");
    row.false_positives = sum("false_positives") as u64;
    row.consensus_p50_us = summary["consensus_latency_us"]["p50"].as_u64();
    row.consensus_p99_us = summary["consensus_latency_us"]["p99"].as_u64();
    row.log_verified = verify_log(hnav, out).is_ok();
    let log = LogNumbers::read(&out.join("log"))?;
    row.rounds = log.rounds;
    row.makespan_rounds = log.makespan_rounds;
    let tally = log.tally.agents();
    row.length_sum = tally.iter().map(|a| a.length).sum();
    row.conflicts = log.tally.conflicts();
    row.replans = log.tally.replans();
    row.agreement = agreement(&summary, &log);
    (row.search_s, row.searches_failed) = lacam_searches(&out.join("logs").join("coordinator.log"));
    Ok(())
}

/// The coordinator's LaCAM searches as its log tells them: the seconds of the first that
/// found a plan, and how many ran out of their budget. A run under other rules, or whose
/// log cannot be read, has none.
fn lacam_searches(log: &Path) -> (Option<f64>, u32) {
    let Ok(text) = std::fs::read_to_string(log) else {
        return (None, 0);
    };
    let mut first = None;
    let mut failed = 0;
    for line in text.lines().filter(|l| l.contains("lacam: ")) {
        let seconds = (line.split_whitespace())
            .find_map(|w| w.strip_prefix("seconds="))
            .and_then(|v| v.parse::<f64>().ok());
        if line.contains("lacam: plan found") {
            first = first.or(seconds);
        } else if line.contains("; online PIBT for ") {
            failed += 1;
        }
    }
    (first, failed)
}

/// What the benchmark reads from a run's consensus log.
#[derive(Debug, Clone, Default)]
pub struct LogNumbers {
    /// The decisions of every round folded in log order.
    pub tally: Tally,
    /// The last round logged.
    pub rounds: u64,
    /// The end record: its round, its count of robots at goal and its reason.
    pub end: Option<(u64, u32, EndReason)>,
    /// The round in which the last robot was at its goal: the end record's round when the
    /// run ended with every robot at goal (the coordinator ends the run in the round whose
    /// candidates all say "at goal"), `None` otherwise.
    pub makespan_rounds: Option<u64>,
}

impl LogNumbers {
    /// Reads the log in `log_dir`.
    pub fn read(log_dir: &Path) -> Result<LogNumbers, String> {
        let contents = read_log(log_dir).map_err(|e| e.to_string())?;
        let mut n = LogNumbers::default();
        for r in &contents.records {
            match r {
                Record::Header(h) => n.tally = Tally::from_header(h),
                Record::Round(rec) => {
                    n.rounds = n.rounds.max(rec.round);
                    n.tally.fold_round(rec);
                }
                Record::End(e) => n.end = Some((e.round, e.at_goal, e.reason)),
                _ => {}
            }
        }
        n.makespan_rounds = match n.end {
            Some((round, _, EndReason::AllAtGoal)) => Some(round),
            _ => None,
        };
        Ok(n)
    }
}

/// Whether the summary's numbers are the log's: per agent steps, length, conflicts and
/// replans; the rounds; the end reason; and, when the run ended with every robot at goal,
/// the robots at goal. `"ok"`, or what differs.
pub fn agreement(summary: &serde_json::Value, log: &LogNumbers) -> String {
    let mut wrong = Vec::new();
    let agents = summary["agents"].as_array().map_or(&[][..], Vec::as_slice);
    if agents.len() != log.tally.agents().len() {
        wrong.push(format!(
            "{} agents in the summary, {} in the log",
            agents.len(),
            log.tally.agents().len()
        ));
    }
    for (a, t) in agents.iter().zip(log.tally.agents()) {
        let same = a["steps"].as_u64() == Some(u64::from(t.steps))
            && a["length"]
                .as_f64()
                .is_some_and(|l| (l - t.length).abs() < 1e-6)
            && a["conflicts"].as_u64() == Some(u64::from(t.conflicts))
            && a["replans"].as_u64() == Some(u64::from(t.replans));
        if !same {
            wrong.push(format!(
                "agent {}: summary {} steps {} long, {} conflicts, {} replans; log {} steps {:.3} long, {} conflicts, {} replans",
                a["id"], a["steps"], a["length"], a["conflicts"], a["replans"],
                t.steps, t.length, t.conflicts, t.replans
            ));
        }
    }
    if summary["rounds"].as_u64() != Some(log.rounds) {
        wrong.push(format!(
            "summary {} rounds, log {}",
            summary["rounds"], log.rounds
        ));
    }
    if let Some((_, at_goal, reason)) = log.end {
        let summary_at_goal = agents.iter().filter(|a| a["reached_goal"] == true).count();
        if summary["end"].as_str() != Some(reason.name()) {
            wrong.push(format!(
                "summary ends {}, log {}",
                summary["end"],
                reason.name()
            ));
        }
        // Only an all-at-goal end must count the same robots: elsewhere the summary counts
        // a robot whose true pose has entered its goal cell, the end record an agent that has
        // arrived at the cell's centre, and a robot still driving in is one and not the other.
        if reason == EndReason::AllAtGoal && summary_at_goal != at_goal as usize {
            wrong.push(format!(
                "summary {summary_at_goal} robots at goal, log's end record {at_goal}"
            ));
        }
    }
    if wrong.is_empty() {
        "ok".into()
    } else {
        wrong.join("; ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::consensus_log::LoggedDecision;
    use hnav_runtime::msg::{Verdict, NO_CELL};

    fn log() -> LogNumbers {
        let mut tally = Tally::new([0, 9], 10);
        for (agent, verdict, cell) in [(0, Verdict::Accept, 11), (1, Verdict::Hold, NO_CELL)] {
            tally.fold(&LoggedDecision {
                agent,
                verdict: verdict as u8,
                refused: 0,
                // A hold for a cell being left: a conflict.
                kind: hnav_runtime::msg::ConflictKind::Reserved as u8,
                cell,
                waypoint: NO_CELL,
            });
        }
        LogNumbers {
            tally,
            rounds: 40,
            end: Some((40, 1, EndReason::TimeLimit)),
            makespan_rounds: None,
        }
    }

    fn summary() -> serde_json::Value {
        serde_json::json!({"rounds": 40, "end": "time-limit", "agents": [
            {"id": 0, "reached_goal": true, "steps": 1, "length": std::f64::consts::SQRT_2, "conflicts": 0, "replans": 0},
            {"id": 1, "reached_goal": false, "steps": 0, "length": 0.0, "conflicts": 1, "replans": 0}]})
    }

    #[test]
    fn the_coordinators_searches_are_read_from_its_log() {
        let dir = tempfile::tempdir().unwrap();
        let log = dir.path().join("coordinator.log");
        std::fs::write(
            &log,
            "2026-12-06T08:33:56.308643Z  WARN hnav_coordinator::conflict::lacam: lacam: the search budget ran out after 100000 configurations; online PIBT for 1000 rounds round=1 robots=1000 seconds=29.81839355\n\
             2026-12-06T08:35:00.000000Z  INFO hnav_coordinator::round: something else seconds=9\n\
             2026-12-06T08:52:05.981959Z  INFO hnav_coordinator::conflict::lacam: lacam: plan found round=1018 robots=1000 steps=423 configurations=424 seconds=0.121985641\n\
             2026-12-06T08:53:05.981959Z  INFO hnav_coordinator::conflict::lacam: lacam: plan found round=2000 robots=10 steps=4 configurations=5 seconds=0.5\n",
        )
        .unwrap();
        assert_eq!(lacam_searches(&log), (Some(0.121985641), 1));
        assert_eq!(lacam_searches(&dir.path().join("none.log")), (None, 0));
    }

    #[test]
    fn a_summary_that_is_the_log_agrees() {
        assert_eq!(agreement(&summary(), &log()), "ok");
    }

    #[test]
    fn every_difference_between_summary_and_log_is_named() {
        let mut s = summary();
        s["agents"][1]["conflicts"] = 2.into();
        s["rounds"] = 41.into();
        s["agents"][1]["reached_goal"] = true.into();
        // At a time limit a robot driving into its goal cell is at goal for the summary only.
        assert!(!agreement(&s, &log()).contains("robots at goal"));
        let mut all_at_goal = log();
        all_at_goal.end = Some((40, 1, EndReason::AllAtGoal));
        assert_eq!(
            agreement(&s, &all_at_goal),
            "agent 1: summary 0 steps 0.0 long, 2 conflicts, 0 replans; log 0 steps 0.000 long, \
             1 conflicts, 0 replans; summary 41 rounds, log 40; summary ends \"time-limit\", \
             log all-at-goal; summary 2 robots at goal, log's end record 1"
        );
    }
}
