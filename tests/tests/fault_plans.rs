//! Fault plans from the command line (`hnav run --kill/--term/--freeze`) and against a live
//! run (`hnav kill`): a lockstep freeze and a kill in seconds are as reproducible as a
//! scenario's kill at a round, a realtime kill in seconds ends with every robot at goal, and
//! `hnav kill` restarts an agent of a running swarm (its `signalled` line before the
//! `exited` line of the death it caused); bad faults and targets are refused before anything
//! is spawned.
//!
//! In its own test binary because it SIGKILLs and SIGSTOPs processes.

use std::path::Path;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use hnav_runtime::msg::{LifecycleEvent, Role};
use hnav_tests::swarm::{hnav_output, lifecycle_records, repo_root, verify_log, SwarmRun};
use hnav_tests::TestRun;

const RUN_TIMEOUT: Duration = Duration::from_secs(300);

/// The machine has two cores: one swarm at a time keeps the runs' timing sane.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn demo() -> std::path::PathBuf {
    repo_root().join("scenarios/demo.toml")
}

/// The lines of `DIR/events.jsonl`.
fn events(dir: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(dir.join("events.jsonl"))
        .unwrap_or_default()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect()
}

/// Whether `events` has an `event` line for `node` whose `key` is `value`.
fn has(events: &[serde_json::Value], event: &str, node: &str, key: &str, value: &str) -> bool {
    events
        .iter()
        .any(|e| e["event"] == event && e["node"] == node && (key.is_empty() || e[key] == value))
}

/// Every robot at its goal, no collision, and the log verifies.
fn assert_finished_well(swarm: &SwarmRun, status: std::process::ExitStatus) {
    let s = swarm.summary().expect("a summary");
    assert!(
        status.success(),
        "run failed: {status}\n{s}\n{}",
        swarm.log_tails()
    );
    let agents = s["agents"].as_array().unwrap();
    assert!(agents.iter().all(|a| a["reached_goal"] == true), "{s}");
    assert_eq!(s["collisions"], 0, "{s}");
    let (ok, report) = verify_log(&swarm.dir.join("log"));
    assert!(ok, "log does not verify:\n{report}");
}

/// Runs the demo with `extra` arguments into `dir` and checks that it finished well.
fn run_demo(tag: &str, dir: &Path, registry: &Path, extra: &[&str]) -> SwarmRun {
    let mut run = TestRun::new(tag);
    let mut swarm = SwarmRun::start(&mut run, &demo(), dir, registry, extra).expect("starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert_finished_well(&swarm, status);
    swarm
}

#[test]
fn a_lockstep_freeze_and_a_kill_in_seconds_give_the_same_log_twice() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    // 0.5 s of simulated time is round 50 of the demo's 10 ms periods.
    let plan = [
        "--mode",
        "lockstep",
        "--freeze",
        "agent:1@round:30+0.3s",
        "--kill",
        "agent:2@0.5s",
    ];
    let mut logs = Vec::new();
    for tag in ["a", "b"] {
        let dir = tmp.path().join(tag);
        run_demo(&format!("plan-{tag}"), &dir, &registry, &plan);
        let ev = events(&dir);
        assert!(
            ev.iter().any(|e| e["event"] == "signalled"
                && e["node"] == "agent-1"
                && e["signal"] == "SIGSTOP"
                && e["fault"] == 0
                && e["round"] == 30),
            "the freeze at round 30: {ev:?}"
        );
        assert!(
            has(&ev, "signalled", "agent-1", "signal", "SIGCONT"),
            "{ev:?}"
        );
        assert!(
            ev.iter().any(|e| e["event"] == "signalled"
                && e["node"] == "agent-2"
                && e["signal"] == "SIGKILL"
                && e["fault"] == 1
                && e["round"] == 50),
            "the kill at 0.5 s = round 50: {ev:?}"
        );
        assert!(
            !has(&ev, "exited", "agent-1", "", ""),
            "a freeze is not a death: {ev:?}"
        );
        assert_eq!(
            lifecycle_records(&dir.join("log")),
            vec![
                (50, Some(Role::Agent), 2, Some(LifecycleEvent::Down)),
                (50, Some(Role::Agent), 2, Some(LifecycleEvent::Restarted)),
            ],
            "the kill is logged at its round; the freeze leaves no record"
        );
        logs.push(std::fs::read(dir.join("log/seg-00000000.hlog")).unwrap());
    }
    assert!(
        logs[0] == logs[1],
        "the two lockstep logs differ ({} vs {} bytes)",
        logs[0].len(),
        logs[1].len()
    );
}

