use std::path::Path;

use super::*;
use crate::recording::{MapWriter, PoseSample, TrajectoryHeader, TrajectoryWriter};
use hnav_runtime::consensus_log::{
    AgentEntry, LifecycleRecord, LogWriter, LoggedDecision, Record, RoundRecord, RunHeader,
    FORMAT_VERSION,
};
use hnav_runtime::grid::{write_map, Grid};
use hnav_runtime::msg::{ConflictKind, Lifecycle, MapHeader, Verdict, NO_CELL};
use hnav_runtime::scenario::FsyncPolicy;

const W: u32 = 4;
const CS: f32 = 0.5;

fn decision(agent: u32, verdict: Verdict, cell: u32) -> LoggedDecision {
    LoggedDecision {
        agent,
        verdict: verdict as u8,
        refused: 0,
        kind: 0,
        cell,
        waypoint: NO_CELL,
    }
}

fn held(agent: u32, verdict: Verdict, kind: ConflictKind, cell: u32) -> LoggedDecision {
    LoggedDecision {
        kind: kind as u8,
        ..decision(agent, verdict, cell)
    }
}

/// A 4 x 3 run of two agents: agent 0 from (0, 0) moves east twice, is blocked and replanned
/// on the way; agent 1 from (3, 2) moves once and is held three rounds for the same cell (one
/// conflict), then once with nothing in the way (no conflict); agent 1's process goes down
/// and is restarted after round 2.
fn write_log(dir: &Path) {
    let (mut log, _) = LogWriter::open(dir.join("log"), FsyncPolicy::None).unwrap();
    log.append(&Record::Header(RunHeader {
        version: FORMAT_VERSION,
        scenario_hash: 1,
        seed: 0,
        clock: "lockstep".into(),
        width: W,
        height: 3,
        agents: vec![
            AgentEntry {
                start: 0,
                goal: 3,
                speed: 1.0,
                priority: 1.0,
            },
            AgentEntry {
                start: 11,
                goal: 8,
                speed: 1.0,
                priority: 1.0,
            },
        ],
    }))
    .unwrap();
    let rounds = [
        vec![
            decision(0, Verdict::Accept, 1),
            decision(1, Verdict::Accept, 10),
        ],
        vec![
            held(0, Verdict::Block, ConflictKind::HeadOn, NO_CELL),
            held(1, Verdict::Hold, ConflictKind::Reserved, 9),
        ],
        vec![
            decision(0, Verdict::Replan, NO_CELL),
            held(1, Verdict::Hold, ConflictKind::Reserved, 9),
        ],
        vec![
            decision(0, Verdict::Accept, 2),
            held(1, Verdict::Hold, ConflictKind::Reserved, 9),
            decision(1, Verdict::Hold, NO_CELL),
        ],
    ];
    for (r, decisions) in rounds.into_iter().enumerate() {
        log.append(&Record::Round(RoundRecord {
            round: r as u64 + 1,
            candidates: 2,
            candidates_digest: 0,
            decisions,
        }))
        .unwrap();
        if r == 1 {
            for event in [
                Lifecycle::down(Role::Agent, 1, 0),
                Lifecycle::restarted(Role::Agent, 1, 1),
            ] {
                log.append(&Record::Lifecycle(LifecycleRecord::new(2, &event)))
                    .unwrap();
            }
        }
    }
    log.sync().unwrap();
}

fn write_map_copy(dir: &Path) {
    let mut blocked = vec![false; 12];
    blocked[5] = true;
    let grid = Grid::from_blocked(W, 3, &blocked).unwrap();
    std::fs::write(dir.join(MAP_FILE), write_map(&grid)).unwrap();
}

fn truth(t_ns: u64, robot: u16, x_m: f32, y_m: f32) -> PoseSample {
    PoseSample {
        t_ns,
        robot,
        source: PoseSource::Truth,
        x_m,
        y_m,
        theta_rad: 0.0,
    }
}

fn write_recording(dir: &Path) {
    let rec = dir.join(recording::DIR);
    std::fs::create_dir_all(&rec).unwrap();
    let header = TrajectoryHeader {
        robots: 2,
        rate_hz: 20,
        cell_size_m: CS,
        width: W,
        height: 3,
        truncated: false,
        control_period_us: 10_000,
        movers: 0,
    };
    let mut w =
        TrajectoryWriter::create(&rec.join(recording::TRAJECTORIES), header, u64::MAX).unwrap();
    for k in 0..3u64 {
        let t = k * 50_000_000;
        w.push(&truth(t, 0, 0.25 + 0.5 * k as f32, 0.25)).unwrap();
        w.push(&truth(t, 1, 1.75, 0.25)).unwrap();
        // Estimates are not drawn.
        w.push(&PoseSample {
            source: PoseSource::Estimate,
            ..truth(t, 0, 9.0, 9.0)
        })
        .unwrap();
    }
    // The collision at 100 ms: robots 0 (1.25 m = 2.5 cells) and 1 (3.5 cells) a cell apart.
    w.finish().unwrap();
    let mut m = MapWriter::create(&rec.join(recording::MAPS), u64::MAX).unwrap();
    for (round, agent, v) in [(0u64, 0u32, 0.1f32), (0, 1, 0.2), (7, 0, 0.3), (3, 0, 0.4)] {
        let h = MapHeader {
            round,
            agent,
            width: W,
            height: 3,
            ..MapHeader::default()
        };
        m.push(round, &h, &[v; 12]).unwrap();
    }
    m.finish().unwrap();
}

