//! The dissertation's criteria (§2.1) in the summary: path optimality, time to goal,
//! energy beside its budget, repairs, false positives and the speed of reaching consensus.
//!
//! Where each comes from:
//! - **path optimality**: the agent's `length` (its accepted moves, from the log) over the
//!   octile shortest path from its start to its goal on the map it ended with: the
//!   scenario's map with every `close`/`open` event due by the end of the run applied (its
//!   rounds times the control period). Only for a robot that reached its goal in a run
//!   without `[tasks]`. A robot that passed a door before it closed can come out below 1:
//!   the shortest path of the final map is longer than the one it had.
//! - **time to goal** and **energy**: the sim's `DIR/sim-criteria.json`
//!   ([`SimCriteria`]).
//! - **energy budget**: the energy of that shortest path driven straight at the agent's
//!   nominal speed under the same motor model
//!   ([`path_budget_j`](hnav_runtime::criteria::energy::path_budget_j)).
//! - **repairs**: the agents' `repair` log lines in `DIR/logs/agent-<i>.log`, by kind.
//! - **false positives**: requests into a cell that was closed in the sim's truth at that
//!   round: the scenario's map with the events due by the round's time. A request is an
//!   accepted move the agent asked for (kind `none`; not one the coordinator chose) or a
//!   refused one (its refused direction from the agent's cell), each once like a conflict.
//! - **consensus latency**: the coordinator's `DIR/consensus-latency.json`
//!   ([`ConsensusLatency`]).

use std::path::Path;

use serde::Serialize;

use hnav_runtime::consensus_log::{read_decided, Counted, Record, Tally};
use hnav_runtime::criteria::energy::path_budget_j;
use hnav_runtime::criteria::{ConsensusLatency, SimCriteria};
use hnav_runtime::grid::neighbours::Direction;
use hnav_runtime::grid::shortest::octile_shortest_path_len;
use hnav_runtime::grid::{Cell, Grid};
use hnav_runtime::msg::{ConflictKind, Role, Verdict, NO_CELL};
use hnav_runtime::scenario::{EventSpec, Scenario};

use super::{AgentSummary, RunSummary};

/// The rounds' candidate-to-commit latencies, microseconds on the coordinator's clock.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LatencySummary {
    /// Rounds measured.
    pub rounds: u64,
    /// Median from the round's first candidate to its commit published.
    pub p50: u64,
    /// 99th percentile of the same.
    pub p99: u64,
    /// Median from the round's last candidate to its commit published (the decision, its
    /// log record and the publish, without the wait for the other agents).
    pub decide_p50: u64,
    /// 99th percentile of the same.
    pub decide_p99: u64,
}

impl LatencySummary {
    /// The percentiles of `l`; `None` when it measured no round.
    pub fn new(l: &ConsensusLatency) -> Option<Self> {
        (!l.from_first.is_empty()).then(|| LatencySummary {
            rounds: l.from_first.len(),
            p50: l.from_first.percentile(0.5),
            p99: l.from_first.percentile(0.99),
            decide_p50: l.from_last.percentile(0.5),
            decide_p99: l.from_last.percentile(0.99),
        })
    }
}

/// `grid` with the cell changes of `events` due by `t_s` applied, from `*next` on; moves
/// `*next` past them. Returns whether a cell changed.
fn apply_due(grid: &mut Grid, events: &[EventSpec], next: &mut usize, t_s: f64) -> bool {
    let mut changed = false;
    while let Some(e) = events.get(*next).filter(|e| e.at_s <= t_s + 1e-9) {
        if let Some((cells, close)) = e.change.cells() {
            for &c in cells {
                grid.set_blocked(c, close);
            }
            changed = true;
        }
        *next += 1;
    }
    changed
}

/// The map of `scenario` at `t_s` seconds into the run.
pub fn map_at(scenario: &Scenario, t_s: f64) -> Grid {
    let mut grid = scenario.map.grid.clone();
    apply_due(&mut grid, &scenario.events, &mut 0, t_s);
    grid
}

