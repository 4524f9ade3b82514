//! A run across hosts as one host's supervisor sees it: the roster it gives a restarted sim
//! or coordinator of another host, and the planned faults it carries out.

use std::path::{Path, PathBuf};

use super::action::Action;
use super::faults::FaultSchedule;
use super::host::HostPart;
use super::slots::Slots;
use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::msg::{LifecycleEvent, Role};
use hnav_runtime::scenario::{
    ClockMode, FaultAction, FaultSignal, FaultSpec, FaultTarget, FaultTime, Scenario,
};

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
    let args = ProcessArgs::new("across", demo());
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

/// The demo in lockstep with `faults` (at rounds) planned.
fn with_faults(faults: &[(u64, FaultTarget)]) -> Scenario {
    let mut s = Scenario::load(demo()).unwrap();
    s.sim.clock = ClockMode::Lockstep;
    s.faults = faults
        .iter()
        .map(|&(round, target)| FaultSpec {
            at: FaultTime::Round(round),
            action: FaultAction::Kill(FaultSignal::Kill),
            target,
        })
        .collect();
    s
}

#[test]
fn each_host_carries_out_the_faults_of_its_own_processes() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = with_faults(&[(40, FaultTarget::Agent(3)), (60, FaultTarget::Sim)]);
    let file = tmp.path().join("hosts.toml");
    std::fs::write(&file, PLACEMENT).unwrap();
    let base = HostPart::load(&file, "base", &scenario).unwrap();
    let robots = HostPart::load(&file, "robots", &scenario).unwrap();
    assert!(
        robots.runs_target(&FaultTarget::Agent(3)) && !base.runs_target(&FaultTarget::Agent(3))
    );
    assert!(base.runs_target(&FaultTarget::Sim) && !robots.runs_target(&FaultTarget::Sim));
    assert!(base.runs_target(&FaultTarget::Coordinator));
    assert_eq!(base.check_faults(&scenario.faults, &scenario), Ok(()));
    // The sim holds at round 40 for agent 3's kill: only the robots' host, which runs it,
    // resumes (agent 3 is not running here, so the fault misses and the hold ends at once);
    // the base station must not.
    let slots = slots_of(tmp.path(), PLACEMENT, "robots");
    let mut here = FaultSchedule::new(&scenario, Some(&robots));
    assert!(
        here.on_hold(&slots, 40).is_empty(),
        "agent 3 is not running"
    );
    assert!(
        matches!(here.resume_due(&slots), Some(Action::Publish(l)) if l.event == LifecycleEvent::Resume as u8)
    );
    let base_slots = slots_of(tmp.path(), PLACEMENT, "base");
    let mut there = FaultSchedule::new(&scenario, Some(&base));
    assert!(there.on_hold(&base_slots, 40).is_empty());
    assert!(
        there.resume_due(&base_slots).is_none(),
        "the base station resumed another host's hold"
    );
    // At round 60 (the sim's kill) it is the other way round.
    assert!(here.on_hold(&slots, 60).is_empty());
    assert!(here.resume_due(&slots).is_none());
    assert!(there.on_hold(&base_slots, 60).is_empty());
    assert!(there.resume_due(&base_slots).is_some());
}

#[test]
fn a_lockstep_round_whose_faults_are_on_two_hosts_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("hosts.toml");
    std::fs::write(&file, PLACEMENT).unwrap();
    let scenario = with_faults(&[(40, FaultTarget::Agent(3)), (40, FaultTarget::Sim)]);
    let part = HostPart::load(&file, "robots", &scenario).unwrap();
    let e = part.check_faults(&scenario.faults, &scenario).unwrap_err();
    assert!(
        e.contains("round 40 target processes of hosts robots and base"),
        "{e}"
    );
    // In realtime each host fires its own when due: nothing to hold, nothing refused.
    let mut realtime = scenario.clone();
    realtime.sim.clock = ClockMode::Realtime;
    assert_eq!(part.check_faults(&realtime.faults, &realtime), Ok(()));
    // `coordinator` in lockstep with the replicas on two hosts: which one leads then is not
    // known, so no host could be the one to resume.
    let apart =
        PLACEMENT.replace("coordinator = true", "coordinator = [1, 2]") + "coordinator = [3]\n";
    std::fs::write(&file, apart).unwrap();
    let mut three = with_faults(&[(40, FaultTarget::Coordinator)]);
    three.coordinator.replicas = 3;
    let part = HostPart::load(&file, "robots", &three).unwrap();
    let e = part.check_faults(&three.faults, &three).unwrap_err();
    assert!(e.contains("name the replica (coordinator:ID)"), "{e}");
    let three = with_faults(&[(40, FaultTarget::Replica(3))]);
    let mut three = three;
    three.coordinator.replicas = 3;
    assert_eq!(part.check_faults(&three.faults, &three), Ok(()));
    assert!(
        part.runs_target(&FaultTarget::Replica(3)) && !part.runs_target(&FaultTarget::Replica(1))
    );
}