fn write_summary(dir: &Path, collisions: u32, at: &[u64]) {
    let v = serde_json::json!({
        "collisions": collisions,
        "recording": { "collisions_at_ns": at },
    });
    std::fs::write(dir.join("summary.json"), v.to_string()).unwrap();
}

#[test]
fn the_log_gives_committed_cells_and_marks_at_the_agents_cell() {
    let dir = tempfile::tempdir().unwrap();
    write_log(dir.path());
    let d = RunData::from_log(&dir.path().join("log")).unwrap();
    assert_eq!((d.width, d.height, d.rounds), (W, 3, 4));
    assert_eq!(d.starts, vec![(0, 0), (3, 2)]);
    assert_eq!(d.goals, vec![(3, 0), (0, 2)]);
    assert_eq!(d.committed, vec![vec![(1, 0), (2, 0)], vec![(2, 2)]]);
    // One conflict each, where each agent stood after round 1's moves: agent 1's hold
    // repeated for the same cell is the same request, its last hold no conflict.
    let conflicts: Vec<(u32, CellXy, u64)> = d
        .conflicts
        .iter()
        .map(|m| (m.agent, m.cell, m.round))
        .collect();
    assert_eq!(conflicts, vec![(0, (1, 0), 2), (1, (2, 2), 2)]);
    assert_eq!(d.waited, 4, "agent 1 held in rounds 2, 3 and twice in 4");
    let events: Vec<(u64, u32, &str, Option<CellXy>)> = d
        .lifecycle
        .iter()
        .map(|l| (l.round, l.index, l.event.name(), l.cell))
        .collect();
    assert_eq!(
        events,
        vec![
            (2, 1, "down", Some((2, 2))),
            (2, 1, "restarted", Some((2, 2)))
        ]
    );
    assert_eq!(
        d.replans,
        vec![Mark {
            agent: 0,
            cell: (1, 0),
            round: 3
        }]
    );
}

#[test]
fn a_whole_run_directory_is_gathered() {
    let dir = tempfile::tempdir().unwrap();
    write_log(dir.path());
    write_map_copy(dir.path());
    write_recording(dir.path());
    write_summary(dir.path(), 1, &[100_000_000]);
    let d = RunData::load(dir.path(), &[0, 1]).unwrap();
    assert_eq!(d.blocked.iter().filter(|b| **b).count(), 1);
    assert!(d.blocked[5]);
    // Truth only, in cells (0.5 m cells).
    assert_eq!(d.trajectories[0], vec![(0.5, 0.5), (1.5, 0.5), (2.5, 0.5)]);
    assert_eq!(d.trajectories[1].len(), 3);
    assert_eq!(d.collisions, 1);
    let marks: Vec<(u32, f64)> = d.collision_marks.iter().map(|m| (m.robot, m.x)).collect();
    assert_eq!(marks, vec![(0, 2.5), (1, 3.5)]);
    // Agent 0's map of the highest round (7), not the last one in the file (round 3).
    let maps: Vec<(u32, u64, f32)> = d
        .maps
        .iter()
        .map(|m| (m.header.agent, m.header.round, m.values[0]))
        .collect();
    assert_eq!(maps, vec![(0, 7, 0.3), (1, 0, 0.2)]);
    assert!(d.notes.is_empty(), "{:?}", d.notes);
}

#[test]
fn robots_far_apart_at_a_collision_are_all_marked() {
    let poses = [(0, 0.0, 0.0), (1, 5.0, 0.0), (2, 0.0, 5.0)];
    assert_eq!(involved(&poses).len(), 3);
    let poses = [(0, 0.0, 0.0), (1, 5.0, 0.0), (2, 5.5, 0.5)];
    assert_eq!(
        involved(&poses).iter().map(|p| p.0).collect::<Vec<_>>(),
        vec![1, 2]
    );
}

#[test]
fn without_a_recording_the_notes_say_what_is_missing() {
    let dir = tempfile::tempdir().unwrap();
    write_log(dir.path());
    let d = RunData::load(dir.path(), &[0]).unwrap();
    assert!(d.trajectories.iter().all(Vec::is_empty));
    assert!(d.maps.is_empty());
    let notes = d.notes.join("\n");
    for what in ["map.map", "trajectories.bin", "summary.json", "maps.bin"] {
        assert!(notes.contains(what), "{notes}");
    }
}

