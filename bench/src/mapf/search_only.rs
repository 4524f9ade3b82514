//! The search-only MAPF benchmark (`hnav-bench lacam`): the coordinator's LaCAM search
//! (`hnav_coordinator::conflict::lacam::standalone`) on the first N entries of a MovingAI
//! `.scen`, without robots, processes or rounds (`hnav-bench mapf` runs whole swarms, up to
//! 256 robots), against a wall-clock limit as the LaCAM papers measure it.
//!
//! Each instance runs in a child process (`hnav-bench lacam --child ...`) that prints one
//! JSON row: the first solution's time, sum of costs and ratio to the lower bound, then
//! LaCAM*'s refinement until the limit, the configurations visited and the child's peak
//! resident set (`VmHWM` of `/proc/self/status`, read by the child when the search is over,
//! so it covers the map, the distance tables and the search; the row also gives the peak
//! before the search began).
//!
//! Costs follow the MAPF papers' convention: an agent's cost is the step at which it last
//! arrives at its goal, one step a move (straight or diagonal) or a wait. The lower bound is
//! the sum over the agents of their fewest steps on the search's graph (8 neighbours, no
//! corner cutting); the `.scen`'s optimal lengths are octile (a diagonal counts √2), not
//! steps, so their sum is printed beside it but is no bound on a sum of steps.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use hnav_coordinator::conflict::lacam::standalone::Instance as Search;
use hnav_coordinator::conflict::lacam::{Budget, SearchError};
use hnav_coordinator::conflict::Options;
use hnav_runtime::grid::scen_gen::generate_scen;
use hnav_runtime::grid::ScenEntry;
use serde::{Deserialize, Serialize};

use super::instance::Benchmark;

/// One instance to search.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// The MovingAI map.
    pub map: PathBuf,
    /// Its `.scen`.
    pub scen: PathBuf,
    /// Agents: the first N entries.
    pub agents: usize,
    /// The search's wall-clock limit.
    pub limit: Duration,
    /// The memory the search's tables may take, MiB (sets the node budgets).
    pub memory_mib: usize,
    /// Extends a `.scen` shorter than `agents` with HNAV's generator at this seed (the one
    /// that made `maps/warehouse-10-20-10-2-1-random-1.scen` at seed 1: the extension keeps
    /// the file's entries as its first ones, which is checked).
    pub extend_seed: Option<u64>,
    /// Agents as points (`sweep = false`): a diagonal does not hold its side cells.
    pub points: bool,
    /// LaCAM3's swap in the generator (on unless `--no-swap`).
    pub swap: bool,
}

/// What one search showed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SearchRow {
    /// The map's file name.
    pub map: String,
    /// Agents.
    pub agents: usize,
    /// The wall-clock limit, s.
    pub limit_s: f64,
    /// Building the distance tables, s (before the search; not in the limit).
    pub tables_s: f64,
    /// The lower bound: the agents' fewest steps, summed.
    pub lower_bound: u64,
    /// The `.scen`'s octile optimal lengths, summed (for reference: no bound on steps).
    pub scen_octile_sum: f64,
    /// Time to the first solution, s; `None` if none was found.
    pub first_s: Option<f64>,
    /// The first solution's sum of costs.
    pub first_soc: Option<u64>,
    /// Configurations visited by then.
    pub first_visited: Option<usize>,
    /// The plan's sum of costs after refinement.
    pub soc: Option<u64>,
    /// Whether the plan was checked a solution (vertex, swap and move rules).
    pub valid: bool,
    /// Whether the search proved it optimal.
    pub optimal: bool,
    /// Configurations visited in all.
    pub visited: usize,
    /// The search's tables at the end, bytes.
    pub search_bytes: usize,
    /// The child's peak RSS before the search, KiB.
    pub rss_before_kib: u64,
    /// The child's peak RSS, KiB.
    pub peak_rss_kib: u64,
    /// Why no plan was found, if none.
    pub error: Option<String>,
    /// Published figures to compare with.
    pub published: String,
}

impl SearchRow {
    /// The first solution's sum of costs over the lower bound.
    pub fn first_ratio(&self) -> Option<f64> {
        self.first_soc
            .map(|s| s as f64 / self.lower_bound.max(1) as f64)
    }

