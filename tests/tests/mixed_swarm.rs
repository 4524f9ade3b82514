//! `scenarios/mixed.toml` end to end: two agents of each planner (`hnav`, `pso`, `ga-fuzzy`)
//! cross a room under one coordinator. Every robot reaches its goal without a collision, two
//! lockstep runs write byte-identical consensus logs, and the recording shows that the seeds'
//! planners really drove their agents (their snapshots are routes, not neural maps).

use std::path::Path;
use std::time::Duration;

use hnav_runtime::msg::ActivationKind;
use hnav_runtime::recording::MapReader;
use hnav_tests::swarm::{repo_root, verify_log, SwarmRun};
use hnav_tests::TestRun;

const RUN_TIMEOUT: Duration = Duration::from_secs(300);

/// Runs the scenario in lockstep into `dir`; returns the log segment's bytes.
fn run(tag: &str, dir: &Path, registry: &Path) -> Vec<u8> {
    let scenario = repo_root().join("scenarios/mixed.toml");
    let mut run = TestRun::new(tag);
    let mut swarm = SwarmRun::start(&mut run, &scenario, dir, registry, &["--mode", "lockstep"])
        .expect("hnav run starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert!(status.success(), "{status}\n{}", swarm.log_tails());
    let s = swarm.summary().unwrap();
    assert_eq!(s["end"], "all-at-goal", "{s}\n{}", swarm.log_tails());
    assert_eq!(s["collisions"], 0, "{s}");
    let agents = s["agents"].as_array().unwrap();
    assert_eq!(agents.len(), 6);
    assert!(agents.iter().all(|a| a["reached_goal"] == true), "{s}");
    let (ok, report) = verify_log(&dir.join("log"));
    assert!(ok, "log does not verify:\n{report}");
    std::fs::read(dir.join("log/seg-00000000.hlog")).unwrap()
}

/// The activation kind of each agent's snapshots in the recording.
fn snapshot_kinds(dir: &Path) -> Vec<Option<ActivationKind>> {
    let (maps, _) = MapReader::open(&dir.join("recording/maps.bin"))
        .unwrap()
        .read_all()
        .unwrap();
    let mut kinds = vec![None; 6];
    for m in maps {
        let k = ActivationKind::from_u8(m.header.activation);
        let slot = &mut kinds[m.header.agent as usize];
        assert!(
            slot.is_none() || *slot == k,
            "agent {} changed kind",
            m.header.agent
        );
        *slot = k;
    }
    kinds
}

#[test]
fn a_mixed_swarm_reaches_every_goal_and_replays_byte_for_byte() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let a = run("mixed-a", &tmp.path().join("a"), &registry);
    let b = run("mixed-b", &tmp.path().join("b"), &registry);
    assert!(
        a == b,
        "the two lockstep logs differ ({} vs {} bytes)",
        a.len(),
        b.len()
    );
    let route = Some(ActivationKind::Route);
    let kinds = snapshot_kinds(&tmp.path().join("a"));
    assert!(
        kinds[..2].iter().all(|k| k.is_some() && *k != route),
        "{kinds:?}"
    );
    assert!(kinds[2..].iter().all(|k| *k == route), "{kinds:?}");
}
