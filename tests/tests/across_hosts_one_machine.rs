//! Two hosts of one run across hosts on one machine, started as
//! `docs/tutorials/across-hosts.md` (section 3) says: the same `--run` for both, no
//! environment variables (issue 34, item 2: the second host was refused, its run id "in use
//! by a live run"). The test runs the tutorial's block itself: its `hosts.toml` (with free
//! loopback ports instead of the block's) and its two `hnav run` lines (the debug binary, the
//! test's run id, its own registry, in a temporary working directory so that the default
//! output directories land there).
//!
//! Both hosts must bring every robot home; the robots' host must not print made-up zeros
//! for the counts that only the coordinator's log has. While they run, `hnav ps` lists one
//! entry per host, and `hnav kill` finds each target in the entry of the host that runs it.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use hnav_runtime::transport::{purge_run, RunId};
use hnav_tests::swarm::{hnav_output, repo_root, workspace_bin};
use hnav_tests::{free_port, Peer, TestRun};

/// Generous: a debug build of ten processes and two bridges on a 2-core machine.
const RUN_TIMEOUT: Duration = Duration::from_secs(600);
/// The section of the tutorial whose block this test runs.
const SECTION: &str = "## 3. Two hosts on one machine";

/// Removes what the run left in each host's iceoryx2 domain, after its processes are gone
/// (declared before the [`TestRun`], so dropped after it kills them).
struct DomainPurge(RunId, Vec<String>);

impl Drop for DomainPurge {
    fn drop(&mut self) {
        for h in &self.1 {
            if let Ok(run) = self.0.clone().in_domain(h) {
                if let Err(e) = purge_run(&run) {
                    eprintln!("cleanup of run {run} in domain {h} failed: {e}");
                }
            }
        }
    }
}

/// The tutorial's block: the placement file's text and each `hnav run` line's words.
fn tutorial_block() -> (String, Vec<Vec<String>>) {
    let path = repo_root().join("docs/tutorials/across-hosts.md");
    let text = std::fs::read_to_string(&path).unwrap();
    let section = &text[text.find(SECTION).expect("the tutorial has its section 3")..];
    let block = section
        .split("```sh\n")
        .nth(1)
        .and_then(|b| b.split("\n```").next())
        .expect("section 3 has a sh block");
    let toml = block
        .split("<<'EOF'\n")
        .nth(1)
        .and_then(|b| b.split("\nEOF\n").next())
        .expect("the block writes hosts.toml with a here-document");
    let runs = block
        .lines()
        .filter(|l| l.starts_with("target/release/hnav run "))
        .map(|l| {
            l.split_whitespace()
                .take_while(|w| !w.starts_with('>') && *w != "&")
                .map(str::to_string)
                .collect()
        })
        .collect();
    (toml.to_string() + "\n", runs)
}

/// `words` of a tutorial line made to run here: the debug binary, the scenario from the
/// repository, the test's placement file and run id.
fn runnable(words: &[String], hosts: &Path, run: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (i, w) in words.iter().enumerate() {
        let after = |flag: &str| i > 0 && words[i - 1] == flag;
        out.push(if i == 0 {
            workspace_bin("hnav").display().to_string()
        } else if after("--hosts") {
            hosts.display().to_string()
        } else if after("--run") {
            run.to_string()
        } else if w.ends_with(".toml") {
            repo_root().join(w).display().to_string()
        } else {
            w.clone()
        });
    }
    out
}

/// The value after `flag` in `words`.
fn value_of<'w>(words: &'w [String], flag: &str) -> &'w str {
    let i = words.iter().position(|w| w == flag).unwrap();
    &words[i + 1]
}

