//! A supervisor killed by SIGKILL (issue 11, item 6): its children die with it, and what the
//! run left (shared memory in `/dev/shm`, iceoryx2 files, the registry entry) is removed by
//! the next `hnav run` or by `hnav clean RUN`; a live run is never cleaned.
//!
//! In its own test binary because it SIGKILLs processes.

use std::path::Path;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use hnav_runtime::transport::{run_iceoryx2_files, run_shm_files, RunId};
use hnav_tests::swarm::{hnav_output, repo_root, wait_for_ps, SwarmRun};
use hnav_tests::TestRun;
use nix::sys::signal::Signal;

const RUN_TIMEOUT: Duration = Duration::from_secs(600);

/// One test at a time: `SwarmRun::start` points `HNAV_RUNS_DIR` of this process at the
/// test's registry.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn pid_exists(pid: i32) -> bool {
    nix::sys::signal::kill(nix::unistd::Pid::from_raw(pid), None).is_ok()
}

/// Starts the 8-agent scenario, waits until rounds are being logged, SIGKILLs the
/// supervisor and waits (bounded) until every child has died with it, leaving files of the
/// run behind.
fn run_and_kill_the_supervisor(run: &mut TestRun, dir: &Path, registry: &Path) {
    let scenario = repo_root().join("scenarios/random-32-32-10.toml");
    let mut swarm = SwarmRun::start(run, &scenario, dir, registry, &["--mode", "lockstep"])
        .expect("hnav run starts");
    let listed = wait_for_ps(registry, run.run.as_str(), Duration::from_secs(120), |r| {
        r["processes"].as_array().is_some_and(|p| p.len() == 10)
    })
    .expect("the run is listed");
    let pids: Vec<i32> = listed["processes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["pid"].as_i64().unwrap() as i32)
        .collect();
    let seg = dir.join("log/seg-00000000.hlog");
    let deadline = Instant::now() + Duration::from_secs(120);
    while std::fs::metadata(&seg).map_or(0, |m| m.len()) < 4096 {
        assert!(
            Instant::now() < deadline,
            "no rounds logged\n{}",
            swarm.log_tails()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    swarm.peer.signal(Signal::SIGKILL).unwrap();
    swarm
        .finish(Duration::from_secs(30))
        .expect("the supervisor dies");
    let deadline = Instant::now() + Duration::from_secs(30);
    while let Some(pid) = pids.iter().find(|&&p| pid_exists(p)) {
        assert!(
            Instant::now() < deadline,
            "process {pid} outlived its SIGKILLed supervisor"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(
        !run_shm_files(&run.run).is_empty() && !run_iceoryx2_files(&run.run).is_empty(),
        "the killed run left no files to clean: the test shows nothing"
    );
}

/// The runs `hnav ps --json` lists.
fn listed_runs(registry: &Path) -> Vec<String> {
    let out = hnav_output(
        &["ps".into(), "--json".into()],
        registry,
        Duration::from_secs(60),
    )
    .expect("hnav ps");
    let v: serde_json::Value = serde_json::from_str(&out.stdout).expect("ps prints JSON");
    v["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["run_id"].as_str().unwrap().to_string())
        .collect()
}

fn assert_nothing_left(run: &RunId, registry: &Path) {
    assert_eq!(
        run_shm_files(run),
        Vec::<std::path::PathBuf>::new(),
        "/dev/shm"
    );
    assert_eq!(
        run_iceoryx2_files(run),
        Vec::<std::path::PathBuf>::new(),
        "iceoryx2 root"
    );
    assert!(
        !listed_runs(registry).contains(&run.to_string()),
        "hnav ps still lists {run}"
    );
}

#[test]
fn a_fresh_run_cleans_up_after_a_sigkilled_supervisor() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let mut dead = TestRun::new("svkill1");
    run_and_kill_the_supervisor(&mut dead, &tmp.path().join("a"), &registry);
    assert!(listed_runs(&registry).contains(&dead.run.to_string()));

    let fresh = TestRun::new("svfresh");
    let out = hnav_output(
        &[
            "run".into(),
            repo_root()
                .join("scenarios/demo.toml")
                .display()
                .to_string(),
            "--run".into(),
            fresh.run.to_string(),
            "--out".into(),
            tmp.path().join("b").display().to_string(),
        ],
        &registry,
        RUN_TIMEOUT,
    )
    .expect("the fresh run ends");
    assert!(out.status.success(), "{out:?}");
    assert!(
        out.stderr.contains(&format!("cleaned run {}", dead.run)),
        "the fresh run does not say it cleaned the dead one: {out:?}"
    );
    assert_nothing_left(&dead.run, &registry);
}

#[test]
fn hnav_clean_removes_a_dead_run_and_refuses_a_live_one() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let clean = |id: &str| {
        hnav_output(
            &["clean".into(), id.into()],
            &registry,
            Duration::from_secs(60),
        )
        .expect("hnav clean ends")
    };

    // A live run: refused, and it runs on.
    let mut live = TestRun::new("svlive");
    let mut swarm = SwarmRun::start(
        &mut live,
        &repo_root().join("scenarios/demo.toml"),
        &tmp.path().join("live"),
        &registry,
        &["--mode", "lockstep"],
    )
    .expect("hnav run starts");
    wait_for_ps(
        &registry,
        live.run.as_str(),
        Duration::from_secs(120),
        |r| r["processes"].as_array().is_some_and(|p| p.len() == 8),
    )
    .expect("the live run is listed");
    let out = clean(live.run.as_str());
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert!(out.stderr.contains("is live"), "{out:?}");
    let status = swarm.finish(RUN_TIMEOUT).expect("the live run ends");
    assert!(status.success(), "{status}\n{}", swarm.log_tails());

    // A dead one: `hnav ps` names the command, which removes everything.
    let mut dead = TestRun::new("svkill2");
    let dir = tmp.path().join("dead");
    run_and_kill_the_supervisor(&mut dead, &dir, &registry);
    let ps = hnav_output(&["ps".into()], &registry, Duration::from_secs(60)).expect("hnav ps");
    assert!(
        ps.stdout.contains(&format!("`hnav clean {}`", dead.run)),
        "{ps:?}"
    );
    let out = clean(dead.run.as_str());
    assert!(out.status.success(), "{out:?}");
    assert!(
        out.stdout.contains(&format!("cleaned run {}", dead.run)),
        "{out:?}"
    );
    assert_nothing_left(&dead.run, &registry);
    assert!(
        dir.join("log/seg-00000000.hlog").exists(),
        "clean touched the run directory"
    );
}
