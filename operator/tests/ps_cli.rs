//! `hnav ps [RUN] [--json]` run as a binary against registries of its own: one line per
//! run by default, a run's processes with RUN, everything in JSON.

mod common;
use common::wait_for_line;

use std::path::Path;
use std::process::Command;
use std::time::Duration;

use hnav_operator::supervisor::child::{Child, ChildSpec, Signal};
use hnav_operator::supervisor::registry::RunRegistry;
use hnav_runtime::msg::Role;
use hnav_runtime::transport::{purge_run, RunId, Transport};

/// A pid that has exited.
fn exited_pid() -> u32 {
    let mut c = Command::new("true").spawn().unwrap();
    let pid = c.id();
    c.wait().unwrap();
    pid
}

fn hnav_ps(runs_dir: &Path, json: bool) -> (String, std::process::ExitStatus) {
    let args: &[&str] = if json { &["--json"] } else { &[] };
    hnav_ps_args(runs_dir, args)
}

fn hnav_ps_args(runs_dir: &Path, args: &[&str]) -> (String, std::process::ExitStatus) {
    let out = Command::new(env!("CARGO_BIN_EXE_hnav"))
        .arg("ps")
        .args(args)
        .env("HNAV_RUNS_DIR", runs_dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    let mut text = String::from_utf8(out.stdout).unwrap();
    text.push_str(&stderr);
    (text, out.status)
}

#[test]
fn ps_with_no_runs_prints_an_empty_list() {
    let dir = tempfile::tempdir().unwrap();
    for runs_dir in [dir.path().to_path_buf(), dir.path().join("missing")] {
        let (out, status) = hnav_ps(&runs_dir, true);
        assert!(status.success());
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v, serde_json::json!({"runs": []}));
        let (out, status) = hnav_ps(&runs_dir, false);
        assert!(status.success());
        assert!(out.contains("no live runs"), "{out}");
    }
}

#[test]
fn ps_reports_running_and_exited_processes() {
    let dir = tempfile::tempdir().unwrap();
    let reg = RunRegistry::at(dir.path());
    let run = RunId::unique("ps");
    let mut rec = reg.new_record(&run, "/tmp/hnav-out/ps-demo");
    rec.set_process(Role::Agent, 0, std::process::id(), 2);
    rec.set_process(Role::Coordinator, 0, exited_pid(), 0);
    rec.write().unwrap();

    let (out, status) = hnav_ps(dir.path(), true);
    assert!(status.success());
    let (run_id, dir_key, procs) = (
        out.find("\"run_id\"").unwrap(),
        out.find("\"dir\"").unwrap(),
        out.find("\"processes\"").unwrap(),
    );
    assert!(run_id < dir_key && dir_key < procs, "field order: {out}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let runs = v["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 1);
    assert_eq!(runs[0]["run_id"], run.as_str());
    assert_eq!(runs[0]["dir"], "/tmp/hnav-out/ps-demo");
    assert_eq!(runs[0]["stale"], false);
    let p = runs[0]["processes"].as_array().unwrap();
    assert_eq!(p[0]["role"], "agent");
    assert_eq!(p[0]["index"], 0);
    assert_eq!(p[0]["pid"], std::process::id());
    assert_eq!(p[0]["state"], "running");
    assert_eq!(p[1]["role"], "coordinator");
    assert_eq!(p[1]["state"], "exited");

    let (table, status) = hnav_ps_args(dir.path(), &[run.as_str()]);
    assert!(status.success());
    println!("{table}");
    let header: Vec<&str> = table.lines().next().unwrap().split_whitespace().collect();
    assert_eq!(header, ["RUN", "DIR", "ROLE", "INDEX", "PID", "STATE"]);
    let line = table.lines().find(|l| l.contains(" agent ")).unwrap();
    assert!(
        line.contains(run.as_str()) && line.contains("running"),
        "{line}"
    );
}

/// Not a test on its own: a process for `ps_reports_a_killed_node_as_dead` to SIGKILL. It
/// joins a run as `agent-0` and waits to be killed.
#[test]
fn helper_iceoryx2_node() {
    let (Ok(run), Ok(ready)) = (
        std::env::var("HNAV_TEST_NODE_RUN"),
        std::env::var("HNAV_TEST_NODE_READY"),
    ) else {
        return;
    };
    let run = RunId::new(&run).unwrap();
    let _node = Transport::builder(&run)
        .node_name("agent-0")
        .handle_signals(false)
        .create()
        .unwrap();
    std::fs::write(ready, "ready").unwrap();
    std::thread::sleep(Duration::from_secs(60));
}

