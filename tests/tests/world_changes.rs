//! A world that changes (issue 35): a door closes across a robot's only short route; the
//! robot sees it with its range sensor, repairs its neural map and arrives by the other
//! route, in lockstep, the same log twice. And a warehouse with doors that close and open
//! and two movers walking the robots' aisles: every robot home, no collision, no contact,
//! the same log twice.

use std::path::Path;

use hnav_runtime::consensus_log::{read_decided, Record};
use hnav_runtime::msg::{Verdict, NO_CELL};
use hnav_tests::swarm::{lockstep_all_home, repo_root};

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

#[test]
fn a_door_that_closes_is_seen_repaired_around_and_the_run_repeats_byte_for_byte() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = repo_root().join("scenarios/door.toml");
    let registry = tmp.path().join("runs");
    let mut logs = Vec::new();
    for k in 0..2 {
        let dir = tmp.path().join(format!("run{k}"));
        let (_, log) = lockstep_all_home(&format!("door{k}"), &scenario, &dir, &registry, 2);
        logs.push(log);
        if k > 0 {
            continue;
        }
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
    assert!(logs[0] == logs[1], "the two lockstep logs differ");
}
