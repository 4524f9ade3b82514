//! Lifelong runs (`[tasks]`, issue 35 item 6): goals that keep coming, a run that ends by
//! time, the same log twice in lockstep, three replicas in realtime, and a bad `[tasks]`
//! refused before anything starts; robots whose wheels slip localise and stay off the walls.

use std::path::{Path, PathBuf};
use std::time::Duration;

use hnav_runtime::consensus_log::{read_decided, Record};
use hnav_tests::swarm::{repo_root, verify_log, workspace_bin, SwarmRun};
use hnav_tests::TestRun;

/// Generous: a debug build of 7 processes on a 2-core machine.
const RUN_TIMEOUT: Duration = Duration::from_secs(600);

/// Four robots in the demo's room, crossing corner to corner, then goals drawn with a seed.
fn scenario(dir: &Path, clock: &str, seconds: u32) -> PathBuf {
    let text = format!(
        r#"name = "lifelong"
[map]
rows = [
  "............",
  "............",
  "..@@....@@..",
  "..@@....@@..",
  "............",
  ".....@@.....",
  ".....@@.....",
  "............",
  "..@@....@@..",
  "..@@....@@..",
  "............",
  "............",
]
[sim]
clock = "{clock}"
seed = 3
[coordinator]
rules = "pibt"
time_limit_s = {seconds}
[tasks]
stream = "seeded"
[[agents]]
start = [0, 0]
goal = [11, 11]
[[agents]]
start = [11, 0]
goal = [0, 11]
[[agents]]
start = [0, 11]
goal = [11, 0]
[[agents]]
start = [11, 11]
goal = [0, 0]
"#
    );
    let path = dir.join(format!("lifelong-{clock}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

fn run(tag: &str, scenario: &Path, dir: &Path, registry: &Path, extra: &[&str]) -> SwarmRun {
    let mut test_run = TestRun::new(tag);
    let mut swarm =
        SwarmRun::start(&mut test_run, scenario, dir, registry, extra).expect("hnav run starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert!(
        status.success(),
        "hnav run failed: {status}\n{}",
        swarm.log_tails()
    );
    swarm
}

/// Tasks done per agent: its task records.
fn tasks_per_agent(log: &Path, agents: usize) -> Vec<u64> {
    let mut done = vec![0; agents];
    for r in read_decided(log).unwrap().records {
        if let Record::Task(t) = r {
            done[t.agent as usize] = done[t.agent as usize].max(t.task);
        }
    }
    done
}

#[test]
fn a_lockstep_lifelong_run_keeps_giving_tasks_ends_by_time_and_repeats_byte_for_byte() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let scenario = scenario(tmp.path(), "lockstep", 90);
    let extra = ["--no-record"];
    let first = run("life1", &scenario, &tmp.path().join("a"), &registry, &extra);
    let s = first.summary().unwrap();
    assert_eq!(s["end"], "time-limit", "{s}");
    assert_eq!(s["rounds"], 9000, "{s}");
    assert_eq!(s["collisions"], 0, "{s}");
    let done = tasks_per_agent(&first.dir.join("log"), 4);
    assert!(done.iter().all(|&n| n >= 2), "tasks per agent {done:?}");
    let t = &s["tasks"];
    assert_eq!(t["tasks_done"], done.iter().sum::<u64>(), "{s}");
    let p50 = t["task_time_p50_s"].as_f64().unwrap();
    let p99 = t["task_time_p99_s"].as_f64().unwrap();
    assert!(0.0 < p50 && p50 <= p99 && p99 <= 90.0, "{t}");
    let per_hour = t["throughput_per_hour"].as_f64().unwrap();
    assert!(
        (per_hour - t["tasks_done"].as_f64().unwrap() * 40.0).abs() < 1e-6,
        "{t}"
    );
    assert_eq!(t["per_window"], serde_json::json!([t["tasks_done"]]), "{t}");
    let (ok, report) = verify_log(&first.dir.join("log"));
    assert!(ok && report.contains(" task"), "{report}");
    // `hnav log replay` decides every round, the tasks included, as logged.
    let replay_run = TestRun::new("lifereplay");
    let replay = std::process::Command::new(workspace_bin("hnav"))
        .args(["log", "replay", first.dir.to_str().unwrap()])
        .args(["--run", replay_run.run.as_str()])
        .env("HNAV_RUNS_DIR", &registry)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&replay.stdout);
    assert!(
        replay.status.success() && said.contains("identical"),
        "{said}\n{}",
        String::from_utf8_lossy(&replay.stderr)
    );
    drop(replay_run);

    let second = run("life2", &scenario, &tmp.path().join("b"), &registry, &extra);
    let seg = "log/seg-00000000.hlog";
    let a = std::fs::read(first.dir.join(seg)).unwrap();
    let b = std::fs::read(second.dir.join(seg)).unwrap();
    assert!(
        a == b,
        "the two lockstep logs differ ({} vs {} bytes)",
        a.len(),
        b.len()
    );
    println!("log {} bytes, tasks {done:?}, summary {t}", a.len());
}

#[test]
fn a_realtime_lifelong_run_with_three_replicas_gives_tasks_until_its_time_limit() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = scenario(tmp.path(), "realtime", 40);
    let extra = ["--no-record", "--replicas", "3"];
    let swarm = run(
        "liferep",
        &scenario,
        &tmp.path().join("out"),
        &tmp.path().join("runs"),
        &extra,
    );
    let s = swarm.summary().unwrap();
    assert_eq!(s["end"], "time-limit", "{s}");
    assert_eq!(s["collisions"], 0, "{s}");
    let done = tasks_per_agent(&swarm.dir.join("log"), 4);
    assert!(done.iter().sum::<u64>() >= 2, "tasks per agent {done:?}");
    assert_eq!(s["tasks"]["tasks_done"], done.iter().sum::<u64>(), "{s}");
    println!("tasks {done:?}, summary {}", s["tasks"]);
}