#[test]
fn a_realtime_coordinator_kill_in_seconds_ends_with_every_robot_at_goal() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("out");
    run_demo(
        "plan-rt",
        &dir,
        &tmp.path().join("runs"),
        &[
            "--mode",
            "realtime",
            "--kill",
            "coordinator@1.0s",
            "--freeze",
            "agent:3@0.5s+0.2s",
        ],
    );
    let ev = events(&dir);
    // The freeze is continued by a deadline of the supervisor's wait, 0.2 s after the stop.
    let stamp = |signal: &str| {
        ev.iter()
            .find(|e| e["node"] == "agent-3" && e["signal"] == signal && e["fault"] == 1)
            .and_then(|e| e["t_ns"].as_u64())
            .unwrap_or_else(|| panic!("agent-3 {signal}: {ev:?}"))
    };
    let frozen_ms = (stamp("SIGCONT") - stamp("SIGSTOP")) as f64 / 1e6;
    println!("agent-3 frozen for {frozen_ms:.1} ms (asked 200 ms)");
    assert!((200.0..1000.0).contains(&frozen_ms), "{frozen_ms} ms");
    assert!(
        ev.iter().any(|e| e["event"] == "signalled"
            && e["node"] == "coordinator"
            && e["signal"] == "SIGKILL"
            && e["fault"] == 0),
        "{ev:?}"
    );
    assert!(has(&ev, "exited", "coordinator", "", ""), "{ev:?}");
    assert!(has(&ev, "up", "coordinator", "", ""), "restarted: {ev:?}");
}