/// The cell agent at `from` (row-major on a grid `width` wide) asked to enter with decision
/// `verdict`/`kind`/`refused`/`cell`: an accepted move it asked for, or a refused one.
fn requested(
    d: &hnav_runtime::consensus_log::LoggedDecision,
    from: u32,
    width: u32,
) -> Option<Cell> {
    let at = |i: u32| Cell::new(i % width, i / width);
    match Verdict::from_u8(d.verdict)? {
        Verdict::Accept if d.kind == ConflictKind::None as u8 && d.cell != NO_CELL => {
            Some(at(d.cell))
        }
        Verdict::Block if d.refused != 0 && from != NO_CELL => {
            let dir = Direction::from_index(d.refused.trailing_zeros() as usize)?;
            let c = at(from);
            let x = i64::from(c.x) + i64::from(dir.dx());
            let y = i64::from(c.y) + i64::from(dir.dy());
            Some(Cell::new(u32::try_from(x).ok()?, u32::try_from(y).ok()?))
        }
        _ => None,
    }
}

/// Per agent, its false positives in the log of `log_dir` (see the [module docs](self)):
/// rounds are `period_s` apart.
pub fn false_positives(log_dir: &Path, scenario: &Scenario, period_s: f64) -> Vec<u32> {
    let Ok(contents) = read_decided(log_dir) else {
        return vec![0; scenario.agents.len()];
    };
    let mut grid = scenario.map.grid.clone();
    let (mut next, mut tally, mut width) = (0, None::<Tally>, 1);
    let mut out = vec![0u32; scenario.agents.len()];
    for r in &contents.records {
        match r {
            Record::Header(h) => {
                width = h.width.max(1);
                tally = Some(
                    contents
                        .compacted
                        .as_ref()
                        .map_or_else(|| Tally::from_header(h), |c| c.tally.clone()),
                );
            }
            Record::Round(rec) => {
                let Some(t) = tally.as_mut() else { continue };
                apply_due(
                    &mut grid,
                    &scenario.events,
                    &mut next,
                    rec.round as f64 * period_s,
                );
                for d in &rec.decisions {
                    let from = t.cells().get(d.agent as usize).copied().unwrap_or(NO_CELL);
                    let asked = requested(d, from, width);
                    let counted = t.fold(d);
                    let new = matches!(counted, Counted::Step | Counted::Conflict);
                    let closed = asked.is_some_and(|c| grid.is_blocked(c));
                    if let (true, true, Some(n)) = (new, closed, out.get_mut(d.agent as usize)) {
                        *n += 1;
                    }
                }
            }
            _ => {}
        }
    }
    out
}

/// Repairs of one agent by kind, from its log lines `... repair agent=I ... kind=K ...`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Repairs {
    /// §2.10 A: partial corrections of the neural map.
    pub partial: u32,
    /// §2.10 Б: the neural map rebuilt from zero.
    pub rebuild: u32,
    /// A route planner's new route (PSO, GA).
    pub replan: u32,
}

/// The repairs in the text of an agent's log.
pub fn repairs_in(log: &str, agent: Option<usize>) -> Repairs {
    let mut r = Repairs::default();
    let named = agent.map(|i| format!("agent={i}"));
    let ours = |l: &&str| (named.as_deref()).is_none_or(|n| l.split_whitespace().any(|w| w == n));
    for line in log
        .lines()
        .filter(|l| l.contains(": repair agent="))
        .filter(ours)
    {
        let kind = line
            .split_whitespace()
            .find_map(|w| w.strip_prefix("kind="));
        match kind {
            Some("Partial") => r.partial += 1,
            Some("Rebuild") => r.rebuild += 1,
            Some("Replan") => r.replan += 1,
            _ => {}
        }
    }
    r
}

