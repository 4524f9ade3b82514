//! A world that changes (issue 35): a door closes across a robot's only short route; the
//! robot sees it with its range sensor, repairs its neural map and arrives by the other
//! route, in lockstep, the same log twice; the summary has the dissertation's criteria. The
//! coordinator logs the change the robot saw and hands the map as it stands to an agent that
//! restarts. And a warehouse with doors that close and open and two movers walking the
//! robots' aisles: every robot home, no collision, no contact, the same log twice. And an
//! unmapped start on a MovingAI map (`known_map = false`): every robot home.

use std::path::Path;

use base64::Engine as _;
use hnav_runtime::consensus_log::MapChangeRecord;
use hnav_runtime::consensus_log::{read_decided, Record};
use hnav_runtime::msg::{Verdict, NO_CELL};
use hnav_tests::swarm::{lockstep_all_home, repo_root, verify_log, workspace_bin, SwarmRun};
use hnav_tests::TestRun;

/// The door (5, 0) of `scenarios/door.toml` closes at this round.
const CLOSED_AT: u64 = 150;

/// The rounds robot `agent` was accepted into each cell, in order: (round, x, y).
fn steps(log: &Path, agent: u32, width: u32) -> Vec<(u64, u32, u32)> {
    let mut out = Vec::new();
    for r in read_decided(log).unwrap().records {
        let Record::Round(rec) = r else { continue };
        for d in rec.decisions.iter().filter(|d| d.agent == agent) {
            if d.verdict == Verdict::Accept as u8 && d.cell != NO_CELL {
                out.push((rec.round, d.cell % width, d.cell / width));
            }
        }
    }
    out.dedup_by_key(|s| (s.1, s.2));
    out
}

/// The period of the agent's first repair with a closed cell, from its log line.
fn first_repair(agent_log: &str) -> Option<u64> {
    let line = agent_log
        .lines()
        .find(|l| l.contains("repair") && l.contains("closed=1"))?;
    let at = line.find("period=")? + "period=".len();
    line[at..]
        .split(|c: char| !c.is_ascii_digit())
        .next()?
        .parse()
        .ok()
}

/// The criteria of `summary.json` (issue 35 item 7) are there for every robot and sane.
fn check_criteria(s: &serde_json::Value) {
    let f = |a: &serde_json::Value, k: &str| {
        a[k].as_f64()
            .unwrap_or_else(|| panic!("agent {}: no {k}: {s}", a["id"]))
    };
    let sim_s = s["rounds"].as_f64().unwrap() * 0.01;
    for a in s["agents"].as_array().unwrap() {
        // Over the final map, with the door closed: nobody went through it before.
        assert!(f(a, "optimality") >= 1.0 - 1e-9, "{a}");
        assert!((f(a, "length") / f(a, "shortest") - f(a, "optimality")).abs() < 1e-9);
        let t = f(a, "time_to_goal_s");
        assert!(t > 0.0 && t <= sim_s + 0.01, "{a}: {t} s of {sim_s} s");
        let (e, budget) = (f(a, "energy_j"), f(a, "energy_budget_j"));
        assert!(
            budget > 0.0 && e >= 0.5 * budget,
            "{a}: {e} J, budget {budget} J"
        );
        assert!(a["false_positives"].is_u64(), "{a}");
    }
    let robot0 = &s["agents"][0];
    let repairs = f(robot0, "repairs_partial") + f(robot0, "repairs_rebuild");
    assert!(
        repairs >= 1.0,
        "robot 0 repaired its map after the door: {robot0}"
    );
    // Robot 0 took the long way: its shortest path on the final map is around the door.
    assert!(f(robot0, "shortest") > 11.0, "{robot0}");
    let l = &s["consensus_latency_us"];
    let rounds = l["rounds"].as_u64().unwrap_or(0);
    assert!(rounds > 0 && l["p50"].as_u64() <= l["p99"].as_u64(), "{l}");
    println!(
        "criteria: robot 0 optimality {:.3}, {:.2} s to goal, {:.3} J (budget {:.3} J), \
         {repairs} repairs; consensus p50 {} us, p99 {} us over {rounds} rounds",
        f(robot0, "optimality"),
        f(robot0, "time_to_goal_s"),
        f(robot0, "energy_j"),
        f(robot0, "energy_budget_j"),
        l["p50"],
        l["p99"]
    );
}

