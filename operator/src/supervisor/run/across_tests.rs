//! A run across hosts as one host's supervisor sees it: the roster it gives a restarted sim
//! or coordinator of another host, and the planned faults it carries out.

use std::path::{Path, PathBuf};

use super::action::Action;
use super::host::HostPart;
use super::slots::Slots;
use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::msg::{LifecycleEvent, Role};
use hnav_runtime::scenario::Scenario;

/// The base station runs the sim and the coordinator, `robots` every agent of the demo.
const PLACEMENT: &str = r#"
[[host]]
name = "base"
listen = ["tcp/10.0.0.1:7447"]
sim = true
coordinator = true

[[host]]
name = "robots"
agents = "0-5"
"#;

fn demo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/demo.toml")
}

/// Host `name`'s slots in a run of the demo placed by `placement`.
fn slots_of(tmp: &Path, placement: &str, name: &str) -> Slots {
    let file = tmp.join("hosts.toml");
    std::fs::write(&file, placement).unwrap();
    let args = ProcessArgs {
        run: "across".into(),
        scenario: demo(),
        agents: None,
        seed: None,
        mode: None,
        replicas: None,
        dir: None,
        resume: false,
        faults: Vec::new(),
    };
    let scenario = Scenario::load(demo()).unwrap();
    let part = HostPart::load(&file, name, &scenario).unwrap();
    Slots::new(&args, tmp, &scenario, tmp, None, Some(&part), None)
}

/// The agents named by the roster entries among `todo`.
fn roster(todo: &[Action]) -> Vec<u32> {
    todo.iter()
        .filter_map(|a| match a {
            Action::Publish(l) if l.event == LifecycleEvent::Roster as u8 => Some(l.index),
            _ => None,
        })
        .collect()
}

#[test]
fn a_restarted_sim_or_coordinator_of_another_host_gets_this_hosts_roster() {
    let tmp = tempfile::tempdir().unwrap();
    let mut robots = slots_of(tmp.path(), PLACEMENT, "robots");
    for role in [Role::Coordinator, Role::Sim] {
        let todo = robots.on_up(&[(role as u8, 0)]);
        assert_eq!(roster(&todo), [0, 1, 2, 3, 4, 5], "after {role:?}'s Up");
    }
    // An agent's Up (or one of an unknown process) asks for no roster; nor does the base
    // station, which runs no agent, answer with one.
    assert!(roster(&robots.on_up(&[(Role::Agent as u8, 3)])).is_empty());
    let mut base = slots_of(tmp.path(), PLACEMENT, "base");
    assert!(roster(&base.on_up(&[(Role::Coordinator as u8, 0)])).is_empty());
}