/// Fills each agent's criteria in `summary` of a run of `scenario` in `run_dir` (see the
/// [module docs](self)); `log_dir` is its consensus log.
pub fn fill(summary: &mut RunSummary, scenario: &Scenario, run_dir: &Path, log_dir: &Path) {
    let period_s = scenario.sim.control_period_s();
    let end_map = map_at(scenario, summary.rounds as f64 * period_s);
    let sim = SimCriteria::load(run_dir).unwrap_or_else(|e| {
        tracing::warn!("{e}; the summary has no energy or goal times");
        None
    });
    let fps = false_positives(log_dir, scenario, period_s);
    let lifelong = scenario.tasks.is_some();
    for (i, a) in summary.agents.iter_mut().enumerate() {
        // A process that hosts several robots logs them all; each repair line names its robot.
        let process = scenario.run.process_of(i as u32);
        let log = run_dir
            .join("logs")
            .join(format!("{}.log", Role::Agent.node_name(process)));
        let rep = std::fs::read_to_string(&log)
            .map(|t| repairs_in(&t, (scenario.run.agents_per_process > 1).then_some(i)))
            .unwrap_or_default();
        (a.repairs_partial, a.repairs_rebuild, a.repairs_replan) =
            (rep.partial, rep.rebuild, rep.replan);
        a.false_positives = fps.get(i).copied().unwrap_or(0);
        if let Some(r) = sim.as_ref().and_then(|s| s.robots.get(i)) {
            a.energy_j = Some(r.energy_j);
            a.time_to_goal_s = r.goal_at_s;
        }
        if let Some(spec) = scenario.agents.get(i).filter(|_| !lifelong) {
            fill_path(a, scenario, &end_map, spec.start, spec.goal, spec.speed);
        }
    }
    summary.consensus_latency_us = ConsensusLatency::load(run_dir)
        .unwrap_or_else(|e| {
            tracing::warn!("{e}; the summary has no consensus latency");
            None
        })
        .as_ref()
        .and_then(LatencySummary::new);
}

