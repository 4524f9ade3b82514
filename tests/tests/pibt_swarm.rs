//! `[coordinator] rules = "pibt"` end to end: eight robots in a 6x4 room, the west column
//! exchanged with the east one, rows reversed, so that every robot must pass the others. The
//! dissertation's rules leave all eight short of their goals at the 120 s limit (12 000
//! rounds, measured with `hnav run`); PIBT brings them home, and two lockstep runs write the
//! same log. The same for `rules = "lacam"` (one plan, followed by the processes).

use std::path::Path;

use hnav_tests::swarm::lockstep_all_home;

fn scenario(dir: &Path, rules: &str) -> std::path::PathBuf {
    let mut text = format!(
        "name = \"{rules}-room\"\n[map]\nrows = [\"......\", \"......\", \"......\", \"......\"]\n\
         [coordinator]\nrules = \"{rules}\"\ntime_limit_s = 120\n",
    );
    for i in 0..4 {
        text += &format!("[[agents]]\nstart = [0, {i}]\ngoal = [5, {}]\n", 3 - i);
        text += &format!("[[agents]]\nstart = [5, {i}]\ngoal = [0, {}]\n", 3 - i);
    }
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join(format!("{rules}-room.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs the scenario in lockstep into `dir`; returns the log segment's bytes.
fn run(tag: &str, scenario: &Path, dir: &Path, registry: &Path) -> Vec<u8> {
    let (s, log) = lockstep_all_home(tag, scenario, dir, registry, 8);
    let agents = s["agents"].as_array().unwrap();
    assert!(
        agents.iter().all(|a| a["replans"] == 0),
        "no replans in pibt or lacam mode: {s}"
    );
    log
}

#[test]
fn pibt_brings_a_crossing_room_home_and_replays_byte_for_byte() {
    twice_the_same("pibt");
}

#[test]
fn lacam_brings_a_crossing_room_home_and_replays_byte_for_byte() {
    twice_the_same("lacam");
}

fn twice_the_same(rules: &str) {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = scenario(&tmp.path().join("s"), rules);
    let registry = tmp.path().join("runs");
    let a = run(
        &format!("{rules}-a"),
        &scenario,
        &tmp.path().join("a"),
        &registry,
    );
    let b = run(
        &format!("{rules}-b"),
        &scenario,
        &tmp.path().join("b"),
        &registry,
    );
    assert!(
        a == b,
        "the two lockstep logs differ ({} vs {} bytes)",
        a.len(),
        b.len()
    );
}
