//! `hnav log replay` and `hnav log export` on real runs of the demo scenario.
//!
//! A lockstep run replays identically; the same log with one decision altered (re-encoded
//! through the log's own writer, so `hnav log verify` still passes and only the content
//! differs) is reported at that round and agent; a run whose scenario changed since, and a
//! realtime run, are refused. A lockstep run with coordinator replicas, and one with a fault
//! plan, replay identically too (issue 34: the invocation did not record `--replicas`, so
//! the replay ran one coordinator and differed at the header). Every `hnav run` and every
//! replay has a test's own run id, so its shared memory is removed whatever happens.

use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::Duration;

use hnav_runtime::consensus_log::{read_log, LogWriter, Record};
use hnav_runtime::msg::{ConflictKind, Verdict, NO_CELL};
use hnav_runtime::scenario::FsyncPolicy;
use hnav_tests::swarm::{repo_root, verify_log, workspace_bin, SwarmRun};
use hnav_tests::TestRun;

const RUN_TIMEOUT: Duration = Duration::from_secs(300);

/// The demo scenario copied into `dir` (so that a test may change it), with `edit` applied.
fn demo(dir: &Path, edit: impl Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(repo_root().join("scenarios/demo.toml")).unwrap();
    let path = dir.join("demo.toml");
    std::fs::write(&path, edit(text)).unwrap();
    path
}

/// `hnav run` of `scenario` into `dir` with `extra` arguments; returns its exit code.
fn run(tag: &str, scenario: &Path, dir: &Path, registry: &Path, extra: &[&str]) -> Option<i32> {
    let mut run = TestRun::new(tag);
    let mut swarm = SwarmRun::start(&mut run, scenario, dir, registry, extra).unwrap();
    let status = swarm.finish(RUN_TIMEOUT).unwrap();
    status.code()
}

/// `hnav log replay DIR` under a test's own run id. A replay is bounded by the scenario's
/// simulated time limit, so the plain wait ends.
fn replay(dir: &Path, registry: &Path) -> (Option<i32>, String, String) {
    let run = TestRun::new("replay");
    let out: Output = std::process::Command::new(workspace_bin("hnav"))
        .args(["log", "replay"])
        .arg(dir)
        .args(["--run", run.run.as_str()])
        .env("HNAV_RUNS_DIR", registry)
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Rewrites the log in `log_dir` with the first accepted move at or after round 50 turned
/// into a block (crossing, the move's direction refused); returns its round and agent and
/// the cell the replay will accept again.
fn alter_one_decision(log_dir: &Path) -> (u64, u32, u32) {
    let mut records = read_log(log_dir).unwrap().records;
    let mut altered = None;
    for r in &mut records {
        let Record::Round(rec) = r else { continue };
        if rec.round < 50 || altered.is_some() {
            continue;
        }
        if let Some(d) = rec
            .decisions
            .iter_mut()
            .find(|d| d.verdict == Verdict::Accept as u8)
        {
            altered = Some((rec.round, d.agent, d.cell));
            d.verdict = Verdict::Block as u8;
            d.kind = ConflictKind::Crossing as u8;
            d.refused = 1;
            d.cell = NO_CELL;
        }
    }
    std::fs::remove_dir_all(log_dir).unwrap();
    let (mut w, _) = LogWriter::open(log_dir, FsyncPolicy::None).unwrap();
    for r in &records {
        w.append(r).unwrap();
    }
    w.sync().unwrap();
    altered.expect("the demo accepts a move after round 50")
}

#[test]
fn a_lockstep_run_replays_identically_and_an_altered_decision_is_found() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let scenario = demo(tmp.path(), |t| t);
    let dir = tmp.path().join("run");
    assert_eq!(
        run(
            "replay-demo",
            &scenario,
            &dir,
            &registry,
            &["--mode", "lockstep"]
        ),
        Some(0)
    );

    replays_as_identical(&dir, &registry);

    let (round, agent, cell) = alter_one_decision(&dir.join("log"));
    let (ok, report) = verify_log(&dir.join("log"));
    assert!(ok, "the altered log still verifies:\n{report}");
    let (code, out, err) = replay(&dir, &registry);
    assert_eq!(code, Some(1), "{out}{err}");
    let width = 12;
    let expected = format!(
        "first divergence: round {round}, agent {agent}: logged block a{agent} crossing (N), replayed accept a{agent}->[{}, {}]",
        cell % width,
        cell / width
    );
    assert_eq!(out.trim(), expected);

    // The scenario changed since the run: refused before anything runs.
    std::fs::write(
        &scenario,
        std::fs::read_to_string(&scenario)
            .unwrap()
            .replace("time_limit_s = 60", "time_limit_s = 61"),
    )
    .unwrap();
    let (code, out, err) = replay(&dir, &registry);
    assert_eq!(code, Some(2), "{out}{err}");
    assert!(
        err.contains("demo.toml: the scenario (with the run's --agents, --seed, --mode and faults) hashes to 0x")
            && err.contains("the scenario file or its map changed since the run"),
        "{err}"
    );
}

/// A lockstep run of the demo cut to its first `agents` robots with `extra` arguments; its
/// `hnav log replay` must print `N rounds replayed, identical` for the summary's N.
fn replays_identically(tag: &str, agents: &str, extra: &[&str]) {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let scenario = demo(tmp.path(), |t| t);
    let dir = tmp.path().join("run");
    let mut args = vec!["--mode", "lockstep", "--agents", agents, "--no-record"];
    args.extend_from_slice(extra);
    assert_eq!(run(tag, &scenario, &dir, &registry, &args), Some(0));
    replays_as_identical(&dir, &registry);
}

