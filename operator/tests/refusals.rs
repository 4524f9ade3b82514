//! `hnav check` and `hnav run` refuse, before anything is spawned, a scenario the runtime
//! cannot carry out: more agents than the message format holds, or a goal that cannot be
//! reached from its start (unless the scenario allows it), or a world change (`[[events]]`)
//! that cannot happen.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use hnav_runtime::msg::MAX_AGENTS;
use hnav_runtime::transport::RunId;

fn hnav(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hnav"))
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .output()
        .expect("hnav runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `hnav run` into `out` with a fresh run id; a refusal must happen before the run
/// directory or any shared memory exists, so the test checks the directory and (by the
/// exit code and message) that no process was started.
fn run(scenario: &Path, out: &Path, extra: &[&str]) -> Output {
    let id = RunId::unique("refusal");
    let mut args = vec![
        "run",
        scenario.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--run",
        id.as_str(),
    ];
    args.extend_from_slice(extra);
    let o = hnav(&args);
    let _ = hnav_runtime::transport::purge_run(&id);
    o
}

/// An open square map with room for `n` agents, each on its own line pair: agent `i`
/// starts on cell `i` (row-major) and goes to the cell as far from the last. Returns the file
/// and the line of agent `MAX_AGENTS`'s `[[agents]]` header.
fn many_agents(dir: &Path, n: usize) -> (PathBuf, usize) {
    let side = (1..).find(|s| s * s >= 2 * n).unwrap();
    let mut text = String::from("name = \"many\"\n[map]\nrows = [\n");
    for _ in 0..side {
        text += &format!("  \"{}\",\n", ".".repeat(side));
    }
    text += "]\n";
    let mut line_of_extra = 0;
    for i in 0..n {
        if i == MAX_AGENTS {
            line_of_extra = text.lines().count() + 1;
        }
        let goal = side * side - 1 - i;
        text += &format!(
            "[[agents]]\nstart = [{}, {}]\ngoal = [{}, {}]\n",
            i % side,
            i / side,
            goal % side,
            goal / side
        );
    }
    let path = dir.join("many.toml");
    std::fs::write(&path, text).unwrap();
    (path, line_of_extra)
}

#[test]
fn more_agents_than_a_run_holds_are_refused_by_check_and_run() {
    let dir = tempfile::tempdir().unwrap();
    let (path, line) = many_agents(dir.path(), MAX_AGENTS + 1);
    let limit = format!(
        "{} agents, but a run holds at most {MAX_AGENTS}",
        MAX_AGENTS + 1
    );

    let o = hnav(&["check", path.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let want = format!("error: {}:{line}: {limit}", path.display());
    assert!(
        stderr(&o).starts_with(&want),
        "{}\nwanted {want}",
        stderr(&o)
    );

    let out = dir.path().join("out");
    let o = run(&path, &out, &["--bin-dir", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).starts_with(&want), "{}", stderr(&o));
    assert!(!out.exists(), "refused before the run directory was made");

    // Exactly the limit is fine.
    let (path, _) = many_agents(dir.path(), MAX_AGENTS);
    let o = hnav(&[
        "check",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));

    // Generated agents: the same limit, named for the requested count.
    let n = (MAX_AGENTS + 44).to_string();
    let want =
        format!("error: scenarios/demo.toml: {n} agents, but a run holds at most {MAX_AGENTS}");
    let o = hnav(&["check", "scenarios/demo.toml", "--agents", &n]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).starts_with(&want), "{}", stderr(&o));
    let out = dir.path().join("out-generated");
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/demo.toml");
    let o = run(
        &demo,
        &out,
        &["--agents", &n, "--bin-dir", dir.path().to_str().unwrap()],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains(&format!("{n} agents, but a run holds at most")),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists(), "refused before the run directory was made");
}

/// Agent 0 is walled in on the left; agent 1 can reach its goal.
const WALLED: &str = r#"name = "walled"
[map]
rows = [".@...",
        "@@...",
        "....."]
[[agents]]
start = [0, 0]
goal = [4, 2]
[[agents]]
start = [2, 0]
goal = [4, 0]
"#;

#[test]
fn an_unreachable_goal_is_refused_by_check_and_run_unless_allowed() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("walled.toml");
    std::fs::write(&path, WALLED).unwrap();
    let want = format!(
        "error: {}:8: agent 0: goal [4, 2] is unreachable from start [0, 0] (write \
         allow_unreachable = true at the top of the scenario to run it anyway)",
        path.display()
    );

    let out = dir.path().join("out");
    let o = hnav(&[
        "check",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).starts_with(&want),
        "{}\nwanted {want}",
        stderr(&o)
    );
    assert!(!out.exists(), "no report for a refused scenario");

    let o = run(&path, &out, &["--bin-dir", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).starts_with(&want), "{}", stderr(&o));
    assert!(!out.exists(), "refused before the run directory was made");

    // Allowed: check passes with a warning.
    let allowed = dir.path().join("allowed.toml");
    std::fs::write(
        &allowed,
        WALLED.replace(
            "name = \"walled\"\n",
            "name = \"walled\"\nallow_unreachable = true\n",
        ),
    )
    .unwrap();
    let o = hnav(&[
        "check",
        allowed.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("warning: agent 0: goal [4, 2] is unreachable from start [0, 0]"),
        "{stdout}"
    );
}

/// A 6 x 4 map with a wall at (1..2, 1) and two robots; `[[events]]` bodies follow from line 15.
const WITH_EVENTS: &str = r#"name = "events"
[map]
rows = [
  "......",
  ".@@...",
  "......",
  "......",
]
[[agents]]
start = [0, 0]
goal = [5, 3]
[[agents]]
start = [5, 0]
goal = [0, 3]
"#;

#[test]
fn every_event_mistake_is_refused_by_check_and_run_at_its_line_before_anything_is_spawned() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let cases: &[(&str, &str)] = &[
        (
            "at_s = 1\nclose = [[5, 0]]\n",
            "17: events.close (5, 0) is agent 1's start: the robot would begin inside it",
        ),
        (
            "at_s = 1\nmover = \"p\"\npath = [[0, 1], [4, 1]]\nspeed = 1\n",
            "18: events.path passes (1, 1), a wall or a closed cell",
        ),
        (
            "at_s = 2\nclose = [[4, 2]]\n[[events]]\nat_s = 1\nclose = [[4, 3]]\n",
            "18: events happens at 1 s, before the event at line 15 (2 s); list the events in time order",
        ),
        ("at_s = 1\nopen = [[4, 2]]\n", "17: events.open (4, 2) is free already: nothing to open"),
        ("at_round = 3\n", "15: events event 0 must be exactly one of close, close_rect, open, open_rect and mover; it gives none"),
    ];
    for (i, (body, problem)) in cases.iter().enumerate() {
        let path = dir.path().join(format!("events-{i}.toml"));
        std::fs::write(&path, format!("{WITH_EVENTS}[[events]]\n{body}")).unwrap();
        let want = format!("error: {}:{problem}", path.display());
        let o = hnav(&["check", path.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(
            stderr(&o).starts_with(&want),
            "{}\nwanted {want}",
            stderr(&o)
        );
        // No binaries where `--bin-dir` points: a run that got as far as spawning would fail
        // otherwise, and the run directory would exist.
        let o = run(&path, &out, &["--bin-dir", dir.path().to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).starts_with(&want), "{}", stderr(&o));
        assert!(!out.exists(), "refused before the run directory was made");
    }
}
