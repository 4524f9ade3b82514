//! A SIGKILLed sim is restarted and resumes from its checkpoint (`DIR/sim.ckpt.{0,1}`): the robots'
//! ground truth, tick counters and collision count carry on where they were, so every agent's
//! odometry stays continuous and every robot reaches its goal. In lockstep the run decides
//! exactly what the same run without the kill decides.
//!
//! In its own test binary because the supervisor SIGKILLs processes.

mod restart_common;

use std::sync::Mutex;
use std::time::Duration;

use hnav_runtime::consensus_log::Record;
use hnav_runtime::msg::{LifecycleEvent, Role};
use restart_common::{demo, run, Finished, FAST};

const BOUND: Duration = Duration::from_secs(300);
const SIM_KILL: &str = "[[faults]]\nat_round = 60\naction = \"kill\"\nrole = \"sim\"\n";

/// One swarm at a time: two at once on a 2-core machine only slow both down.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn all_at_goal(f: &Finished) {
    assert!(f.status.success(), "{}\n{}", f.status, f.swarm.log_tails());
    let s = f.summary();
    assert_eq!(s["collisions"], 0, "{s}");
    for a in s["agents"].as_array().unwrap() {
        assert_eq!(a["reached_goal"], true, "{a}");
    }
    assert!(
        f.process_log("sim").contains("resumed from the checkpoint"),
        "the sim did not resume from its checkpoint:\n{}",
        f.process_log("sim")
    );
}

/// The records that carry decisions: rounds, replans, unreachable goals and the end.
fn decisions(f: &Finished) -> Vec<Record> {
    f.records()
        .into_iter()
        .filter(|r| !matches!(r, Record::Header(_) | Record::Lifecycle(_)))
        .collect()
}

#[test]
fn a_killed_lockstep_sim_resumes_and_the_run_decides_what_it_would_have() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let clean = demo(tmp.path(), "clean", &[], "");
    let killed = demo(tmp.path(), "killed", &[], SIM_KILL);
    let a = run("simclean", &clean, &tmp.path().join("a"), "lockstep", BOUND);
    let b = run("simkill", &killed, &tmp.path().join("b"), "lockstep", BOUND);
    all_at_goal(&b);
    b.check_log_and_summary();
    b.check_odometry_continuous();
    assert_eq!(
        b.lifecycle(),
        vec![
            (60, Role::Sim, 0, LifecycleEvent::Down, 0),
            (60, Role::Sim, 0, LifecycleEvent::Restarted, 1),
        ],
        "the kill and the restart are logged at the fault's round"
    );
    // The header differs (the fault plan is part of the scenario hash) and the kill run logs
    // the sim's death and restart; every decision is the same.
    let (da, db) = (decisions(&a), decisions(&b));
    assert_eq!(
        da.len(),
        db.len(),
        "the runs logged different numbers of records"
    );
    assert!(
        da == db,
        "the lockstep run with the sim killed decided differently"
    );
}

#[test]
fn a_killed_realtime_sim_resumes_and_every_robot_arrives() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let scenario = demo(tmp.path(), "rt", &FAST, SIM_KILL);
    let f = run("simkillrt", &scenario, tmp.path(), "realtime", BOUND);
    all_at_goal(&f);
    f.check_log_and_summary();
    f.check_odometry_continuous();
    let sim: Vec<_> = f
        .lifecycle()
        .into_iter()
        .filter(|l| l.1 == Role::Sim)
        .collect();
    assert_eq!(sim.len(), 2, "{sim:?}");
    assert_eq!(
        (sim[0].3, sim[1].3, sim[1].4),
        (LifecycleEvent::Down, LifecycleEvent::Restarted, 1)
    );
}
