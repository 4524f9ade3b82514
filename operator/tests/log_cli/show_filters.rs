//! `hnav log show --round A..B --agent N --kind K`: each filter alone and together, their
//! refusals, and speeds and priorities printed as people read them.

use std::process::Command;

use hnav_runtime::consensus_log::{AgentEntry, Record, RunHeader, FORMAT_VERSION};

use super::fixtures::{every_kind, write_log, HEIGHT, ONE_SEGMENT, WIDTH};

fn show(dir: &std::path::Path, args: &[&str]) -> (i32, Vec<String>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_hnav"))
        .args(["log", "show", dir.to_str().unwrap()])
        .args(args)
        .output()
        .unwrap();
    let lines = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(str::to_string)
        .collect();
    (
        out.status.code().unwrap_or(-1),
        lines,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `every_kind`'s log with a header whose second agent has speed 0.3 and priority 10/3.
fn log(dir: &std::path::Path) {
    let mut records = every_kind();
    records[0] = Record::Header(RunHeader {
        version: FORMAT_VERSION,
        scenario_hash: 1,
        seed: 42,
        clock: "lockstep".into(),
        width: WIDTH,
        height: HEIGHT,
        agents: vec![
            AgentEntry {
                start: 11,
                goal: 79,
                speed: 1.0,
                priority: 1.0,
            },
            AgentEntry {
                start: 12,
                goal: 78,
                speed: 0.3,
                priority: 10.0 / 3.0,
            },
        ],
    });
    write_log(dir, &records, ONE_SEGMENT);
}

#[test]
fn priorities_and_speeds_are_printed_to_three_decimals() {
    let tmp = tempfile::tempdir().unwrap();
    log(tmp.path());
    let (code, lines, err) = show(tmp.path(), &[]);
    assert_eq!(code, 0, "{err}");
    assert!(
        lines[0].ends_with(
            "a0 [1, 1]->[9, 7] speed 1 priority 1, a1 [2, 1]->[8, 7] speed 0.3 priority 3.333"
        ),
        "{}",
        lines[0]
    );
    // JSON keeps every digit, for tools.
    let (_, json, _) = show(tmp.path(), &["--json"]);
    assert!(json[0].contains("3.3333333333333335"), "{}", json[0]);
}

#[test]
fn round_agent_and_kind_each_narrow_what_is_printed() {
    let tmp = tempfile::tempdir().unwrap();
    log(tmp.path());
    let kinds = |lines: &[String]| -> Vec<String> {
        lines
            .iter()
            .map(|l| l.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
            .collect()
    };
    // every_kind: header, rounds 1 and 2, a lifecycle at 2, a replan at 3, rounds 3 and 4, end at 4.
    let (code, lines, err) = show(tmp.path(), &["--round", "2..3"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        kinds(&lines),
        [
            "round 2 candidates",
            "lifecycle round 2",
            "replan round 3",
            "round 3 candidates"
        ]
    );
    let (_, lines, _) = show(tmp.path(), &["--round", "4"]);
    assert_eq!(kinds(&lines), ["round 4 candidates", "end round 4"]);
    let (_, lines, _) = show(tmp.path(), &["--round", "4.."]);
    assert_eq!(lines.len(), 2, "{lines:?}");

    // Agent 1: its decisions only (agent 0's are dropped from each round), its restart and
    // its replan.
    let (_, lines, _) = show(tmp.path(), &["--agent", "1"]);
    assert_eq!(lines.len(), 6, "{lines:?}");
    assert!(
        lines
            .iter()
            .any(|l| l.starts_with("lifecycle round 2  agent 1")),
        "{lines:?}"
    );
    assert!(lines.iter().all(|l| !l.contains("a0")), "{lines:?}");
    assert!(
        lines[0].ends_with(" block a1 crossing (N,NE)"),
        "{}",
        lines[0]
    );
    assert!(
        lines.iter().any(|l| l.starts_with("replan round 3  a1")),
        "{lines:?}"
    );

    let (_, lines, _) = show(tmp.path(), &["--kind", "lifecycle,end"]);
    assert_eq!(kinds(&lines), ["lifecycle round 2", "end round 4"]);
    let (_, lines, _) = show(tmp.path(), &["--kind", "replan", "--kind", "header"]);
    assert_eq!(lines.len(), 2, "{lines:?}");

    // Together, a record must pass each; --json is filtered the same way.
    let (_, lines, _) = show(
        tmp.path(),
        &[
            "--round", "..3", "--agent", "0", "--kind", "round", "--json",
        ],
    );
    assert_eq!(lines.len(), 3, "{lines:?}");
    let v: serde_json::Value = serde_json::from_str(&lines[2]).unwrap();
    assert_eq!(
        (v["round"].as_u64(), v["decisions"].as_array().map(Vec::len)),
        (Some(3), Some(1))
    );
}

#[test]
fn a_bad_filter_is_refused_with_what_it_must_be() {
    let tmp = tempfile::tempdir().unwrap();
    log(tmp.path());
    for (args, says) in [
        (&["--round", "5..2"][..], "is empty"),
        (&["--round", "x"], "not a round number"),
        (&["--kind", "rounds"], "kinds: header, round"),
        (
            &["--agent", "-1"],
            "an agent's number, a whole number from 0",
        ),
    ] {
        let (code, lines, err) = show(tmp.path(), args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(lines.is_empty() && err.contains(says), "{args:?}: {err}");
    }
}

/// On a terminal the lines go through the pager (`HNAV_PAGER`, here `tee FILE`, which keeps a
/// copy); to a pipe, or with `--no-pager`, never. The terminal is a pseudo-terminal from
/// `script(1)` (util-linux), run by the test itself.
#[test]
fn a_terminal_gets_the_lines_through_the_pager_and_a_pipe_does_not() {
    let has_script = Command::new("script").arg("--version").output().is_ok();
    if !has_script {
        eprintln!("skipped: script(1) is not installed (.ci/run installs it)");
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    log(tmp.path());
    let (_, piped, _) = show(tmp.path(), &[]);
    assert!(piped.len() > 3, "{piped:?}");
    let hnav = env!("CARGO_BIN_EXE_hnav");
    let paged = |extra: &str, copy: &std::path::Path| {
        let line = format!("{hnav} log show {} {extra}", tmp.path().display());
        let out = Command::new("script")
            .args(["-qec", &line, "/dev/null"])
            .env("HNAV_PAGER", format!("tee {}", copy.display()))
            .output()
            .expect("script(1) runs");
        assert!(out.status.success(), "{out:?}");
    };
    let copy = tmp.path().join("paged.txt");
    paged("", &copy);
    let through = std::fs::read_to_string(&copy).expect("the pager read the lines");
    assert_eq!(through.lines().collect::<Vec<_>>(), piped);
    let unpaged = tmp.path().join("unpaged.txt");
    paged("--no-pager", &unpaged);
    assert!(!unpaged.exists(), "--no-pager started the pager");
}