#[test]
fn ps_reports_a_killed_node_as_dead() {
    let dir = tempfile::tempdir().unwrap();
    let run = RunId::unique("psdead");
    let ready = dir.path().join("ready");
    let spec = ChildSpec::new(
        Role::Agent,
        0,
        std::env::current_exe().unwrap(),
        dir.path().join("node.log"),
    )
    .arg("--exact")
    .arg("helper_iceoryx2_node")
    .arg("--test-threads=1")
    .env("HNAV_TEST_NODE_RUN", run.as_str())
    .env("HNAV_TEST_NODE_READY", &ready);
    let node = Child::spawn(&spec).unwrap();
    wait_for_line(&ready, "ready");
    node.signal(Signal::SIGKILL).unwrap();
    node.wait(Some(Duration::from_secs(10))).unwrap();

    let reg = RunRegistry::at(dir.path().join("runs"));
    let mut rec = reg.new_record(&run, dir.path());
    rec.set_process(Role::Agent, 0, node.pid(), 0);
    rec.write().unwrap();
    let (out, status) = hnav_ps(reg.dir(), true);
    let (table, _) = hnav_ps_args(reg.dir(), &[run.as_str()]);
    let (summary, _) = hnav_ps(reg.dir(), false);
    println!("{table}");
    let _ = purge_run(&run);
    assert!(status.success());
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["runs"][0]["processes"][0]["state"], "dead", "{out}");
    assert!(table.contains("dead *"), "{table}");
    assert!(summary.contains("1 dead *"), "{summary}");
}

#[test]
fn ps_prints_one_line_per_run_and_the_processes_of_the_run_named() {
    let dir = tempfile::tempdir().unwrap();
    let reg = RunRegistry::at(dir.path());
    let big = RunId::unique("psbig");
    let mut rec = reg.new_record(&big, "/tmp/hnav-out/big");
    for a in 0..150 {
        rec.set_process(Role::Agent, a, std::process::id(), 0);
    }
    rec.set_process(Role::Sim, 0, std::process::id(), 0);
    rec.set_process(Role::Coordinator, 0, exited_pid(), 1);
    rec.write().unwrap();
    let small = RunId::unique("pssmall");
    let mut rec = reg.new_record(&small, "/tmp/hnav-out/small");
    rec.set_process(Role::Agent, 0, std::process::id(), 0);
    rec.write().unwrap();

    let (summary, status) = hnav_ps(dir.path(), false);
    assert!(status.success(), "{summary}");
    println!("{summary}");
    let lines: Vec<&str> = summary.lines().collect();
    let header: Vec<&str> = lines[0].split_whitespace().collect();
    assert_eq!(header, ["RUN", "DIR", "PROCESSES"]);
    let line = |run: &RunId| {
        let found: Vec<&&str> = lines.iter().filter(|l| l.contains(run.as_str())).collect();
        assert_eq!(found.len(), 1, "one line for {run}: {summary}");
        found[0].to_string()
    };
    assert!(line(&big).ends_with("151 running, 1 exited"), "{summary}");
    assert!(line(&small).ends_with("1 running"), "{summary}");
    assert_eq!(lines.len(), 4, "header, two runs, the hint: {summary}");
    assert!(lines[3].contains("`hnav ps RUN`"), "{summary}");

    let (table, status) = hnav_ps_args(dir.path(), &[big.as_str()]);
    assert!(status.success(), "{table}");
    assert_eq!(table.lines().count(), 1 + 152, "{table}");
    assert!(!table.contains(small.as_str()), "{table}");
    let (table, status) = hnav_ps_args(dir.path(), &["/tmp/hnav-out/small", "--json"]);
    assert!(status.success(), "{table}");
    let v: serde_json::Value = serde_json::from_str(&table).unwrap();
    assert_eq!(v["runs"].as_array().map(Vec::len), Some(1), "{table}");
    assert_eq!(v["runs"][0]["run_id"], small.as_str());

    let (out, status) = hnav_ps_args(dir.path(), &["nosuchrun"]);
    assert_eq!(status.code(), Some(2), "{out}");
    assert!(out.contains("no run nosuchrun"), "{out}");
}