#[test]
fn a_door_that_closes_is_seen_repaired_around_and_the_run_repeats_byte_for_byte() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = repo_root().join("scenarios/door.toml");
    let registry = tmp.path().join("runs");
    let mut logs = Vec::new();
    for k in 0..2 {
        let dir = tmp.path().join(format!("run{k}"));
        let (summary, log) = lockstep_all_home(&format!("door{k}"), &scenario, &dir, &registry, 2);
        logs.push(log);
        if k > 0 {
            continue;
        }
        check_criteria(&summary);
        let walk = steps(&dir.join("log"), 0, 10);
        let agent_log = std::fs::read_to_string(dir.join("logs/agent-0.log")).unwrap();
        let sensed = first_repair(&agent_log).expect("agent 0 logs a repair of a closed cell");
        // Sensed after the door closed, within the robot's reach (3 cells).
        assert!(sensed >= CLOSED_AT, "sensed at period {sensed}: {walk:?}");
        // The new route: the first step after the repair into the bottom corridor or down
        // the left column.
        let detour = walk
            .iter()
            .find(|&&(round, x, y)| round > sensed && (y == 2 || (x == 0 && y == 1)))
            .expect("a step onto the other route");
        assert!(
            walk.iter()
                .all(|&(round, x, y)| !(round > CLOSED_AT && (x, y) == (5, 0))),
            "robot 0 entered the closed door: {walk:?}"
        );
        // The coordinator took the change from agent 0's sighting, which went out before its
        // candidate for the round after the period it saw the door in.
        let changes: Vec<MapChangeRecord> = read_decided(dir.join("log"))
            .unwrap()
            .records
            .into_iter()
            .filter_map(|r| match r {
                Record::MapChange(m) => Some(m),
                _ => None,
            })
            .collect();
        let door = MapChangeRecord {
            round: sensed + 1,
            agent: 0,
            closed: vec![5],
            opened: vec![],
        };
        assert_eq!(
            changes,
            [door],
            "one map change: the door, as agent 0 saw it"
        );
        let last = walk.last().unwrap();
        assert_eq!(
            (last.1, last.2),
            (9, 0),
            "robot 0 ends at its goal: {walk:?}"
        );
        println!(
            "door closed at round {CLOSED_AT}, sensed at period {sensed} (round {}), new route \
             committed at round {} into ({}, {})",
            sensed + 1,
            detour.0,
            detour.1,
            detour.2
        );
    }
    assert!(logs[0] == logs[1], "the two lockstep logs differ");
}