#[test]
fn an_agent_the_run_does_not_have_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    write_log(dir.path());
    let e = RunData::load(dir.path(), &[0, 5]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "report: --agents 5: the run has 2 agents (0-1)"
    );
}

#[test]
fn a_map_copy_of_another_size_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    write_log(dir.path());
    let grid = Grid::new(5, 5).unwrap();
    std::fs::write(dir.path().join(MAP_FILE), write_map(&grid)).unwrap();
    let e = RunData::load(dir.path(), &[]).unwrap_err().to_string();
    assert!(
        e.ends_with("map.map: a 5 x 5 map, the log's run is 4 x 3"),
        "{e}"
    );
}

#[test]
fn the_drawing_holds_one_element_per_mark() {
    let dir = tempfile::tempdir().unwrap();
    write_log(dir.path());
    write_map_copy(dir.path());
    write_recording(dir.path());
    write_summary(dir.path(), 1, &[100_000_000]);
    let out = super::super::write_report(
        dir.path(),
        &super::super::ReportOptions {
            agents: vec![0, 1],
            out: None,
        },
    )
    .unwrap();
    let svg = std::fs::read_to_string(&out.path).unwrap();
    let count = |tag: &str| svg.matches(&format!("<{tag} ")).count();
    // Two trajectories; crosses of two conflicts and the legend's; one replan triangle and
    // the legend's, one agent-down diamond and the legend's.
    assert_eq!(count("polyline"), 2, "{svg}");
    assert_eq!(count("line"), 2 * (2 + 1));
    assert_eq!(count("polygon"), 2 + 2);
    // Each cross is in its robot's colour (tab10 blue, orange), the legend's grey.
    let lines: Vec<&str> = svg
        .split("<line ")
        .skip(1)
        .map(|l| l.split("/>").next().unwrap_or(""))
        .collect();
    let stroke = |c: &str| lines.iter().filter(|l| l.contains(c)).count();
    assert_eq!(
        (stroke("#1F77B4"), stroke("#FF7F0E"), stroke("#404040")),
        (2, 2, 2),
        "{lines:?}"
    );
    // The process events under the legend, the cell coordinates, the title's rules.
    assert!(
        svg.contains("round 2: agent-1 down, restarted at [2, 2]"),
        "{svg}"
    );
    assert!(
        svg.contains("rules not known"),
        "the fixture's summary names none"
    );
    assert!(svg.contains("1 process restarts"), "{svg}");
}

#[test]
fn the_criteria_lines_add_up_the_agents_and_name_the_latency() {
    let v = serde_json::json!({
        "agents": [
            {"optimality": 1.0, "time_to_goal_s": 3.5, "energy_j": 2.0, "energy_budget_j": 1.5,
             "repairs_partial": 1, "repairs_rebuild": 0, "repairs_replan": 0, "false_positives": 2},
            {"optimality": 1.5, "time_to_goal_s": 7.25, "energy_j": 1.0, "energy_budget_j": 0.5,
             "repairs_partial": 0, "repairs_rebuild": 1, "repairs_replan": 0, "false_positives": 0},
        ],
        "consensus_latency_us": {"rounds": 700, "p50": 120, "p99": 950, "decide_p50": 40, "decide_p99": 300},
    });
    let lines = super::criteria_lines(&v);
    assert_eq!(
        lines,
        [
            "criteria: optimality mean 1.250 (max 1.500), last at goal 7.25 s, energy 3.00 J \
             (budget 2.00 J), repairs 1 partial / 1 rebuild / 0 route, 2 false positives",
            "consensus: candidate -> commit p50 120 us, p99 950 us (700 rounds)",
        ]
    );
    // A summary of before the criteria: nothing to say.
    assert!(super::criteria_lines(&serde_json::json!({"agents": [{"steps": 3}]})).is_empty());
}

#[test]
fn cells_the_swarm_saw_close_are_kept_once_each() {
    let dir = tempfile::tempdir().unwrap();
    let (mut log, _) = LogWriter::open(dir.path().join("log"), FsyncPolicy::None).unwrap();
    log.append(&Record::Header(RunHeader {
        version: FORMAT_VERSION,
        scenario_hash: 1,
        seed: 0,
        clock: "lockstep".into(),
        width: W,
        height: 3,
        agents: vec![],
    }))
    .unwrap();
    let change = |round, closed: Vec<u32>, opened: Vec<u32>| {
        Record::MapChange(hnav_runtime::consensus_log::MapChangeRecord {
            round,
            agent: 0,
            closed,
            opened,
        })
    };
    for r in [
        change(1, vec![5, 6], vec![]),
        change(4, vec![], vec![6]),
        change(9, vec![6], vec![]),
    ] {
        log.append(&r).unwrap();
    }
    drop(log);
    let d = RunData::from_log(&dir.path().join("log")).unwrap();
    assert_eq!(d.closed, vec![(1, 1), (2, 1)]);
}
