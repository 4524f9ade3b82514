//! The `hnav` binary: exit codes, error format and the report file.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn hnav(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hnav"))
        .args(args)
        .current_dir(repo())
        .output()
        .expect("hnav runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn check_demo_writes_report() {
    let out = tempfile::tempdir().unwrap();
    let o = hnav(&[
        "check",
        "scenarios/demo.toml",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}{}",
        text(&o.stdout),
        text(&o.stderr)
    );
    let stdout = text(&o.stdout);
    assert!(stdout.contains("scenario  demo"), "{stdout}");
    assert!(stdout.contains("12 x 12"), "{stdout}");
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.path().join("scenario-report.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(json["name"], "demo");
    assert_eq!(json["agents"].as_array().map(Vec::len), Some(6));
    assert!(json["agents"][0]["shortest_path_len"].as_f64().is_some());
}

#[test]
fn check_random_scenario_matches_scen_lengths() {
    let out = tempfile::tempdir().unwrap();
    let o = hnav(&[
        "check",
        "scenarios/random-32-32-10.toml",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.path().join("scenario-report.json")).unwrap(),
    )
    .unwrap();
    // Optimal lengths of the first 8 entries of random-32-32-10-random-1.scen.
    let expected = [
        13.65685425,
        30.89949493,
        22.65685425,
        8.41421356,
        12.65685425,
        24.72792206,
        20.31370850,
        39.52691193,
    ];
    for (i, want) in expected.iter().enumerate() {
        let got = json["agents"][i]["shortest_path_len"].as_f64().unwrap();
        assert!((got - want).abs() < 1e-6, "agent {i}: {got} vs {want}");
    }
}

#[test]
fn check_with_more_agents() {
    let out = tempfile::tempdir().unwrap();
    let o = hnav(&[
        "check",
        "scenarios/demo.toml",
        "--agents",
        "10",
        "--seed",
        "3",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains("agents    10"));
}

#[test]
fn check_invalid_scenario_exits_2_with_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, "name = \"b\"\n[map]\nrows = [\"...\"]\n[[agents]]\nstart = [0, 0]\ngoal = [2, 0]\nspeed = -1\n")
        .unwrap();
    let o = hnav(&["check", path.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let stderr = text(&o.stderr);
    assert!(
        stderr.starts_with(&format!("error: {}:7: agent 0 speed", path.display())),
        "{stderr}"
    );
}

#[test]
fn map_check_exit_codes() {
    let o = hnav(&[
        "map",
        "check",
        "maps/random-32-32-10.map",
        "--scen",
        "maps/random-32-32-10-random-1.scen",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stdout));
    assert!(text(&o.stdout).contains("entries  461 (461 ok"));
    let o = hnav(&[
        "map",
        "check",
        "maps/random-32-32-20.map",
        "--scen",
        "maps/random-32-32-10-random-1.scen",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("x.map");
    std::fs::write(&bad, "type octile\nheight 2\nwidth 2\nmap\n..\n.\n").unwrap();
    let o = hnav(&["map", "check", bad.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("x.map:6: row has 1 character, expected 2"),
        "{}",
        text(&o.stderr)
    );
}
