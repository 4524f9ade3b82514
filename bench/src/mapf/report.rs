//! A row per instance run, printed as a markdown table or as JSON lines.

use std::fmt::Write as _;

use hnav_runtime::scenario::SimParams;
use serde::{Deserialize, Serialize};

use super::instance::{Instance, RunSettings};
use super::memory::RunMemory;

/// What one run of one instance showed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// The map file.
    pub map: String,
    /// The `.scen` file.
    pub scen: String,
    /// Agents (the first N entries).
    pub agents: usize,
    /// The coordinator's rules.
    pub rules: String,
    /// `lockstep` or `realtime`.
    pub mode: String,
    /// The scenario's time limit (simulated seconds in lockstep).
    pub time_limit_s: f64,
    /// Robots per agent process (`[run] agents_per_process`): the agent column's memory is a
    /// process's, so of this many robots.
    #[serde(default = "one")]
    pub agents_per_process: u32,
    /// The control rate (`[sim] odometry_hz`), rounds a simulated second in lockstep.
    #[serde(default = "hundred")]
    pub odometry_hz: u32,
    /// Robots whose true pose ended in their goal cell (`summary.json`).
    pub at_goal: usize,
    /// Collisions on ground truth (`summary.json`).
    pub collisions: u64,
    /// The last round of the log.
    pub rounds: u64,
    /// The round in which the last robot was at its goal (the log's end record of an
    /// all-at-goal run); `None` when not every robot got there.
    pub makespan_rounds: Option<u64>,
    /// [`Row::makespan_rounds`] in simulated seconds.
    pub makespan_s: Option<f64>,
    /// Sum over the agents of their accepted moves' octile length (the log).
    pub length_sum: f64,
    /// Sum of the `.scen`'s optimal lengths: the lower bound.
    pub optimal_sum: f64,
    /// `length_sum / optimal_sum`.
    pub length_ratio: f64,
    /// Refused or held requests (the log).
    pub conflicts: u32,
    /// Global replans (the log).
    pub replans: u32,
    /// Energy the robots' motors drew, J, summed (`summary.json`'s `energy_j`).
    #[serde(default)]
    pub energy_j: f64,
    /// Energy of their shortest paths, J, summed (`summary.json`'s `energy_budget_j`).
    #[serde(default)]
    pub energy_budget_j: f64,
    /// Median candidate-to-commit latency, µs (`summary.json`'s `consensus_latency_us`).
    #[serde(default)]
    pub consensus_p50_us: Option<u64>,
    /// Its 99th percentile, µs.
    #[serde(default)]
    pub consensus_p99_us: Option<u64>,
    /// The coordinator's first LaCAM search that found a plan, s (its log's `lacam: plan
    /// found ... seconds=`); none under other rules or when no search found one.
    #[serde(default)]
    pub search_s: Option<f64>,
    /// The coordinator's LaCAM searches that ran out of their budget (online PIBT drove
    /// until the next).
    #[serde(default)]
    pub searches_failed: u32,
    /// Requests into a closed cell, summed (`summary.json`'s `false_positives`).
    #[serde(default)]
    pub false_positives: u64,
    /// Wall time of `hnav run`, start-up included.
    pub wall_s: f64,
    /// How the run ended (`summary.json`'s `end`).
    pub end: String,
    /// How `hnav run` exited.
    pub exit: String,
    /// Whether the benchmark's wall-clock cap stopped the run.
    pub wall_capped: bool,
    /// Whether `hnav log verify` passed.
    pub log_verified: bool,
    /// `ok` when the summary's numbers are the log's, else what differs.
    pub agreement: String,
    /// The processes' memory.
    pub memory: RunMemory,
}

/// One robot a process, the default.
fn one() -> u32 {
    1
}

/// The default control rate, for rows written before the rate was a column.
fn hundred() -> u32 {
    100
}

impl Row {
    /// A row for `instance` with nothing measured yet but its memory.
    pub fn new(instance: &Instance<'_>, settings: &RunSettings, memory: RunMemory) -> Self {
        Row {
            map: instance.benchmark.map_given.clone(),
            scen: instance.benchmark.scen.clone(),
            agents: instance.agents(),
            rules: settings
                .rules
                .clone()
                .unwrap_or_else(|| "dissertation".into()),
            mode: settings.mode.clone(),
            time_limit_s: settings.time_limit_s,
            agents_per_process: settings.agents_per_process,
            odometry_hz: settings.odometry_hz.unwrap_or(100),
            at_goal: 0,
            collisions: 0,
            rounds: 0,
            makespan_rounds: None,
            makespan_s: None,
            length_sum: 0.0,
            optimal_sum: instance.optimal_sum(),
            length_ratio: 0.0,
            conflicts: 0,
            replans: 0,
            energy_j: 0.0,
            energy_budget_j: 0.0,
            consensus_p50_us: None,
            consensus_p99_us: None,
            search_s: None,
            searches_failed: 0,
            false_positives: 0,
            wall_s: 0.0,
            end: String::new(),
            exit: String::new(),
            wall_capped: false,
            log_verified: false,
            agreement: String::new(),
            memory,
        }
    }

    /// Fills the derived numbers: the ratio and the makespan in seconds (a round is one
    /// control period at the row's `odometry_hz`).
    pub fn derive(&mut self) {
        self.length_ratio = if self.optimal_sum > 0.0 {
            self.length_sum / self.optimal_sum
        } else {
            0.0
        };
        let period = SimParams {
            odometry_hz: self.odometry_hz,
            ..SimParams::default()
        }
        .control_period_s();
        self.makespan_s = self.makespan_rounds.map(|r| r as f64 * period);
    }