#[test]
fn an_agent_that_restarts_gets_the_map_as_it_stands_not_the_one_at_start() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = repo_root().join("scenarios/door.toml");
    let dir = tmp.path().join("run");
    let mut run = TestRun::new("door-restart");
    // Agent 0 saw the door close at period 186; it is killed and restarted at round 250.
    let args = ["--mode", "lockstep", "--kill", "agent:0@round:250"];
    let registry = tmp.path().join("runs");
    let mut swarm = SwarmRun::start(&mut run, &scenario, &dir, &registry, &args).unwrap();
    let status = swarm.finish(std::time::Duration::from_secs(300)).unwrap();
    assert!(status.success(), "{status}\n{}", swarm.log_tails());
    let s = swarm.summary().unwrap();
    assert_eq!(s["end"], "all-at-goal", "{s}");
    assert_eq!(s["restarts"]["agent-0"], 1, "{s}");
    let (ok, report) = verify_log(&dir.join("log"));
    assert!(ok && report.contains(", 1 map-change"), "{report}");
    // `hnav log show` prints the change; a replay decides every round, on the changed map
    // and with the restart, as logged.
    let hnav = |args: &[&str]| {
        let out = std::process::Command::new(workspace_bin("hnav"))
            .args(args)
            .env("HNAV_RUNS_DIR", &registry)
            .output()
            .unwrap();
        let said = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(
            out.status.success(),
            "{args:?}: {said}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        said
    };
    let d = dir.to_str().unwrap();
    let shown = hnav(&["log", "show", d, "--kind", "map-change"]);
    assert_eq!(shown.trim(), "map-change round 187  a0 saw  closed [5, 0]");
    // The MCAP export shows the truth's change (`/map` at 1.5 s) and the coordinator's
    // (`/map/shared` at round 187), each after the map at the start, the door's cell occupied.
    let mcap = tmp.path().join("door.mcap");
    hnav(&["log", "export", d, "--mcap", mcap.to_str().unwrap()]);
    let bytes = std::fs::read(&mcap).unwrap();
    let mut maps: Vec<(String, u64, Vec<u8>)> = Vec::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        if m.channel.topic.starts_with("/map") {
            let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
            let data = base64::engine::general_purpose::STANDARD
                .decode(v["data"].as_str().unwrap())
                .unwrap();
            maps.push((m.channel.topic.clone(), m.log_time, data));
        }
    }
    let at = |topic: &str| -> Vec<(u64, u8)> {
        maps.iter()
            .filter(|(t, _, _)| t == topic)
            .map(|(_, time, data)| (*time, data[5]))
            .collect()
    };
    assert_eq!(at("/map"), [(0, 0), (1_500_000_000, 1)], "the truth");
    assert_eq!(
        at("/map/shared"),
        [(0, 0), (1_870_000_000, 1)],
        "the picture"
    );
    let replay_run = TestRun::new("door-replay");
    let said = hnav(&["log", "replay", d, "--run", replay_run.run.as_str()]);
    assert!(said.contains("identical"), "{said}");
    drop(replay_run);
    let agent_log = std::fs::read_to_string(dir.join("logs/agent-0.log")).unwrap();
    let got = agent_log
        .lines()
        .find(|l| l.contains("the coordinator's map"))
        .unwrap_or_else(|| panic!("the restarted agent got no map:\n{agent_log}"));
    assert!(got.contains("closed=1 opened=0"), "{got}");
    // It learned the door from the map (a repair at its first period back), not by seeing it
    // again later.
    let repairs: Vec<u64> = agent_log
        .lines()
        .filter(|l| l.contains(" repair ") && l.contains("closed=1"))
        .filter_map(|l| l.split("period=").nth(1)?.split(' ').next()?.parse().ok())
        .collect();
    assert_eq!(
        repairs.len(),
        2,
        "seen once, learned once after the restart: {repairs:?}"
    );
    assert!(repairs[1] >= 250 && repairs[1] <= 251, "{repairs:?}");
}

#[test]
fn the_all_knowing_baseline_tells_every_agent_the_door_when_it_closes() {
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(repo_root().join("scenarios/door.toml")).unwrap();
    let text = text.replace("range = 3\n", "range = 3\nall_knowing = true\n");
    assert!(text.contains("all_knowing = true"));
    let scenario = tmp.path().join("door-all-knowing.toml");
    std::fs::write(&scenario, text).unwrap();
    let dir = tmp.path().join("run");
    let registry = tmp.path().join("runs");
    lockstep_all_home("door-all", &scenario, &dir, &registry, 2);
    // The door closes at 1.5 s of sim time, the end of period 149: both agents repair then,
    // wherever their robots are (agent 1's is in the bottom corridor, out of sight).
    for agent in 0..2 {
        let log = std::fs::read_to_string(dir.join(format!("logs/agent-{agent}.log"))).unwrap();
        assert_eq!(
            first_repair(&log),
            Some(CLOSED_AT - 1),
            "agent {agent}:\n{log}"
        );
    }
    // Both report it; the coordinator logs agent 0's and finds agent 1's no news.
    let changes: Vec<(u64, u32)> = read_decided(dir.join("log"))
        .unwrap()
        .records
        .into_iter()
        .filter_map(|r| match r {
            Record::MapChange(m) => Some((m.round, m.agent)),
            _ => None,
        })
        .collect();
    assert_eq!(changes, [(CLOSED_AT, 0)]);
}

