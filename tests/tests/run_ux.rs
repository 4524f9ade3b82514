//! What `hnav run` tells its user: a start-up timeout names what each late process was doing,
//! a run off a terminal prints progress lines, and the process logs are plain text.

use std::path::Path;
use std::time::Duration;

use hnav_tests::swarm::workspace_bin;
use hnav_tests::{Peer, TestRun};

/// Bound on a whole small run, start-up to summary.
const RUN_TIMEOUT: Duration = Duration::from_secs(120);

/// Starts `hnav run SCENARIO --run <id> --out DIR` with stderr merged into the stdout the
/// test reads, and the run registry in `dir/runs`.
fn hnav_run(run: &mut TestRun, scenario: &Path, dir: &Path) -> Peer {
    let args: Vec<String> = vec![
        "-c".into(),
        "HNAV_RUNS_DIR=\"$1\" exec \"$2\" run \"$3\" --run \"$4\" --out \"$5\" 2>&1".into(),
        "sh".into(),
        dir.join("runs").display().to_string(),
        workspace_bin("hnav").display().to_string(),
        scenario.display().to_string(),
        run.run.as_str().to_string(),
        dir.join("out").display().to_string(),
    ];
    run.spawn_exact("/bin/sh", &args).expect("hnav run starts")
}

/// Every line the run printed, once it has exited (bounded).
fn all_lines(peer: &mut Peer) -> (Option<i32>, Vec<String>) {
    let status = peer.wait_exit(RUN_TIMEOUT).expect("hnav run ends");
    let mut lines = Vec::new();
    while let Ok(l) = peer.next_line(Duration::from_secs(5)) {
        lines.push(l);
    }
    (status.code(), lines)
}

/// A `side` x `side` empty MovingAI map in `dir`, and a scenario with one robot crossing it
/// corner to corner, with `extra` appended.
fn open_map_scenario(dir: &Path, side: u32, extra: &str) -> std::path::PathBuf {
    let row = ".".repeat(side as usize);
    let mut map = format!("type octile\nheight {side}\nwidth {side}\nmap\n");
    for _ in 0..side {
        map.push_str(&row);
        map.push('\n');
    }
    std::fs::write(dir.join("open.map"), map).unwrap();
    let last = side - 1;
    let scenario = dir.join("scenario.toml");
    std::fs::write(
        &scenario,
        format!(
            "name = \"open\"\n[map]\nfile = \"open.map\"\n{extra}\n[[agents]]\nstart = [0, 0]\n\
             goal = [{last}, {last}]\n"
        ),
    )
    .unwrap();
    scenario
}

/// An agent building its neural map on a 2500 x 2500 map (some 9e9 updates, minutes) cannot
/// be up within 3 s: the error says so, and says what the agent was doing.
#[test]
fn a_startup_timeout_names_what_the_late_agent_was_doing() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = open_map_scenario(tmp.path(), 2500, "[run]\nstartup_timeout_s = 3");
    let mut run = TestRun::new("uxslow");
    let mut peer = hnav_run(&mut run, &scenario, tmp.path());
    let (code, lines) = all_lines(&mut peer);
    let text = lines.join("\n");
    assert_eq!(code, Some(2), "{text}");
    assert!(
        text.contains("not up within 3.0 s (run.startup_timeout_s): "),
        "{text}"
    );
    // 2502 x 2502 padded cells, 21 bytes each.
    assert!(
        text.contains("agent-0 was building its neural map, 126 MiB"),
        "{text}"
    );
}

/// Off a terminal, `hnav run` prints a plain progress line (the first at once, then every
/// 5 s), and the processes' logs carry no ANSI colour codes.
#[test]
fn a_run_off_a_terminal_prints_progress_lines_and_plain_logs() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = open_map_scenario(tmp.path(), 6, "");
    let mut run = TestRun::new("uxlines");
    let mut peer = hnav_run(&mut run, &scenario, tmp.path());
    let (code, lines) = all_lines(&mut peer);
    let text = lines.join("\n");
    assert_eq!(code, Some(0), "{text}");
    let progress: Vec<&String> = lines
        .iter()
        .filter(|l| l.starts_with("progress: "))
        .collect();
    assert!(!progress.is_empty(), "{text}");
    assert!(progress[0].contains("/1 agents at goal"), "{}", progress[0]);
    let logs = tmp.path().join("out/logs");
    let mut seen = 0;
    for entry in std::fs::read_dir(&logs).unwrap() {
        let path = entry.unwrap().path();
        let bytes = std::fs::read(&path).unwrap();
        seen += bytes.len();
        assert!(
            !bytes.contains(&0x1b),
            "{} holds ANSI escapes:\n{}",
            path.display(),
            String::from_utf8_lossy(&bytes)
        );
    }
    assert!(
        seen > 0,
        "the processes logged nothing in {}",
        logs.display()
    );
}

/// A realtime run whose time limit is too large for a `Duration` (1e300 s passes validation:
/// it is a positive finite number) runs to its goal instead of panicking at the start.
#[test]
fn a_huge_realtime_time_limit_does_not_panic() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = open_map_scenario(
        tmp.path(),
        6,
        "[sim]\nclock = \"realtime\"\n[coordinator]\ntime_limit_s = 1e300",
    );
    let mut run = TestRun::new("uxhuge");
    let mut peer = hnav_run(&mut run, &scenario, tmp.path());
    let (code, lines) = all_lines(&mut peer);
    let text = lines.join("\n");
    assert!(!text.contains("panicked"), "{text}");
    assert_eq!(code, Some(0), "{text}");
}