    /// The refined plan's sum of costs over the lower bound.
    pub fn ratio(&self) -> Option<f64> {
        self.soc.map(|s| s as f64 / self.lower_bound.max(1) as f64)
    }
}

/// What the papers published for the instance (their 4-neighbour grids, agents as points).
pub fn published(map: &str, agents: usize) -> String {
    match (map, agents) {
        ("random-32-32-20", 400) => {
            "LaCAM2 first: SOC 31 373 / LB 9 217 = 3.41 in 31 ms (4-neighbour)".into()
        }
        ("warehouse-10-20-10-2-1", _) => {
            "— (LaCAM*: 99 % of instances up to 1 000 agents within 10 s, MovingAI scens)".into()
        }
        _ => "—".into(),
    }
}

/// The case's entries: the `.scen`'s first N, extended by the generator when asked.
fn entries(case: &Case, bench: &Benchmark) -> Result<Vec<ScenEntry>, String> {
    if bench.entries.len() >= case.agents {
        let instance = bench.instance(case.agents).map_err(|e| e.to_string())?;
        return Ok(instance.entries.to_vec());
    }
    let Some(seed) = case.extend_seed else {
        bench.instance(case.agents).map_err(|e| e.to_string())?;
        return Err("too few entries".into());
    };
    let name = bench.entries.first().map_or("", |e| e.map.as_str());
    let made = generate_scen(&bench.grid, name, case.agents, seed).map_err(|e| e.to_string())?;
    let same = bench
        .entries
        .iter()
        .zip(&made.entries)
        .all(|(a, b)| a.start == b.start && a.goal == b.goal);
    if !same {
        return Err(format!(
            "{}: the generator at seed {seed} does not extend the file (its first entries differ)",
            bench.scen
        ));
    }
    Ok(made.entries)
}

/// `VmHWM` of this process, KiB (0 where `/proc` has none).
fn peak_rss_kib() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0)
}

/// The node budgets that keep the search's tables within `memory_mib` for `agents`: three
/// quarters for configurations (8 bytes an agent, 96 of node, table and queue), a quarter
/// for constraints (16 bytes). No limit on the refinement's iterations: the clock ends it.
pub fn budget(memory_mib: usize, agents: usize) -> Budget {
    let bytes = memory_mib << 20;
    Budget {
        configurations: (bytes / 4 * 3 / (8 * agents + 96)).max(1),
        constraints: (bytes / 4 / 16).max(1),
        refine: usize::MAX,
    }
}

/// Runs one case in this process (the child's work).
pub fn search_case(case: &Case) -> Result<SearchRow, String> {
    let bench = Benchmark::load(&case.map, &case.scen).map_err(|e| e.to_string())?;
    let entries = entries(case, &bench)?;
    let starts: Vec<_> = entries.iter().map(|e| e.start).collect();
    let goals: Vec<_> = entries.iter().map(|e| e.goal).collect();
    let options = Options {
        sweep: !case.points,
        ..Options::default()
    };
    let t0 = Instant::now();
    let mut search =
        Search::new(&bench.grid, &starts, &goals, options).map_err(|e| e.to_string())?;
    search.set_swap(case.swap);
    let tables_s = t0.elapsed().as_secs_f64();
    let stem = Path::new(&bench.map_given)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut row = SearchRow {
        published: published(&stem, case.agents),
        map: stem,
        agents: case.agents,
        limit_s: case.limit.as_secs_f64(),
        tables_s,
        lower_bound: search.lower_bound(),
        scen_octile_sum: entries.iter().map(|e| e.optimal_length).sum(),
        first_s: None,
        first_soc: None,
        first_visited: None,
        soc: None,
        valid: false,
        optimal: false,
        visited: 0,
        search_bytes: 0,
        rss_before_kib: peak_rss_kib(),
        peak_rss_kib: 0,
        error: None,
    };
    let started = Instant::now();
    let result = search.solve(
        budget(case.memory_mib, case.agents),
        Some(started + case.limit),
    );
    match result {
        Ok(plan) => {
            row.first_s = plan.first_at.map(|t| (t - started).as_secs_f64());
            row.first_soc = Some(plan.first_cost);
            row.first_visited = Some(plan.first_visited);
            row.soc = Some(search.sum_of_costs(&plan.configs));
            row.valid = search.check(&plan.configs).is_ok();
            row.optimal = plan.optimal;
            row.visited = plan.visited;
            row.search_bytes = plan.bytes;
        }
        Err(e) => {
            row.visited = match e {
                SearchError::Budget { configurations }
                | SearchError::Deadline { configurations } => configurations,
                SearchError::NoPlan => 0,
            };
            row.error = Some(e.to_string());
        }
    }
    row.peak_rss_kib = peak_rss_kib();
    Ok(row)
}

