//! A run owns its run directory and its run id (issue 11, items 1 and 2): a second `hnav run`
//! on a live run's directory or with a live run's id is refused before it touches anything,
//! and a finished run's directory is reused only with `--force`.

use std::path::Path;
use std::sync::Mutex;
use std::time::Duration;

use hnav_tests::swarm::{hnav_output, repo_root, verify_log, wait_for_ps, HnavOutput, SwarmRun};
use hnav_tests::TestRun;

const RUN_TIMEOUT: Duration = Duration::from_secs(600);
/// A refused run exits at once; this only bounds a run that was not refused.
const REFUSAL_TIMEOUT: Duration = Duration::from_secs(300);

/// One test at a time: `SwarmRun::start` points `HNAV_RUNS_DIR` of this process at the
/// test's registry, and two swarms at once on 2 cores would only slow each other down.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// `hnav run SCENARIO --run ID --out DIR EXTRA...` to its end.
fn hnav_run(scenario: &Path, id: &str, dir: &Path, registry: &Path, extra: &[&str]) -> HnavOutput {
    let mut args: Vec<String> = vec![
        "run".into(),
        scenario.display().to_string(),
        "--run".into(),
        id.into(),
        "--out".into(),
        dir.display().to_string(),
        "--mode".into(),
        "lockstep".into(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    hnav_output(&args, registry, REFUSAL_TIMEOUT).expect("hnav run ends")
}

/// Starts the 8-agent MovingAI scenario and waits until all its processes are listed;
/// returns the run and its supervisor's pid.
fn start_live_run(run: &mut TestRun, dir: &Path, registry: &Path) -> (SwarmRun, u64) {
    let scenario = repo_root().join("scenarios/random-32-32-10.toml");
    let swarm = SwarmRun::start(run, &scenario, dir, registry, &["--mode", "lockstep"])
        .expect("hnav run starts");
    let listed = wait_for_ps(registry, run.run.as_str(), Duration::from_secs(120), |r| {
        r["processes"].as_array().is_some_and(|p| p.len() == 10)
    })
    .expect("the run is listed");
    let pid = listed["supervisor_pid"].as_u64().unwrap();
    (swarm, pid)
}

/// The live run still ends as it would have alone: exit 0, every robot at its goal, an
/// intact log.
fn assert_undisturbed(swarm: &mut SwarmRun) {
    let status = swarm.finish(RUN_TIMEOUT).expect("the live run ends");
    assert!(
        status.success(),
        "the live run was disturbed: {status}\n{}",
        swarm.log_tails()
    );
    let s = swarm.summary().unwrap();
    for a in s["agents"].as_array().unwrap() {
        assert_eq!(a["reached_goal"], true, "{a}");
    }
    let (ok, report) = verify_log(&swarm.dir.join("log"));
    assert!(ok, "the live run's log does not verify:\n{report}");
}

#[test]
fn a_second_run_on_a_live_runs_directory_is_refused() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let (dir, registry) = (tmp.path().join("out"), tmp.path().join("runs"));
    let mut first = TestRun::new("own1a");
    let (mut swarm, pid) = start_live_run(&mut first, &dir, &registry);

    let second = TestRun::new("own1b");
    let scenario = repo_root().join("scenarios/demo.toml");
    let out = hnav_run(&scenario, second.run.as_str(), &dir, &registry, &[]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    for needle in [
        dir.display().to_string(),
        format!("run {}", first.run),
        format!("pid {pid}"),
    ] {
        assert!(out.stderr.contains(&needle), "no {needle:?} in {out:?}");
    }
    assert_undisturbed(&mut swarm);
}

#[test]
fn reusing_a_finished_runs_directory_needs_force() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let (dir, registry) = (tmp.path().join("out"), tmp.path().join("runs"));
    let scenario = repo_root().join("scenarios/demo.toml");
    let seg = dir.join("log/seg-00000000.hlog");

    let first = TestRun::new("own2a");
    let out = hnav_run(&scenario, first.run.as_str(), &dir, &registry, &[]);
    assert!(out.status.success(), "{out:?}");
    let log = std::fs::read(&seg).unwrap();
    std::fs::write(dir.join("notes.txt"), "kept").unwrap();

    let second = TestRun::new("own2b");
    let out = hnav_run(&scenario, second.run.as_str(), &dir, &registry, &[]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert!(
        out.stderr.contains("--force") && out.stderr.contains(&dir.display().to_string()),
        "{out:?}"
    );
    assert_eq!(
        std::fs::read(&seg).unwrap(),
        log,
        "the finished run's log changed"
    );

    let third = TestRun::new("own2c");
    let out = hnav_run(&scenario, third.run.as_str(), &dir, &registry, &["--force"]);
    assert!(out.status.success(), "{out:?}");
    // A fresh run, not a resumed one: lockstep writes the same log again.
    assert_eq!(
        std::fs::read(&seg).unwrap(),
        log,
        "the forced run's log differs"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("notes.txt")).unwrap(),
        "kept"
    );
}

#[test]
fn a_live_run_id_is_refused_before_anything_is_spawned() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let mut live = TestRun::new("own3");
    let (mut swarm, pid) = start_live_run(&mut live, &tmp.path().join("a"), &registry);

    let other = tmp.path().join("b");
    let scenario = repo_root().join("scenarios/demo.toml");
    let out = hnav_run(&scenario, live.run.as_str(), &other, &registry, &[]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    for needle in [
        format!("run id {} is in use", live.run),
        format!("pid {pid}"),
    ] {
        assert!(out.stderr.contains(&needle), "no {needle:?} in {out:?}");
    }
    assert!(!other.exists(), "the refused run touched its directory");
    assert_undisturbed(&mut swarm);
}
