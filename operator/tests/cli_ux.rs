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
            "Exit 0 when the scenario is valid and the report is written, 1 when it is valid but"
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