    /// Every robot at its goal, no collision, an intact log that agrees with the summary.
    pub fn solved(&self) -> bool {
        self.at_goal == self.agents
            && self.collisions == 0
            && self.log_verified
            && self.agreement == "ok"
    }
}

fn mib(kib: u64) -> String {
    format!("{:.1}", kib as f64 / 1024.0)
}

/// The rows as a markdown table, then a line per row whose summary and log disagree or
/// whose log does not verify.
pub fn render_table(rows: &[Row]) -> String {
    let mut out = String::new();
    out += "| N | rules | at goal | collisions | makespan (rounds) | sum of lengths | lower bound | ratio | conflicts | replans | search s (failed) | energy J | budget J | consensus p50/p99 µs | false+ | wall s | end | sim MiB | coordinator MiB | agent MiB | PSS sum MiB |\n";
    out +=
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for r in rows {
        let makespan = r
            .makespan_rounds
            .map_or_else(|| "-".to_string(), |m| m.to_string());
        let end = if r.wall_capped {
            format!("{} (wall cap)", r.end)
        } else {
            r.end.clone()
        };
        let consensus = match (r.consensus_p50_us, r.consensus_p99_us) {
            (Some(a), Some(b)) => format!("{a}/{b}"),
            _ => "-".to_string(),
        };
        let search = match (r.search_s, r.searches_failed) {
            (Some(s), 0) => format!("{s:.3}"),
            (Some(s), n) => format!("{s:.3} ({n})"),
            (None, 0) => "-".to_string(),
            (None, n) => format!("- ({n})"),
        };
        let _ = writeln!(
            out,
            "| {} | {} | {}/{} | {} | {} | {:.1} | {:.1} | {:.3} | {} | {} | {} | {:.2} | {:.2} | {} | {} | {:.1} | {} | {} | {} | {} | {} |",
            r.agents,
            r.rules,
            r.at_goal,
            r.agents,
            r.collisions,
            makespan,
            r.length_sum,
            r.optimal_sum,
            r.length_ratio,
            r.conflicts,
            r.replans,
            search,
            r.energy_j,
            r.energy_budget_j,
            consensus,
            r.false_positives,
            r.wall_s,
            end,
            mib(r.memory.sim.hwm_kib),
            mib(r.memory.coordinator.hwm_kib),
            mib(r.memory.agent.hwm_kib),
            mib(r.memory.pss_sum_kib),
        );
    }
    for r in rows {
        if !r.log_verified {
            let _ = writeln!(
                out,
                "N = {} ({}): the log does not verify",
                r.agents, r.rules
            );
        }
        if r.agreement != "ok" {
            let _ = writeln!(
                out,
                "N = {} ({}): summary and log disagree: {}",
                r.agents, r.rules, r.agreement
            );
        }
    }
    out += "memory: peak RSS (VmHWM) of the sim, the coordinator and the largest agent; PSS sum: the largest sum over all processes at one sample (shared memory counted once)\n";
    out
}

/// The rows as JSON lines, one object per row.
pub fn render_json(rows: &[Row]) -> String {
    rows.iter()
        .map(|r| serde_json::to_string(r).unwrap_or_default() + "\n")
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row of the 400-robot run on random-32-32-20 at 10 Hz (its JSON as the benchmark
    /// wrote it, before the makespan was derived from the row's own control rate).
    const ROW_AT_10_HZ: &str = r#"{"map":"maps/random-32-32-20.map","scen":"maps/random-32-32-20-random-1.scen","agents":400,"rules":"lacam","mode":"lockstep","time_limit_s":6000.0,"agents_per_process":16,"odometry_hz":10,"at_goal":400,"collisions":0,"rounds":25395,"makespan_rounds":25395,"makespan_s":253.95,"length_sum":22863.141269072,"optimal_sum":7819.414930600008,"length_ratio":2.9238941112589916,"conflicts":13039,"replans":0,"energy_j":7937.064552815489,"energy_budget_j":301.34965467529275,"consensus_p50_us":6560,"consensus_p99_us":40192,"false_positives":0,"wall_s":532.570963996,"end":"all-at-goal","exit":"exit code 0","wall_capped":false,"log_verified":true,"agreement":"ok","memory":{"supervisor":{"processes":1,"hwm_kib":244148,"pss_kib":229669},"sim":{"processes":1,"hwm_kib":33572,"pss_kib":27729},"coordinator":{"processes":1,"hwm_kib":34592,"pss_kib":23591},"agent":{"processes":25,"hwm_kib":29992,"pss_kib":19216},"hwm_sum_kib":1049656,"pss_sum_kib":759298,"samples":624}}"#;

    #[test]
    fn the_makespan_in_seconds_follows_the_rows_control_rate() {
        let mut row: Row = serde_json::from_str(ROW_AT_10_HZ).unwrap();
        row.derive();
        let s = row.makespan_s.unwrap();
        assert!((s - 2539.5).abs() < 1e-9, "{s}");
        // A row written before the rate was a column ran at the default 100 Hz.
        let old = ROW_AT_10_HZ.replace(r#""odometry_hz":10,"#, "");
        let mut row: Row = serde_json::from_str(&old).unwrap();
        row.derive();
        assert!((row.makespan_s.unwrap() - 253.95).abs() < 1e-9);
    }
}
