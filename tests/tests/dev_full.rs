//! No HNAV binary panics because a diagnostic cannot be written: with stdout or stderr on
//! `/dev/full` (every write fails with "no space left on device", as on a full disk under a
//! redirected log) each one exits with its documented code, never 101.

use std::fs::File;
use std::process::{Command, ExitStatus, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use hnav_runtime::launch::EXIT_NO_SPACE;
use hnav_tests::swarm::{repo_root, workspace_bin};
use hnav_tests::TestRun;
use nix::sys::signal::{kill, Signal};
use nix::unistd::Pid;

/// How long one short command may take (a debug build on a loaded 2-core machine).
const TIMEOUT: Duration = Duration::from_secs(60);

fn full() -> Stdio {
    Stdio::from(
        File::options()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full"),
    )
}

/// Runs `bin args` with the chosen streams on `/dev/full` (the others discarded) and waits,
/// bounded, for its exit.
fn run(
    bin: &str,
    args: &[&str],
    full_out: bool,
    full_err: bool,
    env: &[(&str, &str)],
) -> ExitStatus {
    let mut cmd = Command::new(workspace_bin(bin));
    cmd.args(args)
        .stdin(Stdio::null())
        .stdout(if full_out { full() } else { Stdio::null() })
        .stderr(if full_err { full() } else { Stdio::null() });
    for (k, v) in env {
        cmd.env(k, v);
    }
    let mut child = cmd
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {bin}: {e}"));
    let pid = child.id();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(child.wait());
    });
    match rx.recv_timeout(TIMEOUT) {
        Ok(status) => status.expect("wait"),
        Err(_) => {
            let _ = kill(Pid::from_raw(pid as i32), Signal::SIGKILL);
            panic!("{bin} {args:?} did not exit within {TIMEOUT:?}");
        }
    }
}

fn demo() -> String {
    repo_root()
        .join("scenarios/demo.toml")
        .display()
        .to_string()
}

#[test]
fn hnav_reports_errors_and_results_into_a_full_disk_without_panicking() {
    let status = run(
        "hnav",
        &["check", "/nonexistent/scenario.toml"],
        false,
        true,
        &[],
    );
    assert_eq!(
        status.code(),
        Some(2),
        "hnav check, error on /dev/full: {status}"
    );

    let out = tempfile::tempdir().unwrap();
    let out_dir = out.path().display().to_string();
    let status = run(
        "hnav",
        &["check", &demo(), "--out", &out_dir],
        true,
        true,
        &[],
    );
    assert_eq!(
        status.code(),
        Some(0),
        "hnav check, summary on /dev/full: {status}"
    );
    assert!(out.path().join("scenario-report.json").is_file());

    let status = run(
        "hnav",
        &["run", "/nonexistent/scenario.toml"],
        true,
        true,
        &[],
    );
    assert_eq!(
        status.code(),
        Some(2),
        "hnav run, error on /dev/full: {status}"
    );
}

#[test]
fn a_process_that_cannot_print_its_error_exits_with_the_no_space_code() {
    let run_id = TestRun::new("devfull");
    let id = run_id.run.as_str().to_string();
    let status = run(
        "hnav-sim",
        &["--run", &id, "--scenario", "/nonexistent/scenario.toml"],
        false,
        true,
        &[],
    );
    assert_eq!(
        status.code(),
        Some(i32::from(EXIT_NO_SPACE)),
        "hnav-sim, error on /dev/full: {status}"
    );
}

#[test]
fn tracing_into_a_full_disk_does_not_panic() {
    // iceoryx2 and the sim trace plenty at `trace`; every line of it fails to be written.
    let run_id = TestRun::new("devfulltrace");
    let id = run_id.run.as_str().to_string();
    let status = run(
        "hnav-sim",
        &[
            "--run",
            &id,
            "--scenario",
            &demo(),
            "--standalone",
            "--mode",
            "realtime",
            "--periods",
            "3",
        ],
        true,
        true,
        &[("HNAV_LOG", "trace")],
    );
    assert_eq!(
        status.code(),
        Some(0),
        "hnav-sim tracing into /dev/full: {status}"
    );
}
