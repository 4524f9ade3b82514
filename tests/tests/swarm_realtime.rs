//! A large swarm in realtime mode: 64 agent processes, the sim and the coordinator on a
//! 128 x 128 MovingAI map, with the wall clock driving the sim, as on hardware.

use std::time::Duration;

use hnav_tests::swarm::{generated_scenario, repo_root, verify_log, wait_for_ps, SwarmRun};
use hnav_tests::TestRun;

#[test]
fn sixty_four_agents_on_a_128_map_finish_in_realtime() {
    let tmp = tempfile::tempdir().unwrap();
    let map = repo_root().join("maps/maze-128-128-10.map");
    let scenario = generated_scenario(tmp.path(), &map, 64, 7, (10.0, 30.0), 2.5);
    let mut run = TestRun::new("rt64");
    let mut swarm = SwarmRun::start(
        &mut run,
        &scenario,
        &tmp.path().join("out"),
        &tmp.path().join("runs"),
        &["--mode", "realtime"],
    )
    .expect("hnav run starts");
    // While it runs, `hnav ps` lists the run with all 66 processes running.
    let listed = wait_for_ps(
        &tmp.path().join("runs"),
        run.run.as_str(),
        Duration::from_secs(60),
        |r| {
            let procs = r["processes"].as_array().cloned().unwrap_or_default();
            procs.len() == 66 && procs.iter().all(|p| p["state"] == "running")
        },
    )
    .expect("hnav ps lists the run");
    let procs = listed["processes"].as_array().unwrap();
    for role in ["sim", "coordinator", "agent"] {
        assert!(
            procs.iter().any(|p| p["role"] == role),
            "no {role} in {listed}"
        );
    }
    assert!(procs
        .iter()
        .all(|p| p["pid"].as_u64().is_some_and(|pid| pid > 0)));
    let status = swarm
        .finish(Duration::from_secs(600))
        .expect("hnav run ends");
    let s = swarm.summary().expect("a summary");
    println!("{s}");
    assert!(
        status.success(),
        "run failed: {status}\n{s}\n{}",
        swarm.log_tails()
    );
    let agents = s["agents"].as_array().unwrap();
    assert_eq!(agents.len(), 64);
    assert!(agents.iter().all(|a| a["reached_goal"] == true));
    assert_eq!(s["collisions"], 0);
    let (ok, report) = verify_log(&swarm.dir.join("log"));
    assert!(ok, "{report}");
}