/// `hnav log replay DIR` prints `N rounds replayed, identical` for the summary's N.
fn replays_as_identical(dir: &Path, registry: &Path) {
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let rounds = summary["rounds"].as_u64().unwrap();
    let (code, out, err) = replay(dir, registry);
    assert_eq!(code, Some(0), "{out}{err}");
    assert_eq!(out.trim(), format!("{rounds} rounds replayed, identical"));
}

#[test]
fn a_lockstep_run_with_three_replicas_replays_identically() {
    replays_identically("replay-raft", "2", &["--replicas", "3"]);
}

#[test]
fn a_lockstep_run_with_a_fault_plan_replays_identically() {
    replays_identically(
        "replay-plan",
        "3",
        &[
            "--kill",
            "agent:1@round:40",
            "--freeze",
            "agent:2@round:60+0.2s",
        ],
    );
}

#[test]
fn a_realtime_run_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let scenario = demo(tmp.path(), |t| {
        t.replace("time_limit_s = 60", "time_limit_s = 1")
    });
    let dir = tmp.path().join("run");
    assert_eq!(
        run(
            "replay-rt",
            &scenario,
            &dir,
            &registry,
            &["--mode", "realtime"]
        ),
        Some(1),
        "a realtime run that ends on its 1 s limit"
    );
    let (code, out, err) = replay(&dir, &registry);
    assert_eq!(code, Some(2), "{out}{err}");
    assert!(
        err.contains("a realtime run cannot be replayed: only a lockstep run is a function of its scenario and seed"),
        "{err}"
    );
}

#[test]
fn the_demo_run_exports_to_mcap_with_every_channel() {
    use hnav_operator::recording::{self, MapReader, PoseSource, TrajectoryReader};
    use std::collections::BTreeMap;

    let tmp = tempfile::tempdir().unwrap();
    let registry = tmp.path().join("runs");
    let scenario = demo(tmp.path(), |t| t);
    let dir = tmp.path().join("run");
    assert_eq!(
        run(
            "export-demo",
            &scenario,
            &dir,
            &registry,
            &["--mode", "lockstep"]
        ),
        Some(0)
    );
    let rec = dir.join(recording::DIR);
    let (samples, _) = TrajectoryReader::open(&rec.join(recording::TRAJECTORIES))
        .expect("the run recorded trajectories")
        .read_all()
        .unwrap();
    let (maps, _) = MapReader::open(&rec.join(recording::MAPS))
        .expect("the run recorded neural maps")
        .read_all()
        .unwrap();
    let mut expected: BTreeMap<String, u64> = BTreeMap::new();
    for i in 0..6 {
        for t in ["truth", "estimate", "neural_map"] {
            expected.insert(format!("/robots/{i}/{t}"), 0);
        }
    }
    for s in &samples {
        let t = if s.source == PoseSource::Truth {
            "truth"
        } else {
            "estimate"
        };
        *expected
            .get_mut(&format!("/robots/{}/{t}", s.robot))
            .unwrap() += 1;
    }
    for m in &maps {
        *expected
            .get_mut(&format!("/robots/{}/neural_map", m.header.agent))
            .unwrap() += 1;
    }
    let log = read_log(dir.join("log")).unwrap().records;
    let rounds = log.iter().filter(|r| matches!(r, Record::Round(_))).count() as u64;
    let decisions = log
        .iter()
        .map(|r| match r {
            Record::Round(x) => x.decisions.len() as u64,
            _ => 0,
        })
        .sum();
    let replans = log
        .iter()
        .filter(|r| matches!(r, Record::Replan(_)))
        .count() as u64;
    expected.insert("/map".into(), 1);
    expected.insert("/commits".into(), rounds);
    expected.insert("/decisions".into(), decisions);
    expected.insert("/replans".into(), replans);
    let lifecycle = log
        .iter()
        .filter(|r| matches!(r, Record::Lifecycle(_)))
        .count() as u64;
    expected.insert("/lifecycle".into(), lifecycle);
    // The live view's channels: a scene and each robot's speed per ground-truth sampling time.
    let times: std::collections::BTreeSet<u64> = samples
        .iter()
        .filter(|s| s.source == PoseSource::Truth)
        .map(|s| s.t_ns)
        .collect();
    expected.insert("/scene".into(), times.len() as u64);
    for i in 0..6 {
        expected.insert(format!("/robots/{i}/stats"), times.len() as u64);
    }

    let out_file = tmp.path().join("demo.mcap");
    let out = std::process::Command::new(workspace_bin("hnav"))
        .args(["log", "export"])
        .arg(&dir)
        .arg("--mcap")
        .arg(&out_file)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&out_file).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    let mut got: BTreeMap<String, u64> = summary
        .channels
        .values()
        .map(|c| (c.topic.clone(), 0))
        .collect();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        *got.get_mut(&m.unwrap().channel.topic).unwrap() += 1;
    }
    // `/log`: a line per decision worth one (the fold's rule, operator/src/channels/scene.rs's
    // tests); here only that the demo's accepted moves gave some.
    let log_lines = got.remove("/log").expect("a /log channel");
    assert!(log_lines >= 6, "{log_lines} log lines");
    assert_eq!(got, expected);
    assert!(expected["/robots/0/truth"] > 0 && expected["/robots/0/neural_map"] > 0);
}