/// The `hnav ps --json` entries of run `id`, once there are two whose processes are all
/// recorded (bounded: the start-up of both hosts).
fn both_entries(registry: &Path, id: &str) -> Vec<serde_json::Value> {
    let deadline = Instant::now() + Duration::from_secs(120);
    let mut last = String::new();
    while Instant::now() < deadline {
        let args = ["ps".to_string(), "--json".to_string()];
        last = hnav_output(&args, registry, Duration::from_secs(30))
            .expect("hnav ps")
            .stdout;
        let v: serde_json::Value = serde_json::from_str(&last).unwrap_or_default();
        let entries: Vec<serde_json::Value> = v["runs"]
            .as_array()
            .map(|r| r.iter().filter(|r| r["run_id"] == id).cloned().collect())
            .unwrap_or_default();
        // The sim, the coordinator, 6 agents and the host's bridge.
        let full = |e: &serde_json::Value| e["processes"].as_array().is_some_and(|p| p.len() == 9);
        if entries.len() == 2 && entries.iter().all(full) {
            return entries;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    panic!("run {id} not listed once per host within 120 s:\n{last}");
}

/// The state and host `entry` shows for process `role` `index`.
fn state(entry: &serde_json::Value, role: &str, index: u32) -> (String, Option<String>) {
    let p = entry["processes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["role"] == role && p["index"] == index)
        .unwrap_or_else(|| panic!("no {role} {index} in {entry}"));
    (
        p["state"].as_str().unwrap().to_string(),
        p["host"].as_str().map(str::to_string),
    )
}

/// `hnav ps` shows each host's part, and `hnav kill` (a harmless SIGCONT) reaches agent 3
/// on the robots' host and the sim on the base, each recorded in that host's journal.
fn tools_find_each_host(registry: &Path, id: &str, names: &[String]) {
    let entries = both_entries(registry, id);
    let (base, robots) = (&names[0], &names[1]);
    let running = ("running".to_string(), None);
    let on = |h: &String| ("remote".to_string(), Some(h.clone()));
    let base_entry = entries
        .iter()
        .find(|e| state(e, "sim", 0) == running)
        .unwrap_or_else(|| panic!("no entry runs the sim: {entries:?}"));
    let robots_entry = entries
        .iter()
        .find(|e| state(e, "agent", 3) == running)
        .unwrap_or_else(|| panic!("no entry runs agent 3: {entries:?}"));
    assert_eq!(state(base_entry, "agent", 3), on(robots));
    assert_eq!(state(robots_entry, "sim", 0), on(base));
    for target in ["agent:3", "sim"] {
        let args: Vec<String> = ["kill", id, target, "--signal", "CONT"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let o = hnav_output(&args, registry, Duration::from_secs(30)).expect("hnav kill");
        assert!(
            o.status.success()
                && o.stdout
                    .starts_with(&format!("sent SIGCONT to {target} (pid ")),
            "{o:?}"
        );
    }
}

/// Whether `dir/events.jsonl` has a `signalled` line for `node` with `signal`.
fn journalled(dir: &Path, node: &str, signal: &str) -> bool {
    std::fs::read_to_string(dir.join("events.jsonl"))
        .unwrap_or_default()
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .any(|e| e["event"] == "signalled" && e["node"] == node && e["signal"] == signal)
}

/// Every line `peer` printed, once it has exited (bounded by `deadline`).
fn all_lines(peer: &mut Peer, deadline: Instant) -> (Option<i32>, String) {
    let left = deadline.saturating_duration_since(Instant::now());
    let status = peer.wait_exit(left).expect("hnav run ends");
    let mut lines = Vec::new();
    while let Ok(l) = peer.next_line(Duration::from_secs(5)) {
        lines.push(l);
    }
    (status.code(), lines.join("\n"))
}

#[test]
fn the_tutorials_two_hosts_on_one_machine_run_with_the_same_run_id() {
    let (toml, lines) = tutorial_block();
    assert_eq!(lines.len(), 2, "two `hnav run` lines: {lines:?}");
    let tmp = tempfile::tempdir().unwrap();
    // The tutorial's ports may be taken on this machine; free ones instead.
    let toml: String = toml
        .lines()
        .map(|l| match l.find("tcp/127.0.0.1:") {
            Some(at) => format!("{}tcp/127.0.0.1:{}\"]", &l[..at], free_port()),
            None => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n");
    let hosts = tmp.path().join("hosts.toml");
    std::fs::write(&hosts, toml).unwrap();
    let names: Vec<String> = lines
        .iter()
        .map(|l| value_of(l, "--host").to_string())
        .collect();

    let run = TestRun::new("onebox");
    let _purge = DomainPurge(run.run.clone(), names.clone());
    let mut run = run;
    let registry = tmp.path().join("runs");
    let mut peers: Vec<Peer> = lines
        .iter()
        .map(|l| {
            let mut args: Vec<String> = vec![
                "-c".into(),
                "cd \"$1\" && shift && HNAV_RUNS_DIR=\"$1\" && shift && export HNAV_RUNS_DIR && exec \"$@\" 2>&1".into(),
                "sh".into(),
                tmp.path().display().to_string(),
                registry.display().to_string(),
            ];
            args.extend(runnable(l, &hosts, run.run.as_str()));
            run.spawn_exact("/bin/sh", &args).expect("hnav run starts")
        })
        .collect();
    let deadline = Instant::now() + RUN_TIMEOUT;
    tools_find_each_host(&registry, run.run.as_str(), &names);
    // The robots' host first: the tutorial runs it in the foreground.
    let (robots_code, robots) = all_lines(&mut peers[1], deadline);
    assert_eq!(robots_code, Some(0), "host {}:\n{robots}", names[1]);
    let (base_code, base) = all_lines(&mut peers[0], deadline);
    assert_eq!(base_code, Some(0), "host {}:\n{base}", names[0]);

    assert!(base.contains("6 of 6 at goal, 0 collisions"), "{base}");
    assert!(robots.contains("6 of 6 at goal, 0 collisions"), "{robots}");
    // Counts the robots' host does not have are not printed as zeros.
    assert!(!robots.contains("0.00"), "{robots}");
    assert!(
        robots.contains(&format!(
            "(steps, length, conflicts, waited, replans: in the consensus log on host {};",
            names[0]
        )) && robots.contains(&format!(
            "log       on host {} (the coordinator's)",
            names[0]
        )),
        "{robots}"
    );
    // Each host's default output directory is its own, and its journal has its signal.
    let dir =
        |name: &String| -> PathBuf { tmp.path().join(format!("target/hnav-out/demo-{name}")) };
    for name in &names {
        assert!(
            dir(name).join("summary.json").is_file(),
            "{}",
            dir(name).display()
        );
    }
    assert!(journalled(&dir(&names[1]), "agent-3", "SIGCONT"));
    assert!(journalled(&dir(&names[0]), "sim", "SIGCONT"));
    assert!(tmp.path().join("target/hnav-out/demo-base/log").is_dir());
    println!("host {}:\n{robots}\nhost {}:\n{base}", names[1], names[0]);
}
