//! What the experiment tests share: `hnav-bench` run through its binary, killed if it hangs.

use std::process::{Command, Output, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// A quick run takes about a second; a run past this is a hang, and is killed.
const LIMIT: Duration = Duration::from_secs(60);

/// `hnav-bench ARGS`, its output once it exits; panics (failing the test) after [`LIMIT`].
#[allow(dead_code)] // Not every test binary that includes this module calls both.
pub fn bench(args: &[&str]) -> Output {
    bench_within(args, LIMIT)
}

/// `hnav-bench ARGS`, its output once it exits; panics (failing the test) after `limit`.
#[allow(dead_code)]
pub fn bench_within(args: &[&str], limit: Duration) -> Output {
    let child = Command::new(env!("CARGO_BIN_EXE_hnav-bench"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("hnav-bench starts");
    let pid = child.id();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(child.wait_with_output());
    });
    match rx.recv_timeout(limit) {
        Ok(out) => out.expect("hnav-bench output"),
        Err(_) => {
            let pid = nix::unistd::Pid::from_raw(pid as i32);
            let _ = nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGKILL);
            panic!("hnav-bench {args:?} did not finish within {limit:?}");
        }
    }
}

/// `hnav-bench ARGS`, a `latency` run writing into `dir`, which must succeed within `limit`;
/// the text of its `latency.csv`, checked to begin with the header.
#[allow(dead_code)]
pub fn latency_csv(args: &[&str], dir: &std::path::Path, limit: Duration) -> String {
    let run = bench_within(args, limit);
    assert!(
        run.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr)
    );
    let text = std::fs::read_to_string(dir.join("latency.csv")).unwrap();
    assert_eq!(text.lines().next(), Some(hnav_bench::latency::csv::HEADER));
    text
}

/// `hnav-bench round ARGS --rounds 60 --warmup 20 --json --out DIR`, which must succeed
/// within `limit`: its round rows (JSON), each checked to account for all 60 measured rounds
/// (a stalled round is left out of the distribution, every other is in it), and the text of
/// its `DIR/round.csv`.
#[allow(dead_code)]
pub fn round_rows(args: &[&str], limit: Duration) -> (Vec<serde_json::Value>, String) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().display().to_string();
    let mut all = vec!["round"];
    all.extend_from_slice(args);
    all.extend(["--rounds", "60", "--warmup", "20", "--json", "--out", &out]);
    let run = bench_within(&all, limit);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let rows: Vec<serde_json::Value> = (stdout.lines())
        .map(|l| serde_json::from_str(l).unwrap())
        .filter(|v: &serde_json::Value| v["bench"] == "round")
        .collect();
    for v in &rows {
        let (rounds, stalled) = (
            v["rounds"].as_u64().unwrap(),
            v["stalled"].as_u64().unwrap(),
        );
        assert_eq!(rounds + stalled, 60, "{v}");
    }
    let csv = std::fs::read_to_string(dir.path().join("round.csv")).unwrap();
    (rows, csv)
}