/// The arguments of the child that runs `case`.
pub fn child_args(case: &Case) -> Vec<String> {
    let mut args = vec![
        "lacam".to_string(),
        "--child".into(),
        "--map".into(),
        case.map.display().to_string(),
        "--scen".into(),
        case.scen.display().to_string(),
        "--agents".into(),
        case.agents.to_string(),
        "--limit-s".into(),
        case.limit.as_secs_f64().to_string(),
        "--memory-mib".into(),
        case.memory_mib.to_string(),
    ];
    if let Some(seed) = case.extend_seed {
        args.extend(["--extend-seed".into(), seed.to_string()]);
    }
    if case.points {
        args.push("--points".into());
    }
    if !case.swap {
        args.push("--no-swap".into());
    }
    args
}

/// Runs `case` in a child `exe` (this benchmark's binary) and reads its row.
pub fn search_in_child(exe: &Path, case: &Case) -> Result<SearchRow, String> {
    let out = Command::new(exe)
        .args(child_args(case))
        .output()
        .map_err(|e| format!("{}: {e}", exe.display()))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(format!(
            "the child for {} agents failed ({}): {}",
            case.agents,
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    let line = stdout.lines().last().unwrap_or_default();
    serde_json::from_str(line).map_err(|e| format!("the child's row {line:?}: {e}"))
}

/// The rows as a markdown table.
pub fn table(rows: &[SearchRow]) -> String {
    let mut out = String::from(
        "| map | agents | limit s | first s | first SOC | first SOC/LB | SOC | SOC/LB | LB | configurations | peak RSS MiB | published |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let f = |v: Option<f64>, p: usize| v.map_or("—".to_string(), |v| format!("{v:.p$}"));
    let u = |v: Option<u64>| v.map_or("—".to_string(), |v| v.to_string());
    for r in rows {
        let soc = match (&r.error, r.optimal) {
            (Some(e), _) => format!("none: {e}"),
            (None, true) => format!("{} (optimal)", u(r.soc)),
            (None, false) => u(r.soc),
        };
        out.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.0} | {} |\n",
            r.map,
            r.agents,
            r.limit_s,
            f(r.first_s, 3),
            u(r.first_soc),
            f(r.first_ratio(), 2),
            soc,
            f(r.ratio(), 2),
            r.lower_bound,
            r.visited,
            r.peak_rss_kib as f64 / 1024.0,
            r.published
        ));
    }
    out
}

/// The cases of `--quick`: random-32-32-10, 50 agents, 1 s.
pub fn quick_cases() -> Vec<Case> {
    let (map, scen) = super::quick_files();
    vec![Case {
        map,
        scen,
        agents: 50,
        limit: Duration::from_secs(1),
        memory_mib: 256,
        extend_seed: None,
        points: false,
        swap: true,
    }]
}

/// The measured cases (`docs/perf/lacam-search.txt`): warehouse at 500 and 1 000 agents (the
/// `.scen` extended by its generator), random-32-32-20 at 400, `limit` each.
pub fn default_cases(limit: Duration, memory_mib: usize) -> Vec<Case> {
    let maps = Path::new(env!("CARGO_MANIFEST_DIR")).join("../maps");
    let case = |stem: &str, agents: usize| Case {
        map: maps.join(format!("{stem}.map")),
        scen: maps.join(format!("{stem}-random-1.scen")),
        agents,
        limit,
        memory_mib,
        extend_seed: Some(1).filter(|_| stem.starts_with("warehouse")),
        points: false,
        swap: true,
    };
    vec![
        case("warehouse-10-20-10-2-1", 500),
        case("warehouse-10-20-10-2-1", 1000),
        case("random-32-32-20", 400),
    ]
}
