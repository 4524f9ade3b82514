//! Lifelong runs (`[tasks]`, issue 35 item 6): goals that keep coming, a run that ends by
//! time, the same log twice in lockstep, three replicas in realtime, and a bad `[tasks]`
//! refused before anything starts.

use std::path::{Path, PathBuf};
use std::time::Duration;

use hnav_runtime::consensus_log::{read_decided, Record};
use hnav_tests::swarm::{verify_log, workspace_bin, SwarmRun};
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
