//! Supervisor building blocks against real processes: small shell children for spawning,
//! exit reporting, waiter wake-ups, restart decisions and the escalating stop; the run
//! registry. `hnav ps` run as a binary is in `ps_cli.rs`.

mod common;
use common::wait_for_line;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use hnav_operator::supervisor::child::{Child, ChildError, ChildSpec, ExitInfo, Signal};
use hnav_operator::supervisor::exit_fd::WatchMode;
use hnav_operator::supervisor::proc_stat::pid_alive;
use hnav_operator::supervisor::registry::{RunRecord, RunRegistry};
use hnav_operator::supervisor::restart::{GiveUpReason, RestartDecision, RestartTracker};
use hnav_operator::supervisor::stop::{stop_all, StopHow};
use hnav_runtime::msg::Role;
use hnav_runtime::scenario::{RestartPolicy, RestartRule};
use hnav_runtime::transport::{PurgeOnDrop, RunId, Transport};

fn sh(dir: &Path, name: &str, script: &str) -> ChildSpec {
    ChildSpec::new(Role::Agent, 0, "/bin/sh", dir.join(format!("{name}.log")))
        .arg("-c")
        .arg(script)
}

/// Test-only: a pid that is gone (zombies count as gone) within 5 s.
fn gone_soon(pid: u32) -> bool {
    let deadline = Instant::now() + Duration::from_secs(5);
    while Instant::now() < deadline {
        if !pid_alive(pid) {
            return true;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    false
}

fn exited_pid() -> u32 {
    let mut c = Command::new("true").spawn().unwrap();
    let pid = c.id();
    c.wait().unwrap();
    pid
}

// ---------------------------------------------------------------------------------------
// child

#[test]
fn exit_code_is_reported_and_output_appended() {
    let dir = tempfile::tempdir().unwrap();
    let spec = sh(
        &dir.path().join("logs/nested"),
        "a",
        "echo out; echo err >&2; exit 3",
    );
    for _ in 0..2 {
        let child = Child::spawn(&spec).unwrap();
        let exit = child.wait(Some(Duration::from_secs(10))).unwrap();
        assert_eq!(exit, ExitInfo::Exited(3));
        assert!(exit.is_failure());
        assert_eq!(exit.code(), Some(3));
        assert_eq!(child.exit(), Some(exit));
    }
    let log = std::fs::read_to_string(&spec.log_file).unwrap();
    assert_eq!(log.matches("out\n").count(), 2, "{log}");
    assert_eq!(log.matches("err\n").count(), 2, "{log}");
}

#[test]
fn clean_exit_is_not_a_failure() {
    let dir = tempfile::tempdir().unwrap();
    let child = Child::spawn(&sh(dir.path(), "ok", "exit 0")).unwrap();
    let exit = child.wait(Some(Duration::from_secs(10))).unwrap();
    assert_eq!(exit, ExitInfo::Exited(0));
    assert!(!exit.is_failure());
}

#[test]
fn sigkill_is_reported_as_the_signal() {
    let dir = tempfile::tempdir().unwrap();
    let spec = ChildSpec::new(Role::Sim, 0, "sleep", dir.path().join("s.log")).arg("30");
    let child = Child::spawn(&spec).unwrap();
    assert_eq!(child.try_reap(), None);
    child.signal(Signal::SIGKILL).unwrap();
    let exit = child.wait(Some(Duration::from_secs(10))).unwrap();
    assert_eq!(exit, ExitInfo::Signaled(Signal::SIGKILL));
    assert_eq!(exit.signal(), Some(Signal::SIGKILL));
    assert!(exit.is_failure());
    // After reaping, signalling is a no-op rather than a shot at a reused pid.
    child.signal(Signal::SIGKILL).unwrap();
    child.signal_group(Signal::SIGKILL).unwrap();
}

#[test]
fn child_runs_in_its_own_process_group() {
    let dir = tempfile::tempdir().unwrap();
    let child = Child::spawn(&sh(dir.path(), "pg", "exec sleep 30")).unwrap();
    let stat = std::fs::read_to_string(format!("/proc/{}/stat", child.pid())).unwrap();
    let after_comm = &stat[stat.rfind(')').unwrap() + 2..];
    let pgrp: u32 = after_comm.split(' ').nth(2).unwrap().parse().unwrap();
    assert_eq!(pgrp, child.pid());
    child.signal_group(Signal::SIGKILL).unwrap();
    assert_eq!(
        child.wait(Some(Duration::from_secs(10))),
        Some(ExitInfo::Signaled(Signal::SIGKILL))
    );
}

#[test]
fn spawn_errors_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let missing = ChildSpec::new(
        Role::Agent,
        1,
        dir.path().join("nope"),
        dir.path().join("x"),
    );
    assert!(matches!(
        Child::spawn(&missing),
        Err(ChildError::Spawn { .. })
    ));
    let file = dir.path().join("file");
    std::fs::write(&file, "").unwrap();
    let bad_log = ChildSpec::new(Role::Agent, 1, "true", file.join("sub/x.log"));
    assert!(matches!(
        Child::spawn(&bad_log),
        Err(ChildError::LogFile { .. })
    ));
}

#[test]
fn dropping_a_running_child_kills_and_reaps_it() {
    let dir = tempfile::tempdir().unwrap();
    let child = Child::spawn(&sh(dir.path(), "d", "exec sleep 30")).unwrap();
    let pid = child.pid();
    drop(child);
    assert!(!pid_alive(pid));
}

#[test]
fn reaping_kills_leftovers_in_the_group() {
    let dir = tempfile::tempdir().unwrap();
    let pidfile = dir.path().join("grandchild.pid");
    let spec = sh(dir.path(), "l", "sleep 60 & echo $! > \"$0\"; exit 0").arg(&pidfile);
    let child = Child::spawn(&spec).unwrap();
    assert_eq!(
        child.wait(Some(Duration::from_secs(10))),
        Some(ExitInfo::Exited(0))
    );
    let grandchild: u32 = std::fs::read_to_string(&pidfile)
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    assert!(gone_soon(grandchild), "grandchild {grandchild} survived");
}

fn waitset_wake_latency(mode: WatchMode) -> Duration {
    let dir = tempfile::tempdir().unwrap();
    // `exec date` makes the timestamp writer the child itself: it exits right after writing.
    let spec = sh(dir.path(), "w", "sleep 0.2 && exec date +%s%N");
    let run = PurgeOnDrop(RunId::unique("exitwake"));
    let transport = Transport::builder(&run.0)
        .handle_signals(false)
        .create()
        .unwrap();
    // Without the lost-wake-up re-check, so that a wake-up is the exit and nothing else.
    let waiter = transport.waiter().unwrap().with_recheck(None);
    let child = Child::spawn_with(&spec, mode).unwrap();
    assert_eq!(child.exit_fd().mode(), mode);
    let exit = child.watch(&waiter).unwrap();
    let exit_id = exit.id();

    // No wake-up while the child runs.
    let mut early = false;
    let soon = Instant::now() + Duration::from_millis(50);
    waiter
        .wait_with(Some(soon), |id| early |= id == exit_id)
        .unwrap();
    assert!(!early, "woke before the child exited");

    let mut woke = None;
    let started = Instant::now();
    let deadline = started + Duration::from_secs(10);
    while woke.is_none() && Instant::now() < deadline {
        waiter
            .wait_with(Some(deadline), |id| {
                if id == exit_id {
                    woke = Some(SystemTime::now());
                }
            })
            .unwrap();
    }
    let woke = woke.expect("no wake-up within 10 s");
    drop(exit);
    assert_eq!(
        child.try_reap(),
        Some(ExitInfo::Exited(0)),
        "readable pidfd means reapable"
    );
    let log = std::fs::read_to_string(&spec.log_file).unwrap();
    let exited_ns: u128 = log.trim().parse().unwrap();
    let woke_ns = woke.duration_since(UNIX_EPOCH).unwrap().as_nanos();
    Duration::from_nanos(woke_ns.saturating_sub(exited_ns) as u64)
}

#[test]
fn waitset_wakes_on_child_exit_pidfd() {
    let latency = waitset_wake_latency(WatchMode::Pidfd);
    println!("pidfd wake latency: {latency:?}");
    assert!(latency < Duration::from_millis(500), "{latency:?}");
}

#[test]
fn waitset_wakes_on_child_exit_waiter_thread() {
    let latency = waitset_wake_latency(WatchMode::WaiterThread);
    println!("waiter-thread wake latency: {latency:?}");
    assert!(latency < Duration::from_millis(500), "{latency:?}");
}

// ---------------------------------------------------------------------------------------
// restart

fn rule(policy: RestartPolicy, max_restarts: u32, backoff_ms: u64) -> RestartRule {
    RestartRule {
        policy,
        max_restarts,
        backoff_ms,
    }
}

const FAIL: ExitInfo = ExitInfo::Exited(1);
const CLEAN: ExitInfo = ExitInfo::Exited(0);
const KILLED: ExitInfo = ExitInfo::Signaled(Signal::SIGKILL);

fn restart_after(ms: u64) -> RestartDecision {
    RestartDecision::Restart {
        after: Duration::from_millis(ms),
    }
}

#[test]
fn restart_never() {
    let mut t = RestartTracker::new(rule(RestartPolicy::Never, 3, 100));
    for exit in [FAIL, CLEAN, KILLED] {
        assert_eq!(
            t.on_exit(&exit),
            RestartDecision::GiveUp(GiveUpReason::Never)
        );
    }
    assert_eq!(t.restarts(), 0);
}

#[test]
fn restart_on_failure() {
    let mut t = RestartTracker::new(rule(RestartPolicy::OnFailure, 5, 100));
    assert_eq!(
        t.on_exit(&CLEAN),
        RestartDecision::GiveUp(GiveUpReason::CleanExit)
    );
    assert_eq!(t.on_exit(&FAIL), restart_after(100));
    assert_eq!(t.on_exit(&KILLED), restart_after(200));
    assert_eq!(t.on_exit(&ExitInfo::Lost), restart_after(400));
    assert_eq!(t.restarts(), 3);
}

#[test]
fn restart_always() {
    let mut t = RestartTracker::new(rule(RestartPolicy::Always, 5, 10));
    assert_eq!(t.on_exit(&CLEAN), restart_after(10));
    assert_eq!(t.on_exit(&FAIL), restart_after(20));
    assert_eq!(t.restarts(), 2);
}

#[test]
fn restart_cap_is_enforced() {
    let mut t = RestartTracker::new(rule(RestartPolicy::Always, 2, 10));
    assert!(matches!(t.on_exit(&FAIL), RestartDecision::Restart { .. }));
    assert!(matches!(t.on_exit(&FAIL), RestartDecision::Restart { .. }));
    for _ in 0..2 {
        assert_eq!(
            t.on_exit(&FAIL),
            RestartDecision::GiveUp(GiveUpReason::LimitReached { max_restarts: 2 })
        );
    }
    assert_eq!(t.restarts(), 2);
    let mut zero = RestartTracker::new(rule(RestartPolicy::Always, 0, 10));
    assert_eq!(
        zero.on_exit(&FAIL),
        RestartDecision::GiveUp(GiveUpReason::LimitReached { max_restarts: 0 })
    );
}

#[test]
fn restart_backoff_doubles_up_to_the_cap() {
    let mut t = RestartTracker::new(rule(RestartPolicy::OnFailure, 100, 100));
    let delays: Vec<u64> = (0..9)
        .map(|_| match t.on_exit(&FAIL) {
            RestartDecision::Restart { after } => after.as_millis() as u64,
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(delays, [100, 200, 400, 800, 1600, 3200, 5000, 5000, 5000]);
    assert_eq!(t.backoff(63), Duration::from_secs(5), "no overflow");
    let capped = RestartTracker::new(rule(RestartPolicy::Always, 9, 100))
        .with_backoff_cap(Duration::from_millis(250));
    assert_eq!(capped.backoff(2), Duration::from_millis(250));
    // A base above the cap is used as it is, never shortened.
    let slow = RestartTracker::new(rule(RestartPolicy::Always, 9, 7000));
    assert_eq!(slow.backoff(0), Duration::from_secs(7));
    assert_eq!(slow.backoff(3), Duration::from_secs(7));
}

// ---------------------------------------------------------------------------------------
// stop_all

#[test]
fn stop_all_escalates_and_reaps() {
    let dir = tempfile::tempdir().unwrap();
    let done = Child::spawn(&sh(dir.path(), "done", "exit 4")).unwrap();
    let polite = Child::spawn(&sh(dir.path(), "polite", "echo ready; exec sleep 30")).unwrap();
    let stubborn = Child::spawn(&sh(
        dir.path(),
        "stubborn",
        "trap '' TERM; echo ready; sleep 30",
    ))
    .unwrap();
    wait_for_line(&polite.spec().log_file, "ready");
    wait_for_line(&stubborn.spec().log_file, "ready");
    let grace = Duration::from_millis(300);
    let started = Instant::now();
    let stopped = stop_all([&done, &polite, &stubborn], grace);
    let took = started.elapsed();
    println!("stop_all took {took:?}: {stopped:?}");
    assert_eq!(stopped.len(), 3);
    assert_eq!(stopped[0].how, StopHow::ByItself);
    assert_eq!(stopped[0].exit, ExitInfo::Exited(4));
    assert_eq!(stopped[1].how, StopHow::AfterSigterm);
    assert_eq!(stopped[1].exit, ExitInfo::Signaled(Signal::SIGTERM));
    assert_eq!(stopped[2].how, StopHow::AfterSigkill);
    assert_eq!(stopped[2].exit, ExitInfo::Signaled(Signal::SIGKILL));
    assert_eq!(stopped[2].pid, stubborn.pid());
    assert!(took >= 2 * grace, "{took:?}");
    assert!(took < Duration::from_secs(5), "{took:?}");
    for c in [&done, &polite, &stubborn] {
        assert!(c.exit().is_some(), "reaped");
        assert!(!pid_alive(c.pid()), "no zombie");
    }
}

#[test]
fn a_stopped_child_is_seen_stopped_and_stop_all_ends_it_with_sigterm() {
    let dir = tempfile::tempdir().unwrap();
    let frozen = Child::spawn(&sh(dir.path(), "frozen", "echo ready; exec sleep 30")).unwrap();
    wait_for_line(&frozen.spec().log_file, "ready");
    frozen.signal(Signal::SIGSTOP).unwrap();
    assert!(frozen.wait_stopped(), "stopped, not exited");
    let stopped = stop_all([&frozen], Duration::from_millis(300));
    assert_eq!(stopped[0].how, StopHow::AfterSigterm, "{stopped:?}");
    assert_eq!(stopped[0].exit, ExitInfo::Signaled(Signal::SIGTERM));
    // One that dies instead of stopping is reported as not stopped, and left to be reaped.
    let dying = Child::spawn(&sh(dir.path(), "dying", "exit 3")).unwrap();
    assert!(!dying.wait_stopped());
    assert_eq!(dying.wait(None), Some(ExitInfo::Exited(3)));
}

#[test]
fn stop_all_returns_early_when_everything_exits() {
    let dir = tempfile::tempdir().unwrap();
    let a = Child::spawn(&sh(dir.path(), "a", "sleep 0.1")).unwrap();
    let started = Instant::now();
    let stopped = stop_all([&a], Duration::from_secs(20));
    assert!(started.elapsed() < Duration::from_secs(5));
    assert_eq!(stopped[0].how, StopHow::ByItself);
    assert_eq!(stopped[0].exit, ExitInfo::Exited(0));
}

#[test]
fn stop_all_kills_grandchildren_in_the_group() {
    let dir = tempfile::tempdir().unwrap();
    let pidfile = dir.path().join("grandchild.pid");
    let spec = sh(dir.path(), "g", "sleep 60 & echo $! > \"$0\"; wait").arg(&pidfile);
    let child = Child::spawn(&spec).unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    let grandchild: u32 = loop {
        if let Some(pid) = std::fs::read_to_string(&pidfile)
            .ok()
            .and_then(|s| s.trim().parse().ok())
        {
            break pid;
        }
        assert!(Instant::now() < deadline, "no grandchild pid");
        std::thread::sleep(Duration::from_millis(10));
    };
    let stopped = stop_all([&child], Duration::from_millis(200));
    assert_eq!(stopped[0].how, StopHow::AfterSigterm);
    assert!(gone_soon(grandchild), "grandchild {grandchild} survived");
}

// ---------------------------------------------------------------------------------------
// registry

fn sample_record(reg: &RunRegistry, tag: &str) -> RunRecord {
    let mut rec = reg.new_record(&RunId::unique(tag), "/tmp/out/demo");
    rec.set_process(Role::Sim, 0, 11, 0);
    rec.set_process(Role::Agent, 0, 12, 0);
    rec
}

#[test]
fn registry_write_list_update_remove() {
    let dir = tempfile::tempdir().unwrap();
    let reg = RunRegistry::at(dir.path().join("runs"));
    assert!(reg.list_runs().is_empty(), "missing dir = no runs");
    let mut rec = sample_record(&reg, "wl");
    rec.write().unwrap();
    let runs = reg.list_runs();
    assert_eq!(runs.len(), 1);
    assert!(!runs[0].stale);
    assert_eq!(runs[0].record, rec);

    rec.set_process(Role::Agent, 0, 99, 1);
    rec.set_process(Role::Coordinator, 0, 13, 0);
    rec.write().unwrap();
    let back = RunRecord::read(rec.path()).unwrap();
    assert_eq!(back.processes.len(), 3);
    assert_eq!(back.processes[1].pid, 99);
    assert_eq!(back.processes[1].restarts, 1);

    let text = std::fs::read_to_string(rec.path()).unwrap();
    for key in [
        "\"run_id\"",
        "\"dir\"",
        "\"supervisor_pid\"",
        "\"started_unix_ms\"",
        "\"role\": \"coordinator\"",
    ] {
        assert!(text.contains(key), "{key} in {text}");
    }

    rec.remove().unwrap();
    rec.remove().unwrap();
    assert!(reg.list_runs().is_empty());
}

#[test]
fn registry_skips_bad_files_and_marks_stale_runs() {
    let dir = tempfile::tempdir().unwrap();
    let reg = RunRegistry::at(dir.path());
    sample_record(&reg, "live").write().unwrap();
    let mut stale = sample_record(&reg, "stale");
    stale.supervisor_pid = exited_pid();
    stale.write().unwrap();
    std::fs::write(dir.path().join("garbage.json"), "{ not json").unwrap();
    std::fs::write(
        dir.path().join("badrole.json"),
        r#"{"run_id":"x","dir":"/","supervisor_pid":1,"started_unix_ms":0,
            "processes":[{"role":"robot","index":0,"pid":1,"restarts":0}]}"#,
    )
    .unwrap();
    std::fs::write(dir.path().join(".half.tmp"), "{").unwrap();
    std::fs::write(dir.path().join("notes.txt"), "hi").unwrap();
    std::fs::create_dir(dir.path().join("dir.json")).unwrap();
    let runs = reg.list_runs();
    assert_eq!(runs.len(), 2, "{runs:?}");
    let by_id = |tag: &str| {
        runs.iter()
            .find(|r| r.record.run_id.starts_with(tag))
            .unwrap()
    };
    assert!(!by_id("live").stale);
    assert!(by_id("stale").stale);
}

#[test]
fn registry_updates_are_atomic() {
    let dir = tempfile::tempdir().unwrap();
    let reg = RunRegistry::at(dir.path());
    let mut rec = sample_record(&reg, "atomic");
    rec.write().unwrap();
    let path = rec.path().to_path_buf();
    let writer = std::thread::spawn(move || {
        for i in 0..300u32 {
            for a in 0..(i % 40) {
                rec.set_process(Role::Agent, a, 1000 + i, i);
            }
            rec.write().unwrap();
        }
    });
    let mut reads = 0;
    while !writer.is_finished() {
        RunRecord::read(&path).expect("never a torn record");
        reads += 1;
    }
    writer.join().unwrap();
    println!("{reads} consistent reads during 300 writes");
    let names: Vec<PathBuf> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(names, [path], "no temporary files left");
}
