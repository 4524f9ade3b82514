//! `scenarios/mixed.toml` end to end: two agents of each planner (`hnav`, `pso`, `ga-fuzzy`)
//! cross a room under one coordinator. Every robot reaches its goal without a collision, two
//! lockstep runs write byte-identical consensus logs, and the recording shows that the seeds'
//! planners really drove their agents (their snapshots are routes, not neural maps).

use std::path::Path;

use hnav_operator::recording::MapReader;
use hnav_runtime::msg::ActivationKind;
use hnav_tests::swarm::{lockstep_all_home, repo_root};

/// Runs the scenario in lockstep into `dir`; returns the log segment's bytes.
fn run(tag: &str, dir: &Path, registry: &Path) -> Vec<u8> {
    let scenario = repo_root().join("scenarios/mixed.toml");
    lockstep_all_home(tag, &scenario, dir, registry, 6).1
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
