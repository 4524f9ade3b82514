//! `hnav log verify|show` take the run directory as well as its `log/` folder.

use std::process::Command;

use serde_json::json;

use super::fixtures::{every_kind, write_log, ONE_SEGMENT};

fn hnav(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_hnav"))
        .args(args)
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.code().unwrap_or(-1), text)
}

#[test]
fn verify_and_show_accept_the_run_directory() {
    let tmp = tempfile::tempdir().unwrap();
    let run_dir = tmp.path().join("run");
    let records = every_kind();
    write_log(&run_dir.join("log"), &records, ONE_SEGMENT);
    std::fs::create_dir(run_dir.join("logs")).unwrap();
    let run = run_dir.to_str().unwrap();
    let log = run_dir.join("log");
    let log = log.to_str().unwrap();

    let (code, out) = hnav(&["log", "verify", run]);
    assert_eq!(code, 0, "{out}");
    assert_eq!(out, hnav(&["log", "verify", log]).1);

    let (code, out) = hnav(&["log", "show", run]);
    assert_eq!(code, 0, "{out}");
    assert_eq!(out.lines().count(), records.len(), "{out}");
    assert_eq!(out, hnav(&["log", "show", log]).1);

    // A directory that is neither stays an error naming it.
    let (code, out) = hnav(&["log", "verify", tmp.path().join("none").to_str().unwrap()]);
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("none"), "{out}");
}

/// `hnav log show --json` spells enumerations by name and cells as `[x, y]`, as the text
/// output does; only an unknown code stays a number.
#[test]
fn show_json_names_enumerations_and_spells_cells_as_x_y() {
    let tmp = tempfile::tempdir().unwrap();
    let log = tmp.path().join("log");
    write_log(&log, &every_kind(), ONE_SEGMENT);
    let (code, out) = hnav(&["log", "show", "--json", log.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}");
    let lines: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();

    assert_eq!(lines[0]["agents"][0]["start"], json!([1, 1]));
    let d = &lines[1]["decisions"];
    assert_eq!(d[0]["verdict"], "accept");
    assert_eq!(d[0]["kind"], "none");
    assert_eq!(d[0]["cell"], json!([2, 2]));
    assert_eq!(d[0]["waypoint"], serde_json::Value::Null);
    assert_eq!(d[1]["verdict"], "block");
    assert_eq!(d[1]["kind"], "crossing");
    assert_eq!(d[1]["refused"], json!(["N", "NE"]));
    let life = &lines[3];
    assert_eq!(
        (&life["role"], &life["event"]),
        (&json!("agent"), &json!("restarted"))
    );
    assert_eq!(lines[4]["waypoints"][0], json!([2, 1]));
    assert_eq!(lines.last().unwrap()["reason"], "all-at-goal");
}