/// Waits (bounded) until the run in `dir` is logging rounds: past its start-up.
fn wait_for_rounds(swarm: &SwarmRun) {
    let seg = swarm.dir.join("log/seg-00000000.hlog");
    let deadline = Instant::now() + Duration::from_secs(120);
    while std::fs::metadata(&seg).map_or(0, |m| m.len()) < 4096 {
        assert!(
            Instant::now() < deadline,
            "no rounds logged within 120 s\n{}",
            swarm.log_tails()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn hnav(args: &[&str], registry: &Path) -> hnav_tests::swarm::HnavOutput {
    let args: Vec<String> = args.iter().map(|s| s.to_string()).collect();
    hnav_output(&args, registry, Duration::from_secs(30)).expect("hnav runs")
}

#[test]
fn hnav_kill_restarts_an_agent_of_a_live_run_and_refuses_what_it_cannot_do() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let mut run = TestRun::new("plan-kill");
    let id = run.run.as_str().to_string();
    let mut swarm = SwarmRun::start(
        &mut run,
        &demo(),
        &tmp.path().join("out"),
        &registry,
        &["--mode", "lockstep"],
    )
    .expect("starts");
    wait_for_rounds(&swarm);

    let o = hnav(&["kill", &id, "agent:99"], &registry);
    assert_eq!(o.status.code(), Some(2), "{o:?}");
    assert_eq!(
        o.stderr.trim(),
        format!("error: run `{id}` has no agent:99 (its agents are 0-5)")
    );
    let o = hnav(&["kill", &id, "robot:1"], &registry);
    assert_eq!(o.status.code(), Some(2), "{o:?}");
    assert_eq!(
        o.stderr.trim(),
        "error: robot:1: unknown target `robot:1`: expected agent:N, coordinator, coordinator:ID or sim"
    );
    let o = hnav(&["kill", "no-such-run", "agent:0"], &registry);
    assert_eq!(o.status.code(), Some(2), "{o:?}");
    assert_eq!(
        o.stderr.trim(),
        format!(
            "error: no live run `no-such-run` in the run registry {} (`hnav ps` lists the live runs)",
            registry.display()
        )
    );

    let o = hnav(&["kill", &id, "agent:0", "--signal", "KILL"], &registry);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    assert!(
        o.stdout.starts_with("sent SIGKILL to agent:0 (pid "),
        "{o:?}"
    );

    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert_finished_well(&swarm, status);
    let ev = events(&swarm.dir);
    let signalled = ev
        .iter()
        .position(|e| {
            e["event"] == "signalled"
                && e["node"] == "agent-0"
                && e["signal"] == "SIGKILL"
                && e["fault"].is_null()
        })
        .unwrap_or_else(|| panic!("hnav kill's line: {ev:?}"));
    // The journal reads in the order things happened (issue 34): the signal, then the death.
    let exited = ev
        .iter()
        .position(|e| e["event"] == "exited" && e["node"] == "agent-0")
        .unwrap_or_else(|| panic!("agent 0's exit: {ev:?}"));
    assert!(
        signalled < exited && ev[signalled]["t_ns"].as_u64() <= ev[exited]["t_ns"].as_u64(),
        "hnav kill's `signalled` line must come before the `exited` line it caused:\n{:#}\n{:#}",
        ev[signalled],
        ev[exited]
    );
    assert!(
        ev[signalled..]
            .iter()
            .any(|e| e["event"] == "spawned" && e["node"] == "agent-0"),
        "agent 0 restarted after the kill: {ev:?}"
    );
    let downs: Vec<_> = lifecycle_records(&swarm.dir.join("log"))
        .into_iter()
        .filter(|r| r.1 == Some(Role::Agent) && r.2 == 0)
        .map(|r| r.3)
        .collect();
    assert_eq!(
        downs,
        vec![Some(LifecycleEvent::Down), Some(LifecycleEvent::Restarted)]
    );

    // The run is over: its registry entry is gone.
    let o = hnav(&["kill", &id, "agent:0"], &registry);
    assert_eq!(o.status.code(), Some(2), "{o:?}");
    assert!(o.stderr.contains("no live run"), "{o:?}");
}

#[test]
fn bad_faults_on_the_command_line_are_refused_before_anything_starts() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let out = tmp.path().join("out");
    let scenario = demo().display().to_string();
    let out_s = out.display().to_string();
    for (flag, value, problem) in [
        (
            "--kill",
            "agent:9@round:40",
            "the scenario has 6 agents (0-5)",
        ),
        (
            "--kill",
            "agent:3",
            "expected TARGET@WHEN, e.g. agent:3@round:40",
        ),
        (
            "--freeze",
            "sim@round:4+x",
            "`+x`: expected +SECONDSs, e.g. +3s",
        ),
        (
            "--term",
            "coordinator@1s+1s",
            "`+1s`: only --freeze takes a duration",
        ),
    ] {
        let o = hnav(&["run", &scenario, "--out", &out_s, flag, value], &registry);
        assert_eq!(o.status.code(), Some(2), "{o:?}");
        assert_eq!(o.stderr.trim(), format!("error: {flag} {value}: {problem}"));
        assert!(!out.exists(), "nothing is spawned, no run directory made");
    }
    // With --agents the faults are checked against the agents of the run.
    let o = hnav(
        &[
            "run",
            &scenario,
            "--out",
            &out_s,
            "--agents",
            "2",
            "--kill",
            "agent:2@1s",
        ],
        &registry,
    );
    assert_eq!(o.status.code(), Some(2), "{o:?}");
    assert_eq!(
        o.stderr.trim(),
        "error: --kill agent:2@1s: the scenario has 2 agents (0-1)"
    );
}
