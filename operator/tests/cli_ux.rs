//! `hnav check` as documented: its exit codes, one spelling of cells (`[x, y]`, 0-based
//! column and row) in its messages and summary, and readable numbers in its errors.

use std::path::Path;
use std::process::{Command, Output};

fn hnav(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hnav"))
        .args(args)
        .output()
        .expect("hnav runs")
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

const SCENARIO: &str = "name = \"u\"\n[map]\nrows = [\"....\", \".@..\", \"....\"]\n[[agents]]\nstart = [0, 0]\ngoal = [3, 2]\n";

fn write(dir: &Path, name: &str, body: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, body).unwrap();
    p.display().to_string()
}

#[test]
fn check_exit_codes_are_the_documented_ones() {
    let tmp = tempfile::tempdir().unwrap();
    let good = write(tmp.path(), "good.toml", SCENARIO);
    let out = tmp.path().join("out");
    let o = hnav(&["check", &good, "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    // Valid, but the report cannot be written: the output directory is a file.
    let blocker = write(tmp.path(), "file", "");
    let o = hnav(&["check", &good, "--out", &format!("{blocker}/sub")]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("cannot write report"), "{}", text(&o));
    let bad = write(
        tmp.path(),
        "bad.toml",
        &SCENARIO.replace("[3, 2]", "[1, 1]"),
    );
    let o = hnav(&["check", &bad]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let o = hnav(&[
        "check",
        &tmp.path().join("missing.toml").display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    // What docs/reference/cli.md says, `hnav check --help` says too.
    let help = text(&hnav(&["check", "--help"]));
    assert!(
        help.contains(
            "Exit 0 when the scenario is valid (and the report asked for is written), 1 when it is"
        ),
        "{help}"
    );
}

#[test]
fn check_spells_cells_as_x_y_in_errors_and_summary() {
    let tmp = tempfile::tempdir().unwrap();
    let bad = write(
        tmp.path(),
        "bad.toml",
        &SCENARIO.replace("[3, 2]", "[1, 1]"),
    );
    let o = hnav(&["check", &bad]);
    assert!(
        text(&o).contains(":6: agent 0 goal [1, 1] is on an obstacle"),
        "{}",
        text(&o)
    );
    let good = write(tmp.path(), "good.toml", SCENARIO);
    let o = hnav(&["check", &good, "--out", tmp.path().to_str().unwrap()]);
    let out = text(&o);
    assert!(out.contains("[0, 0]") && out.contains("[3, 2]"), "{out}");
    assert!(!out.contains("(0, 0)"), "{out}");
}

#[test]
fn check_prints_huge_numbers_readably() {
    let tmp = tempfile::tempdir().unwrap();
    let bad = write(
        tmp.path(),
        "huge.toml",
        &format!("{SCENARIO}speed = -1e300\n"),
    );
    let o = hnav(&["check", &bad]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let err = text(&o);
    assert!(err.contains("got -1e300"), "{err}");
    assert!(err.len() < 200, "{err}");
}

#[test]
fn check_writes_nothing_unless_a_report_is_asked_for() {
    let tmp = tempfile::tempdir().unwrap();
    let good = write(tmp.path(), "good.toml", SCENARIO);
    let run_in = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_hnav"))
            .args(args)
            .current_dir(tmp.path())
            .output()
            .expect("hnav runs")
    };
    let o = run_in(&["check", &good]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let files: Vec<String> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(files, ["good.toml"], "{}", text(&o));
    assert!(!text(&o).contains("report "), "{}", text(&o));
    let o = run_in(&["check", &good, "--report", "r.json"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(text(&o).contains("report    r.json"), "{}", text(&o));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("r.json")).unwrap()).unwrap();
    assert_eq!(json["name"], "u");
}

#[test]
fn a_value_of_the_wrong_type_is_named_in_the_formats_words() {
    let tmp = tempfile::tempdir().unwrap();
    let bad = write(
        tmp.path(),
        "fast.toml",
        &format!("{SCENARIO}speed = \"fast\"\n"),
    );
    let o = hnav(&["check", &bad]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let err = text(&o);
    assert!(
        err.contains("fast.toml:7: speed: expected a number, got the string \"fast\""),
        "{err}"
    );
    assert!(!err.contains("f64"), "{err}");
}

#[test]
fn an_agent_count_below_one_is_refused_in_the_command_lines_words() {
    let tmp = tempfile::tempdir().unwrap();
    let good = write(tmp.path(), "good.toml", SCENARIO);
    for verb in ["check", "run"] {
        for n in ["0", "-1"] {
            let o = hnav(&[verb, &good, "--agents", n]);
            let err = text(&o);
            assert_eq!(o.status.code(), Some(2), "{verb} --agents {n}: {err}");
            assert!(
                err.contains(&format!("invalid value '{n}' for '--agents <N>'"))
                    && err.contains("at least one agent"),
                "{verb} --agents {n}: {err}"
            );
            assert!(
                !err.contains("[[agents]]") && !err.contains("'-- "),
                "{verb} --agents {n}: {err}"
            );
        }
    }
    let o = hnav(&["check", &good, "--seed", "-1"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("S is a whole number from 0"),
        "{}",
        text(&o)
    );
}

#[test]
fn run_force_help_names_every_output_it_replaces() {
    let help = text(&hnav(&["run", "--help"]));
    let force = help
        .split("--force")
        .nth(1)
        .expect("--force in the help")
        .split("\n      --")
        .next()
        .unwrap()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    for output in hnav_operator::supervisor::run_dir::RUN_OUTPUTS {
        assert!(force.contains(output), "{output} not in: {force}");
    }
    assert!(force.contains("other files there are kept"), "{force}");
}
