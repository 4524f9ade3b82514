//! `[coordinator] rules = "pibt"` end to end: eight robots in a 6x4 room, the west column
//! exchanged with the east one, rows reversed, so that every robot must pass the others. The
//! dissertation's rules leave all eight short of their goals at the 120 s limit (12 000
//! rounds, measured with `hnav run`); PIBT brings them home, and two lockstep runs write the
//! same log.

use std::path::Path;
use std::time::Duration;

use hnav_tests::swarm::{verify_log, SwarmRun};
use hnav_tests::TestRun;

const RUN_TIMEOUT: Duration = Duration::from_secs(300);

fn scenario(dir: &Path) -> std::path::PathBuf {
    let mut text = String::from(
        "name = \"pibt-room\"\n[map]\nrows = [\"......\", \"......\", \"......\", \"......\"]\n\
         [coordinator]\nrules = \"pibt\"\ntime_limit_s = 120\n",
    );
    for i in 0..4 {
        text += &format!("[[agents]]\nstart = [0, {i}]\ngoal = [5, {}]\n", 3 - i);
        text += &format!("[[agents]]\nstart = [5, {i}]\ngoal = [0, {}]\n", 3 - i);
    }
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("pibt-room.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs the scenario in lockstep into `dir`; returns the log segment's bytes.
fn run(tag: &str, scenario: &Path, dir: &Path, registry: &Path) -> Vec<u8> {
    let mut run = TestRun::new(tag);
    let mut swarm = SwarmRun::start(&mut run, scenario, dir, registry, &["--mode", "lockstep"])
        .expect("hnav run starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert!(status.success(), "{status}\n{}", swarm.log_tails());
    let s = swarm.summary().unwrap();
    assert_eq!(s["end"], "all-at-goal", "{s}\n{}", swarm.log_tails());
    assert_eq!(s["collisions"], 0, "{s}");
    let agents = s["agents"].as_array().unwrap();
    assert_eq!(agents.len(), 8);
    assert!(agents.iter().all(|a| a["reached_goal"] == true), "{s}");
    assert!(
        agents.iter().all(|a| a["replans"] == 0),
        "no replans in pibt mode: {s}"
    );
    let (ok, report) = verify_log(&dir.join("log"));
    assert!(ok, "log does not verify:\n{report}");
    std::fs::read(dir.join("log/seg-00000000.hlog")).unwrap()
}

#[test]
fn pibt_brings_a_crossing_room_home_and_replays_byte_for_byte() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = scenario(&tmp.path().join("s"));
    let registry = tmp.path().join("runs");
    let a = run("pibt-a", &scenario, &tmp.path().join("a"), &registry);
    let b = run("pibt-b", &scenario, &tmp.path().join("b"), &registry);
    assert!(
        a == b,
        "the two lockstep logs differ ({} vs {} bytes)",
        a.len(),
        b.len()
    );
}
