//! The Python client (`clients/python/`) against the Rust side: its `ctypes` mirrors match the
//! layout table of `hnav layout --json` field by field, and its example joins a live run by
//! its id and prints commits, ground truth and an agent's neural map; its second example reads
//! a changing world (a robot's view, the agents' sightings, the coordinator's map); given a run
//! id that no run has, it leaves nothing of it in `/dev/shm` or iceoryx2's root (issue 34).
//!
//! The Python is the virtual environment's with the pinned `iceoryx2` package: `$HNAV_PYTHON`,
//! else `target/py-venv/bin/python` (made by the command in docs/how-to/python-client.md). Without either the tests
//! skip, saying so, unless `HNAV_REQUIRE_PYTHON` is set (CI sets it): then they fail.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use hnav_runtime::transport::{run_iceoryx2_files, run_shm_files};
use hnav_tests::python::python;
use hnav_tests::swarm::{repo_root, workspace_bin, SwarmRun};
use hnav_tests::TestRun;
use nix::sys::signal::Signal;

/// Bound on stopping the demo run.
const RUN_TIMEOUT: Duration = Duration::from_secs(120);
/// Bound on the Python example, joining included.
const WATCH_TIMEOUT: Duration = Duration::from_secs(90);
/// Commits the example is asked to print.
const COMMITS: usize = 300;

/// Runs the Python example `args` against `swarm`'s run until it exits, then stops the run
/// (the rest of it is not the test's business, and takes minutes on a loaded machine); the
/// lines it printed, once it exited 0.
fn watch(
    run: &mut TestRun,
    python: &Path,
    args: &[String],
    start: impl FnOnce(&mut TestRun) -> SwarmRun,
) -> Vec<String> {
    // The example first, the run after it: the example waits for the run to be live and
    // joins it while its processes start up, so it is subscribed before the first round.
    // Started the other way round, a Python slow to import could join after round 1 (the
    // commit topic keeps only the latest commit for a late joiner), and the first test's
    // check of round 1 failed now and then under load.
    let mut watcher = run
        .spawn_exact(&python.display().to_string(), args)
        .expect("the example starts");
    let mut swarm = start(run);
    let deadline = Instant::now() + WATCH_TIMEOUT;
    let mut lines = Vec::new();
    while let Ok(line) = watcher.next_line(deadline.saturating_duration_since(Instant::now())) {
        lines.push(line);
    }
    let status = watcher
        .wait_exit(deadline.saturating_duration_since(Instant::now()))
        .expect("the example exits");
    swarm.peer.signal(Signal::SIGTERM).unwrap();
    swarm.finish(RUN_TIMEOUT).expect("hnav run stops");
    let text = lines.join("\n");
    assert!(status.success(), "the example failed ({status}):\n{text}");
    lines
}

#[test]
fn ctypes_mirrors_match_the_rust_layout_table() {
    let Some(python) = python() else { return };
    let out = Command::new(workspace_bin("hnav"))
        .args(["layout", "--json"])
        .output()
        .expect("hnav layout runs");
    assert!(out.status.success(), "hnav layout --json failed");
    let dir = tempfile::tempdir().unwrap();
    let table = dir.path().join("layout.json");
    std::fs::write(&table, &out.stdout).unwrap();
    let client = repo_root().join("clients/python");
    let test = Command::new(&python)
        .args(["-m", "unittest", "discover", "-v", "-s", "tests"])
        .current_dir(&client)
        .env("HNAV_LAYOUT_JSON", &table)
        .output()
        .expect("python runs");
    let report = String::from_utf8_lossy(&test.stderr);
    eprintln!("{report}");
    assert!(test.status.success(), "the layout test failed:\n{report}");
    assert!(
        report.contains("Ran 5 tests"),
        "not every layout test ran:\n{report}"
    );
}