/// Agent `a`'s shortest path on `map`, its energy budget and, if it reached its goal, its
/// optimality.
fn fill_path(a: &mut AgentSummary, s: &Scenario, map: &Grid, start: Cell, goal: Cell, speed: f64) {
    let Some(best) = octile_shortest_path_len(map, start, goal, s.map.corner_cutting) else {
        return;
    };
    let dt = f64::from(s.sim.step_ms) * 1e-3;
    a.shortest = Some(best);
    a.energy_budget_j = Some(path_budget_j(&s.robot, best, speed, dt));
    if a.reached_goal && best > 0.0 {
        a.optimality = Some(a.length / best);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::consensus_log::LoggedDecision;

    #[test]
    fn repair_lines_are_counted_by_kind_and_other_lines_are_not() {
        let log = "\
2026-12-05T14:00:00.1Z  INFO hnav_agent::navigator::sense: repair agent=0 period=151 closed=1 opened=0 kind=Partial us=40
2026-12-05T14:00:00.2Z  INFO hnav_agent::navigator::sense: repair agent=0 period=160 closed=1 opened=0 kind=Rebuild us=900
2026-12-05T14:00:00.3Z  INFO hnav_agent::navigator::sense: repair agent=0 period=170 closed=0 opened=1 kind=Rebuild us=800
2026-12-05T14:00:00.4Z  INFO hnav_agent::process: repair of nothing
";
        assert_eq!(
            repairs_in(log, None),
            Repairs {
                partial: 1,
                rebuild: 2,
                replan: 0
            }
        );
    }

    #[test]
    fn a_shared_processs_log_counts_each_robots_repairs_apart() {
        let log = "2026-12-05T14:00:00.1Z  INFO agent{index=4}: hnav_agent::navigator::sense: repair agent=4 period=151 closed=1 opened=0 kind=Partial us=40
2026-12-05T14:00:00.2Z  INFO agent{index=5}: hnav_agent::navigator::sense: repair agent=5 period=160 closed=1 opened=0 kind=Rebuild us=900
2026-12-05T14:00:00.3Z  INFO agent{index=4}: hnav_agent::navigator::sense: repair agent=4 period=170 closed=0 opened=1 kind=Rebuild us=800
2026-12-05T14:00:00.4Z  INFO agent{index=4}: hnav_agent::navigator::sense: repair agent=45 period=170 closed=0 opened=1 kind=Replan us=800
";
        let four = repairs_in(log, Some(4));
        assert_eq!((four.partial, four.rebuild, four.replan), (1, 1, 0));
        let five = repairs_in(log, Some(5));
        assert_eq!((five.partial, five.rebuild, five.replan), (0, 1, 0));
        assert_eq!(repairs_in(log, None).rebuild, 2);
    }

    fn decision(verdict: Verdict, kind: ConflictKind, refused: u8, cell: u32) -> LoggedDecision {
        LoggedDecision {
            agent: 0,
            verdict: verdict as u8,
            refused,
            kind: kind as u8,
            cell,
            waypoint: NO_CELL,
        }
    }

    #[test]
    fn a_request_is_the_asked_move_or_the_refused_direction() {
        // 10 wide; from (3, 2) = 23.
        let accept = decision(Verdict::Accept, ConflictKind::None, 0, 24);
        assert_eq!(requested(&accept, 23, 10), Some(Cell::new(4, 2)));
        let chosen = decision(Verdict::Accept, ConflictKind::Redirected, 0, 24);
        assert_eq!(requested(&chosen, 23, 10), None);
        // Bit 0 is north: (3, 1).
        let block = decision(Verdict::Block, ConflictKind::Invalid, 1, NO_CELL);
        assert_eq!(requested(&block, 23, 10), Some(Cell::new(3, 1)));
        let off = decision(Verdict::Block, ConflictKind::Invalid, 1, NO_CELL);
        assert_eq!(requested(&off, 3, 10), None);
        let hold = decision(Verdict::Hold, ConflictKind::Crossing, 0, 23);
        assert_eq!(requested(&hold, 23, 10), None);
    }

    /// Robot 0 of `scenarios/door.toml` stands at (4, 0) beside the door (5, 0), which closes
    /// at round 150: held at 149 (no request known), accepted into the closed door at 160
    /// (one false positive), back to (4, 0) at 161 (free), refused east into the door at 170
    /// and 171 (one more: the same refusal repeated is one request).
    #[test]
    fn a_request_into_a_closed_cell_is_a_false_positive_once() {
        use hnav_runtime::consensus_log::{
            AgentEntry, LogWriter, RoundRecord, RunHeader, FORMAT_VERSION,
        };
        use hnav_runtime::scenario::FsyncPolicy;
        let s =
            Scenario::load(Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/door.toml"))
                .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let (mut log, _) = LogWriter::open(dir.path(), FsyncPolicy::None).unwrap();
        let entry = |start: u32, goal: u32| AgentEntry {
            start,
            goal,
            speed: 1.0,
            priority: 1.0,
        };
        log.append(&Record::Header(RunHeader {
            version: FORMAT_VERSION,
            scenario_hash: 1,
            seed: 0,
            clock: "lockstep".into(),
            width: 10,
            height: 4,
            agents: vec![entry(4, 9), entry(39, 30)],
        }))
        .unwrap();
        let round = |round: u64, d: LoggedDecision| {
            Record::Round(RoundRecord {
                round,
                candidates: 1,
                candidates_digest: 0,
                decisions: vec![d],
            })
        };
        let east = 1 << Direction::E.index();
        for r in [
            round(149, decision(Verdict::Hold, ConflictKind::Crossing, 0, 4)),
            round(160, decision(Verdict::Accept, ConflictKind::None, 0, 5)),
            round(161, decision(Verdict::Accept, ConflictKind::None, 0, 4)),
            round(
                170,
                decision(Verdict::Block, ConflictKind::Invalid, east, NO_CELL),
            ),
            round(
                171,
                decision(Verdict::Block, ConflictKind::Invalid, east, NO_CELL),
            ),
        ] {
            log.append(&r).unwrap();
        }
        drop(log);
        let fps = false_positives(dir.path(), &s, s.sim.control_period_s());
        assert_eq!(fps, [2, 0]);
    }

    #[test]
    fn the_final_map_has_the_events_due_and_optimality_is_over_its_shortest_path() {
        let s =
            Scenario::load(Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/door.toml"))
                .unwrap();
        let door = Cell::new(5, 0);
        let closes_s = 150.0 * s.sim.control_period_s();
        assert!(!map_at(&s, closes_s - 0.005).is_blocked(door));
        let end = map_at(&s, closes_s);
        assert!(end.is_blocked(door));
        // Robot 0, (0, 0) to (9, 0): 9 cells along the top, longer around by the bottom.
        let mut a = AgentSummary {
            reached_goal: true,
            length: 12.0,
            ..AgentSummary::default()
        };
        let (start, goal) = (s.agents[0].start, s.agents[0].goal);
        fill_path(&mut a, &s, &s.map.grid, start, goal, 1.0);
        assert_eq!(a.shortest, Some(9.0));
        let open_budget = a.energy_budget_j.unwrap();
        fill_path(&mut a, &s, &end, start, goal, 1.0);
        let around = a.shortest.unwrap();
        assert!(around > 9.0, "{around}");
        assert!((a.optimality.unwrap() - 12.0 / around).abs() < 1e-12);
        assert!(a.energy_budget_j.unwrap() > open_budget);
    }
}
