//! `hnav-ros2`'s command line: bad input is a clear message and exit 1, never a panic. (Its
//! integration test with a ROS 2 client is `tests/tests/ros2.rs`; this file also makes
//! `cargo test` build the binary that one and `hnav run --ros2` start.)

use std::process::Command;

fn hnav_ros2(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_hnav-ros2"))
        .args(args)
        .output()
        .expect("hnav-ros2 runs");
    let text = String::from_utf8_lossy(&out.stderr).into_owned();
    (out.status.code().unwrap_or(-1), text)
}

#[test]
fn a_missing_scenario_and_a_bad_rate_are_clear_errors() {
    let (code, err) = hnav_ros2(&["--run", "r", "--scenario", "/nonexistent/s.toml"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.starts_with("hnav-ros2: "), "{err}");
    assert!(err.contains("/nonexistent/s.toml"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let demo = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios/demo.toml");
    let (code, err) = hnav_ros2(&["--run", "r", "--scenario", demo, "--rate-hz", "0"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--rate-hz 0: must be in (0, 1000]"), "{err}");
}