/// The warehouse run in `dir` as the report and the playback show it: the movers' tracks, the
/// doors closing and opening at their time, and what the robots' sensors saw.
fn seen_as_it_happens(dir: &Path) {
    use hnav_operator::monitor::feed::{Feed, Update};
    use hnav_operator::monitor::playback::PlaybackFeed;
    use hnav_operator::monitor::state::ViewState;
    use hnav_operator::recording::{PoseSource, TrajectoryReader};
    use hnav_runtime::grid::Cell;
    use std::time::{Duration, Instant};

    let (samples, _) = TrajectoryReader::open(&dir.join("recording/trajectories.bin"))
        .unwrap()
        .read_all()
        .unwrap();
    for k in 0..2 {
        let n = samples
            .iter()
            .filter(|s| s.source == PoseSource::Mover && s.robot == k)
            .count();
        assert!(n > 100, "mover {k}: {n} samples recorded");
    }
    // The report: both movers' tracks and the sensed floor, the doors among it.
    let data = hnav_operator::report::RunData::load(dir, &[]).unwrap();
    assert_eq!(data.movers.len(), 2);
    assert!(data.movers.iter().all(|t| t.len() > 100));
    let sensed = |x: u32, y: u32| data.sensed[(y * data.width + x) as usize];
    assert!(sensed(5, 2) && sensed(10, 7), "the doors were seen");
    let svg = std::fs::read_to_string(dir.join("report.svg")).unwrap();
    assert!(
        svg.contains("mover (dashed: its track)"),
        "the report's legend"
    );
    // The playback: doors closed between their rounds (10 ms each), movers, rebuilt views.
    let mut feed = PlaybackFeed::open(dir, 10_000.0).unwrap();
    let mut state = ViewState::new(feed.info().clone());
    let door = Cell::new(5, 2);
    let (started, mut movers, mut views) = (Instant::now(), 0, 0);
    let (mut closed_in_time, mut closed_out_of_time) = (false, false);
    while state.ended.is_none() {
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "playback too slow"
        );
        feed.wait(Instant::now() + Duration::from_millis(5))
            .unwrap();
        let mut t_ns = None;
        feed.pump(&mut |u| {
            match u {
                Update::Movers(m) => movers += usize::from(m.len() == 2),
                Update::View(_) => views += 1,
                Update::Truth(t) => t_ns = Some(t.sim_time_ns()),
                _ => {}
            }
            state.apply(u, Instant::now());
            if let Some(t) = t_ns {
                let round = t / 10_000_000;
                let shut = state.info.grid.is_blocked(door);
                let inside = (DOORS_CLOSE + 1..DOORS_OPEN).contains(&round);
                closed_in_time |= shut && inside;
                closed_out_of_time |= shut && !(DOORS_CLOSE..=DOORS_OPEN).contains(&round);
            }
        })
        .unwrap();
    }
    assert!(
        movers > 100 && views > 100,
        "movers {movers}, views {views}"
    );
    assert!(
        closed_in_time && !closed_out_of_time,
        "the door in the playback"
    );
    assert_eq!(state.movers.len(), 2);
    assert!(
        state.sensed().iter().any(|&s| s),
        "a sensed area in the playback"
    );
}

/// The rounds `scenarios/warehouse-doors.toml`'s doors are closed: from this round ...
const DOORS_CLOSE: u64 = 100;
/// ... to this one.
const DOORS_OPEN: u64 = 1500;