#[test]
fn the_python_example_watches_a_live_run() {
    let Some(python) = python() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let mut run = TestRun::new("pywatch");
    let start = |run: &mut TestRun| {
        SwarmRun::start(
            run,
            &repo_root().join("scenarios/demo.toml"),
            &tmp.path().join("out"),
            &tmp.path().join("runs"),
            &["--mode", "lockstep"],
        )
        .expect("hnav run starts")
    };
    let example = repo_root().join("clients/python/examples/watch_run.py");
    let args = vec![
        example.display().to_string(),
        run.run.as_str().to_string(),
        "--agent".into(),
        "2".into(),
        "--commits".into(),
        COMMITS.to_string(),
    ];
    let lines = watch(&mut run, &python, &args, start);
    let text = lines.join("\n");

    let commits: Vec<&String> = lines.iter().filter(|l| l.starts_with("commit ")).collect();
    assert!(
        commits.len() >= 100,
        "{} commits printed:\n{text}",
        commits.len()
    );
    assert_eq!(commits.len(), COMMITS);
    // Each decision names its agent, and every robot moves within the commits watched. Not
    // "round 1 moves them all": a watcher that joins under load after round 1 (the topic keeps
    // only the latest commit for a late joiner) sees the later moves one by one.
    assert!(
        (0..6).all(|a| commits
            .iter()
            .any(|l| l.contains(&format!("a{a} accept [")))),
        "not every agent's move was printed:\n{text}"
    );
    assert!(lines
        .iter()
        .any(|l| l.starts_with("truth period ") && l.contains("r5 (")));
    // The demo's map is 12 x 12: the header says so and 12 rows of 12 cells follow.
    let at = lines
        .iter()
        .position(|l| l.starts_with("map agent 2 round "))
        .unwrap_or_else(|| panic!("no neural map printed:\n{text}"));
    assert!(lines[at].contains(": 12 x 12,"), "{}", lines[at]);
    let rows: Vec<&String> = lines[at + 1..]
        .iter()
        .take_while(|l| l.starts_with("  |"))
        .collect();
    assert_eq!(rows.len(), 12, "{text}");
    assert!(rows.iter().all(|r| r.chars().count() == 12 + 4), "{text}");
    // The map's pillars are blocked cells: '@' where demo.toml has them ([2,2]).
    assert_eq!(rows[2].chars().nth(3 + 2), Some('@'), "{text}");
}

/// `scenarios/door.toml` slowed for a client that joins late: the door closes at round 500
/// (about 5 s into a realtime run), seen from 6 cells away; agent 0 is killed at round 700
/// and, restarted, is sent the coordinator's map.
fn late_door(dir: &std::path::Path) -> PathBuf {
    let text = std::fs::read_to_string(repo_root().join("scenarios/door.toml")).unwrap();
    let text = text
        .replace("at_round = 150", "at_round = 500")
        .replace("range = 3", "range = 6");
    assert!(text.contains("at_round = 500") && text.contains("range = 6"));
    let path = dir.join("late-door.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn the_python_world_example_reads_views_sightings_and_the_coordinators_map() {
    let Some(python) = python() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let mut run = TestRun::new("pyworld");
    let scenario = late_door(tmp.path());
    let args = ["--mode", "realtime", "--kill", "agent:0@round:700"];
    let out = tmp.path().join("out");
    let start = |run: &mut TestRun| {
        SwarmRun::start(run, &scenario, &out, &tmp.path().join("runs"), &args)
            .expect("hnav run starts")
    };
    let example = repo_root().join("clients/python/examples/watch_world.py");
    let args = [example.display().to_string(), run.run.as_str().to_string()];
    let args = [
        &args[..],
        &[
            "--width".into(),
            "10".into(),
            "--timeout".into(),
            "60".into(),
        ],
    ];
    let lines = watch(&mut run, &python, &args.concat(), start);
    let text = lines.join("\n");
    let has = |start: &str, part: &str| {
        lines
            .iter()
            .any(|l| l.starts_with(start) && l.contains(part))
    };
    assert!(has("view agent 0 period ", " cells seen, "), "{text}");
    assert!(
        has("sighting round ", "a0: closed [5,0]; opened -"),
        "{text}"
    );
    assert!(
        has("world round ", "for [0]: closed [5,0]; opened -"),
        "{text}"
    );
}

#[test]
fn a_mistyped_run_id_leaves_nothing_behind() {
    let Some(python) = python() else { return };
    // No run has this id; whatever the example left of it is purged when this drops.
    let typo = TestRun::new("pytypo");
    let example = repo_root().join("clients/python/examples/watch_run.py");
    // Bounded by the example's own --timeout.
    let out = Command::new(&python)
        .arg(&example)
        .arg(typo.run.as_str())
        .args(["--timeout", "1"])
        .output()
        .expect("python runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        run_shm_files(&typo.run),
        Vec::<PathBuf>::new(),
        "left in /dev/shm by the example with a mistyped run id ({stderr})"
    );
    assert_eq!(
        run_iceoryx2_files(&typo.run),
        Vec::<PathBuf>::new(),
        "left under iceoryx2's root"
    );
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!("error: no live run '{}'", typo.run))
            && stderr.contains("within 1.0 s (`hnav ps` lists the live runs)"),
        "{stderr}"
    );
}
