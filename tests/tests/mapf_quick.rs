//! `hnav-bench mapf --quick` as a test: the first 8 and 16 entries of
//! `random-32-32-10-random-1.scen` run by whole swarms (lockstep, debug build), the JSON rows
//! read back, every robot at goal with no collision and a log that verifies and agrees with
//! the summary; and the same 8 agents under a time limit too short for them, which the rows
//! must report as robots not at goal (so the first check can fail).
//!
//! The same code as `hnav-bench mapf` (`hnav_bench::mapf`). Its own test binary because it
//! runs whole swarms for about half a minute.

use std::time::Duration;

use hnav_bench::mapf::report::{render_json, Row};
use hnav_bench::mapf::{quick_files, run_benchmark, MapfConfig, DISSERTATION, QUICK_AGENTS};
use hnav_tests::swarm::workspace_bin;

fn config(out: &std::path::Path, agents: Vec<usize>, time_limit_s: Option<f64>) -> MapfConfig {
    let (map, scen) = quick_files();
    let hnav = workspace_bin("hnav");
    MapfConfig {
        map,
        scen,
        agents,
        rules: vec![DISSERTATION.into()],
        mode: "lockstep".into(),
        time_limit_s,
        agents_per_process: 1,
        odometry_hz: None,
        // Far above the ~20 s the runs take alone: the cap is not what is tested, and a machine
        // shared with a big swarm gives these few processes a small share of the cores.
        wall_limit: Duration::from_secs(900),
        out: out.to_path_buf(),
        bin_dir: hnav.parent().expect("binaries live in a directory").into(),
    }
}

/// The rows as a script reads them: the JSON lines, parsed.
fn parsed(rows: &[Row]) -> Vec<Row> {
    render_json(rows)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}

#[test]
fn the_quick_instances_end_with_every_robot_at_goal_and_a_short_limit_does_not() {
    let out = tempfile::tempdir().unwrap();
    let rows = run_benchmark(
        &config(out.path(), QUICK_AGENTS.to_vec(), None),
        |l| println!("{l}"),
        |_| {},
    )
    .expect("the quick benchmark runs");
    let rows = parsed(&rows);
    assert_eq!(rows.len(), QUICK_AGENTS.len());
    for (r, n) in rows.iter().zip(QUICK_AGENTS) {
        assert_eq!(r.agents, n);
        assert!(r.solved(), "N = {n} not solved: {r:?}");
        assert_eq!((r.at_goal, r.collisions), (n, 0), "{r:?}");
        assert_eq!(r.end, "all-at-goal");
        assert_eq!(r.makespan_rounds, Some(r.rounds));
        assert!(r.length_ratio >= 1.0 - 1e-9, "below the lower bound: {r:?}");
        assert!(r.memory.agent.processes as usize >= n && r.memory.pss_sum_kib > 0);
    }

    // 2 s of simulated time (200 rounds) is far too short for 8 robots whose solo trips
    // take 10-40 s: the run ends on its limit, robots away from their goals.
    let rows = run_benchmark(
        &config(out.path(), vec![8], Some(2.0)),
        |l| println!("{l}"),
        |_| {},
    )
    .expect("the short benchmark runs");
    let [r] = &parsed(&rows)[..] else {
        panic!("one row: {rows:?}")
    };
    assert!(!r.solved(), "{r:?}");
    assert!(r.at_goal < 8, "{r:?}");
    assert_eq!(
        (r.end.as_str(), r.rounds, r.makespan_rounds),
        ("time-limit", 200, None)
    );
    assert_eq!(r.agreement, "ok");
}
