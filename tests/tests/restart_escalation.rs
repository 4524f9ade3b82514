//! A role that exceeds its restart budget: an agent's robot is lost (it stands for the rest of
//! the run and its goal counts as not reached) and the run ends as soon as every other robot
//! is at its goal, with exit code 4 and the summary naming the lost robot, instead of waiting
//! out its time limit; under `[restart] on_give_up = "stop"` the run stops at once (exit 3).
//! A coordinator killed together with an agent that is not restarted resumes knowing that
//! agent is gone (the supervisor's roster), so lockstep does not deadlock and realtime keeps
//! its round rate.
//!
//! In its own test binary because the supervisor SIGKILLs processes.

mod restart_common;

use std::sync::Mutex;
use std::time::Duration;

use hnav_runtime::msg::{LifecycleEvent, Role};
use restart_common::{demo, run, Finished, FAST};

/// Far below the ten-minute time limits, far above a debug run on a loaded machine.
const BOUND: Duration = Duration::from_secs(180);
/// Agent 4 starts in the corner [0, 0], which no other robot needs: standing there for good
/// it leaves every other goal reachable.
const LOST: usize = 4;

static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn kill(round: u64, role: &str) -> String {
    let index = if role == "agent" {
        format!("index = {LOST}\n")
    } else {
        String::new()
    };
    format!("[[faults]]\nat_round = {round}\naction = \"kill\"\nrole = \"{role}\"\n{index}\n")
}

/// The run ended with exit code 4, robot [`LOST`] lost (for `why`) and every other one at its
/// goal, well before the time limit.
fn ended_with_the_robot_lost(f: &Finished, why: &str) {
    assert_eq!(
        f.status.code(),
        Some(4),
        "{}\n{}",
        f.status,
        f.swarm.log_tails()
    );
    let s = f.summary();
    assert_eq!(s["end"], "all-at-goal-or-lost", "{s}");
    let lost = s["lost"].as_array().unwrap();
    assert_eq!(lost.len(), 1, "{s}");
    assert_eq!(lost[0]["id"], LOST as u64, "{s}");
    let said = lost[0]["why"].as_str().unwrap();
    assert!(
        said.contains("hnav-agent 4") && said.contains(why),
        "{said}"
    );
    for (i, a) in s["agents"].as_array().unwrap().iter().enumerate() {
        assert_eq!(a["lost"], i == LOST, "{a}");
        assert_eq!(a["reached_goal"], i != LOST, "{a}");
    }
    f.check_log_and_summary();
    let rounds = s["rounds"].as_u64().unwrap();
    assert!(
        rounds < 20_000,
        "{rounds} rounds: the run waited for its time limit"
    );
}

#[test]
fn an_agent_past_its_restart_budget_is_lost_and_the_run_ends_when_the_others_arrive() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let extra = format!(
        "[restart]\nagent = {{ max_restarts = 1 }}\n\n{}{}",
        kill(5, "agent"),
        kill(10, "agent")
    );
    let scenario = demo(
        tmp.path(),
        "budget",
        &[("time_limit_s = 60", "time_limit_s = 600")],
        &extra,
    );
    let f = run("budget", &scenario, tmp.path(), "lockstep", BOUND);
    ended_with_the_robot_lost(&f, "restart limit of 1 reached");
    let agent = |e, n| (Role::Agent, LOST as u32, e, n);
    let logged: Vec<_> = f
        .lifecycle()
        .into_iter()
        .map(|l| (l.0, (l.1, l.2, l.3, l.4)))
        .collect();
    assert_eq!(
        logged,
        vec![
            (5, agent(LifecycleEvent::Down, 0)),
            (5, agent(LifecycleEvent::Restarted, 1)),
            (10, agent(LifecycleEvent::Down, 1)),
            (10, agent(LifecycleEvent::Lost, 1)),
        ]
    );
}

#[test]
fn under_on_give_up_stop_an_agent_not_restarted_stops_the_run_at_once() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let extra = format!(
        "[restart]\nagent = {{ policy = \"never\" }}\non_give_up = \"stop\"\n\n{}",
        kill(5, "agent")
    );
    let scenario = demo(
        tmp.path(),
        "stop",
        &[("time_limit_s = 60", "time_limit_s = 600")],
        &extra,
    );
    let f = run("giveupstop", &scenario, tmp.path(), "lockstep", BOUND);
    assert_eq!(
        f.status.code(),
        Some(3),
        "{}\n{}",
        f.status,
        f.swarm.log_tails()
    );
    let s = f.summary();
    let why = s["cannot_go_on"].as_str().unwrap_or_default();
    assert!(
        why.contains("hnav-agent 4") && why.contains("on_give_up"),
        "{s}"
    );
    assert!(s["rounds"].as_u64().unwrap() < 1000, "{s}");
}

/// The coordinator and agent 4 (policy never) killed at the same round: the coordinator
/// was down when agent 4 died, so only the roster tells it.
fn coordinator_and_lost_agent(mode: &str) -> Finished {
    let tmp = tempfile::tempdir().unwrap().keep();
    let extra = format!(
        "[restart]\nagent = {{ policy = \"never\" }}\n\n{}{}",
        kill(30, "agent"),
        kill(30, "coordinator")
    );
    let replace: Vec<(&str, &str)> = if mode == "realtime" {
        FAST.to_vec()
    } else {
        vec![("time_limit_s = 60", "time_limit_s = 600")]
    };
    let scenario = demo(&tmp, "both", &replace, &extra);
    let f = run(&format!("both{mode}"), &scenario, &tmp, mode, BOUND);
    ended_with_the_robot_lost(&f, "restart policy is never");
    let life = f.lifecycle();
    let restarted = life
        .iter()
        .find(|l| l.1 == Role::Coordinator && l.3 == LifecycleEvent::Restarted)
        .expect("the coordinator's restart is logged");
    assert_eq!(
        restarted.4, 1,
        "the coordinator's restart count is the supervisor's: {life:?}"
    );
    // Both logged, in order, whichever of the two the supervisor reaps first: the restarted
    // coordinator does not log the agent's events it hears before its own `Restarted` (the
    // topic's history may be the `Lost` alone); the roster after it says what it missed.
    let agent: Vec<_> = life
        .iter()
        .filter(|l| l.1 == Role::Agent && l.2 == LOST as u32)
        .map(|l| l.3)
        .collect();
    assert_eq!(
        agent,
        [LifecycleEvent::Down, LifecycleEvent::Lost],
        "agent {LOST}'s events: {life:?}"
    );
    f
}

#[test]
fn a_lockstep_coordinator_killed_with_an_agent_for_good_does_not_deadlock() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let f = coordinator_and_lost_agent("lockstep");
    let life = f.lifecycle();
    assert!(
        life.iter().all(|l| l.0 == 30),
        "logged at the faults' round: {life:?}"
    );
}

#[test]
fn a_realtime_coordinator_killed_with_an_agent_for_good_keeps_its_round_rate() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let f = coordinator_and_lost_agent("realtime");
    let s = f.summary();
    // Rounds follow the sim's 100 Hz periods; a coordinator waiting for the dead agent
    // closes a round only at its 50 ms deadline (at most 20 a second).
    let rate = s["rounds"].as_f64().unwrap() / s["wall_time_s"].as_f64().unwrap();
    assert!(rate > 35.0, "{rate:.1} rounds/s over the run: {s}");
}