#[test]
fn doors_and_movers_in_a_warehouse_every_robot_home_no_contact_and_the_run_repeats() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = repo_root().join("scenarios/warehouse-doors.toml");
    let registry = tmp.path().join("runs");
    let mut logs = Vec::new();
    for k in 0..2 {
        let dir = tmp.path().join(format!("run{k}"));
        // Exit 0, every robot at its goal, `collisions` 0: robot, wall and mover contacts.
        let (summary, log) = lockstep_all_home(
            &format!("warehouse-doors{k}"),
            &scenario,
            &dir,
            &registry,
            4,
        );
        logs.push(log);
        if k > 0 {
            continue;
        }
        // No robot entered a door while it was closed.
        for agent in 0..4 {
            let walk = steps(&dir.join("log"), agent, 16);
            assert!(
                walk.iter().all(|&(round, x, y)| {
                    !((DOORS_CLOSE..DOORS_OPEN).contains(&round)
                        && [(5, 2), (10, 7)].contains(&(x, y)))
                }),
                "robot {agent} entered a closed door: {walk:?}"
            );
        }
        let agent_logs: String = (0..4)
            .map(|a| std::fs::read_to_string(dir.join(format!("logs/agent-{a}.log"))).unwrap())
            .collect();
        let repairs = |what: &str| {
            (agent_logs.lines())
                .filter(|l| l.contains("repair") && l.contains(what))
                .count()
        };
        // The doors were seen closing and opening; the movers were not map changes.
        let (closed, opened) = (repairs("closed=1"), repairs("opened=1"));
        assert!(closed > 0 && opened > 0, "{agent_logs}");
        // The robots met the movers and kept clear of them.
        let kept_clear = agent_logs.matches("waits for a mover").count();
        assert!(kept_clear > 0, "{agent_logs}");
        seen_as_it_happens(&dir);
        let sim_log = std::fs::read_to_string(dir.join("logs/sim.log")).unwrap();
        println!(
            "warehouse-doors: {} rounds, {} collisions, repairs with a closed cell {closed}, \
             with an opened cell {opened}; robots waited for a mover {kept_clear} times, movers \
             for a robot {} times, turned back {} times",
            summary["rounds"],
            summary["collisions"],
            sim_log.matches("mover waits for a robot").count(),
            sim_log.matches("mover turned back").count()
        );
    }
    if logs[0] != logs[1] {
        panic!(
            "the two lockstep logs differ: {}",
            first_difference(&tmp.path().join("run0"), &tmp.path().join("run1"))
        );
    }
}

#[test]
fn an_unmapped_start_on_a_movingai_map_brings_every_robot_home() {
    // Seed 003's setting: no agent knows a wall at Start (`known_map = false`), each learns
    // the random-32-32-10 map from its own range sensor, and all eight still get home.
    let tmp = tempfile::tempdir().unwrap();
    let scenario = repo_root().join("scenarios/random-32-32-10-unmapped.toml");
    let dir = tmp.path().join("run");
    let (summary, _) = lockstep_all_home("unmapped", &scenario, &dir, &tmp.path().join("runs"), 8);
    // Every agent learned walls as it went: each repaired its map at least once.
    for a in 0..8 {
        let text = std::fs::read_to_string(dir.join(format!("logs/agent-{a}.log"))).unwrap();
        let repairs = text.lines().filter(|l| l.contains(" repair ")).count();
        assert!(repairs > 0, "agent {a} never repaired its map:\n{text}");
    }
    println!(
        "unmapped random-32-32-10: {} rounds, {} collisions",
        summary["rounds"], summary["collisions"]
    );
}

/// The first decided record in which the logs of the runs in `a` and `b` differ.
fn first_difference(a: &Path, b: &Path) -> String {
    let records = |d: &Path| read_decided(d.join("log")).unwrap().records;
    let (ra, rb) = (records(a), records(b));
    match ra.iter().zip(&rb).position(|(x, y)| x != y) {
        Some(i) => format!("record {i}:\n{:?}\nagainst\n{:?}", ra[i], rb[i]),
        None => format!("{} records against {}", ra.len(), rb.len()),
    }
}
