//! A run whose coordinator or sim, or whose last agent, is gone for good ends at once, with
//! exit code 3 and the reason in its summary, instead of idling until its time limit.
//!
//! In its own test binary because the supervisor SIGKILLs processes.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use hnav_tests::swarm::{repo_root, SwarmRun};
use hnav_tests::TestRun;

/// Far below the scenario's ten-minute time limit, far above a debug run's start-up.
const BOUND: Duration = Duration::from_secs(90);

/// The demo scenario with a ten-minute time limit, `role` SIGKILLed at round 20 and never
/// restarted (for an agent: agent 0).
fn scenario(dir: &Path, role: &str) -> PathBuf {
    let text = std::fs::read_to_string(repo_root().join("scenarios/demo.toml")).unwrap();
    let text = text.replace("time_limit_s = 60", "time_limit_s = 600");
    let index = if role == "agent" { "index = 0\n" } else { "" };
    let extra = format!(
        "\n[restart]\n{role} = {{ policy = \"never\" }}\n\
         \n[[faults]]\nat_round = 20\naction = \"kill\"\nrole = \"{role}\"\n{index}"
    );
    let path = dir.join(format!("{role}.toml"));
    std::fs::write(&path, format!("{text}{extra}")).unwrap();
    path
}

/// Runs `role`'s scenario with `extra` arguments; it must end with exit code 3 well within
/// [`BOUND`], its summary's `cannot_go_on` containing each of `says`.
fn ends_at_once(role: &str, extra: &[&str], says: &[&str]) {
    let tmp = tempfile::tempdir().unwrap();
    let mut run = TestRun::new(&format!("gone-{role}"));
    let started = Instant::now();
    let mut args = vec!["--mode", "lockstep"];
    args.extend_from_slice(extra);
    let mut swarm = SwarmRun::start(
        &mut run,
        &scenario(tmp.path(), role),
        &tmp.path().join("out"),
        &tmp.path().join("runs"),
        &args,
    )
    .expect("hnav run starts");
    let status = swarm.finish(BOUND).expect("the run ends at once");
    assert_eq!(status.code(), Some(3), "{status}\n{}", swarm.log_tails());
    assert!(started.elapsed() < BOUND);
    let s = swarm.summary().unwrap();
    let why = s["cannot_go_on"].as_str().unwrap_or_default();
    for word in says {
        assert!(why.contains(word), "{word:?} not in {s}");
    }
}

#[test]
fn a_run_whose_coordinator_is_gone_for_good_ends_at_once() {
    ends_at_once("coordinator", &[], &["hnav-coordinator", "never"]);
}

#[test]
fn a_run_whose_sim_is_gone_for_good_ends_at_once() {
    ends_at_once("sim", &[], &["hnav-sim", "never"]);
}

/// An agent gone for good ends the run only when it was the last one: here the only one.
#[test]
fn a_run_whose_last_agent_is_gone_for_good_ends_at_once() {
    ends_at_once(
        "agent",
        &["--agents", "1"],
        &["no agent is left", "hnav-agent 0", "never"],
    );
}