#[test]
fn a_bad_tasks_section_is_refused_at_its_line_and_nothing_starts() {
    let tmp = tempfile::tempdir().unwrap();
    let good = std::fs::read_to_string(scenario(tmp.path(), "lockstep", 10)).unwrap();
    let bad = good.replace(
        "stream = \"seeded\"\n",
        "stream = \"list\"\n[[tasks.goals]]\nagent = 1\ncells = [[2, 2]]\n",
    );
    let path = tmp.path().join("bad.toml");
    std::fs::write(&path, bad).unwrap();
    let line = 1
        + good
            .lines()
            .position(|l| l == "stream = \"seeded\"")
            .unwrap()
        + 3;
    let out = tmp.path().join("out");
    let o = std::process::Command::new(workspace_bin("hnav"))
        .args([
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .env("HNAV_RUNS_DIR", tmp.path().join("runs"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "{}:{line}: tasks.goals.cells (2, 2) is on an obstacle",
            path.display()
        )),
        "{stderr}"
    );
    assert!(!out.join("logs").exists(), "a process log was written");
}

/// The largest distance between a robot's true and dead-reckoned positions in a run's
/// recording, and the robot and simulated second where it was.
fn largest_estimate_error(dir: &Path) -> (f64, u16, f64) {
    use hnav_operator::recording::{PoseSource, TrajectoryReader, DIR, TRAJECTORIES};
    let (samples, _) = TrajectoryReader::open(&dir.join(DIR).join(TRAJECTORIES))
        .unwrap()
        .read_all()
        .unwrap();
    let mut truth = std::collections::HashMap::new();
    for s in samples.iter().filter(|s| s.source == PoseSource::Truth) {
        truth.insert((s.t_ns, s.robot), (s.x_m, s.y_m));
    }
    let mut worst = (0.0, 0, 0.0);
    for s in samples.iter().filter(|s| s.source == PoseSource::Estimate) {
        if let Some(&(x, y)) = truth.get(&(s.t_ns, s.robot)) {
            let e = f64::from((x - s.x_m).hypot(y - s.y_m));
            if e > worst.0 {
                worst = (e, s.robot, s.t_ns as f64 / 1e9);
            }
        }
    }
    worst
}

/// Dead reckoning drifts (a heading known to a tick pair, here also 1 % wheel slip); nothing
/// bounded it before the sim's localisation fixes, and the six robots of
/// `scenarios/replicas-lifelong.toml` drove into walls after half a minute once their
/// wheels slipped (after 2 260 s with the default Hall sensors and no slip: the release-only
/// check is that scenario itself). With the default `[localisation]` the agents take a fix
/// whenever they drifted past its gate, and no robot touches anything.
#[test]
fn slipping_robots_localise_and_stay_off_the_walls_in_a_lifelong_run() {
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(repo_root().join("scenarios/replicas-lifelong.toml"))
        .unwrap()
        .replace("replicas = 3\n", "")
        .replace("time_limit_s = 7200\n", "time_limit_s = 40\n")
        .replace("seed = 1\n", "seed = 1\nslip_std = 0.01\n");
    assert!(text.contains("time_limit_s = 40\n") && text.contains("slip_std"));
    let scenario = tmp.path().join("drift.toml");
    std::fs::write(&scenario, text).unwrap();
    let mut test_run = TestRun::new("drift");
    let dir = tmp.path().join("out");
    let mut swarm = SwarmRun::start(
        &mut test_run,
        &scenario,
        &dir,
        &tmp.path().join("runs"),
        &[],
    )
    .expect("hnav run starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    let s = swarm.summary().unwrap();
    let (error_m, robot, at_s) = largest_estimate_error(&dir);
    println!("largest estimate error {error_m:.4} m (robot {robot} at {at_s} s)");
    assert_eq!(
        s["collisions"], 0,
        "collisions at {} ns; largest estimate error {error_m:.4} m (robot {robot} at {at_s} s)",
        s["recording"]["collisions_at_ns"]
    );
    // The gate (5 sigma = 10 mm) plus a fix's noise and a second's drift: well inside the
    // 22 mm between a robot at a cell's centre and the cell's edge.
    assert!(
        error_m < 0.016,
        "estimate error {error_m} m (robot {robot} at {at_s} s)"
    );
    assert!(status.success(), "{status}\n{}", swarm.log_tails());
    assert_eq!(s["end"], "time-limit", "{s}");
}
