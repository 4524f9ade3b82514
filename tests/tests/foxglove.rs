//! The live Foxglove view against a client that shares no code with HNAV
//! (`clients/python/examples/foxglove_client.py`: PyPI `websockets` speaking the Foxglove
//! WebSocket protocol, offering it as `foxglove.websocket.v1` and `foxglove.sdk.v1`, its old
//! and new names, PyPI `mcap`): during a live `hnav run --foxglove ADDR` it reads the
//! advertised channels, subscribes, decodes the binary frames and sees the demo's 12 x 12 map
//! and its six robots moving (after a first connection of its own dropped mid-stream, which
//! the run does not notice); then the run's `hnav log export --mcap` holds every channel
//! advertised live, with the same schemas. And `--foxglove` with an address in use or one
//! that does not parse stops `hnav run` before anything is spawned.
//!
//! The Python is the virtual environment's (`hnav_tests::python::python`): skipped without one,
//! unless `HNAV_REQUIRE_PYTHON` is set (CI sets it).

use std::net::TcpListener;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use hnav_runtime::transport::{run_iceoryx2_files, run_shm_files, RunId};
use hnav_tests::python::python as venv_python;
use hnav_tests::swarm::{repo_root, workspace_bin, SwarmRun};
use hnav_tests::{free_port, TestRun};

/// Bound on the whole live run (realtime, so the client has time to join).
const RUN_TIMEOUT: Duration = Duration::from_secs(180);
/// Bound on `hnav view` playing the run back at 10x.
const VIEW_TIMEOUT: Duration = Duration::from_secs(120);
/// How long the client reads, at most, before it checks what it got.
const CLIENT_READS_S: u32 = 120;

fn client(python: &Path, args: &[String]) -> std::process::Output {
    let script = repo_root().join("clients/python/examples/foxglove_client.py");
    Command::new(python)
        .arg(script)
        .args(args)
        .output()
        .expect("the client starts")
}

#[test]
fn a_foxglove_client_watches_a_live_run_and_its_export_holds_the_same_channels() {
    let Some(python) = venv_python() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let mut run = TestRun::new("foxglove");
    let addr = format!("127.0.0.1:{}", free_port());
    let out = tmp.path().join("out");
    let mut swarm = SwarmRun::start(
        &mut run,
        &repo_root().join("scenarios/demo.toml"),
        &out,
        &tmp.path().join("runs"),
        &["--mode", "realtime", "--foxglove", &addr],
    )
    .expect("hnav run starts");
    let advertised = tmp.path().join("advertised.json");
    let live = client(
        &python,
        &[
            "live".into(),
            format!("ws://{addr}"),
            "--width=12".into(),
            "--height=12".into(),
            "--robots=6".into(),
            format!("--advertised={}", advertised.display()),
            format!("--timeout={CLIENT_READS_S}"),
        ],
    );
    let said =
        String::from_utf8_lossy(&live.stdout).into_owned() + &String::from_utf8_lossy(&live.stderr);
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert!(live.status.success(), "the live client failed:\n{said}");
    assert!(said.contains("ok a client dropped in the middle"), "{said}");
    assert!(said.contains("ok grid 12 x 12"), "{said}");
    assert!(said.contains("robots moved"), "{said}");
    assert!(
        status.success(),
        "the run, watched, did not end well ({status}):\n{}",
        swarm.log_tails()
    );
    // The view's own node in the supervisor was gone before the supervisor purged the run.
    let left: Vec<_> = run_shm_files(&run.run)
        .into_iter()
        .chain(run_iceoryx2_files(&run.run))
        .collect();
    assert!(left.is_empty(), "the run left {left:?}");

    let mcap = tmp.path().join("run.mcap");
    let export = Command::new(workspace_bin("hnav"))
        .args(["log", "export"])
        .arg(&out)
        .arg("--mcap")
        .arg(&mcap)
        .output()
        .unwrap();
    assert!(export.status.success(), "{export:?}");
    let read = client(
        &python,
        &[
            "mcap".into(),
            mcap.display().to_string(),
            format!("--advertised={}", advertised.display()),
        ],
    );
    let said =
        String::from_utf8_lossy(&read.stdout).into_owned() + &String::from_utf8_lossy(&read.stderr);
    assert!(read.status.success(), "the MCAP check failed:\n{said}");
    assert!(
        said.contains("holds the 15 channels advertised live"),
        "{said}"
    );
    // The finished run served again by `hnav view`, played back: the same checks, the same
    // channels advertised.
    let addr = format!("127.0.0.1:{}", free_port());
    let args: Vec<String> = [
        "view",
        &out.display().to_string(),
        "--foxglove",
        &addr,
        "--speed",
        "10",
        "--exit-on-end",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let mut view = run
        .spawn_exact_env(
            &workspace_bin("hnav").display().to_string(),
            &args,
            &[("HNAV_RUNS_DIR", &tmp.path().join("runs"))],
        )
        .expect("hnav view starts");
    let replayed = tmp.path().join("advertised-view.json");
    let live = client(
        &python,
        &[
            "live".into(),
            format!("ws://{addr}"),
            "--width=12".into(),
            "--height=12".into(),
            "--robots=6".into(),
            format!("--advertised={}", replayed.display()),
            format!("--timeout={CLIENT_READS_S}"),
        ],
    );
    let said =
        String::from_utf8_lossy(&live.stdout).into_owned() + &String::from_utf8_lossy(&live.stderr);
    let status = view.wait_exit(VIEW_TIMEOUT).expect("hnav view ends");
    assert!(
        live.status.success(),
        "the client of hnav view failed:\n{said}"
    );
    assert!(status.success(), "hnav view: {status}");
    assert_eq!(
        std::fs::read_to_string(&replayed).unwrap(),
        std::fs::read_to_string(&advertised).unwrap(),
        "hnav view advertised other channels than the live run"
    );
}

/// `hnav run --foxglove ADDR` with `extra`, into a fresh directory: must refuse with exit 2,
/// before the run directory exists (so before anything was spawned); the message.
fn refused(foxglove: &str) -> String {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let id = RunId::unique("foxglove-refusal");
    let started = Instant::now();
    let o = Command::new(workspace_bin("hnav"))
        .arg("run")
        .arg(repo_root().join("scenarios/demo.toml"))
        .args(["--run", id.as_str(), "--out"])
        .arg(&out)
        .args(["--foxglove", foxglove])
        .env("HNAV_RUNS_DIR", tmp.path().join("runs"))
        .output()
        .unwrap();
    let _ = hnav_runtime::transport::purge_run(&id);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(!out.exists(), "the run directory was made: {err}");
    assert!(started.elapsed() < Duration::from_secs(30));
    err
}

#[test]
fn an_address_in_use_or_unparseable_stops_the_run_before_anything_is_spawned() {
    let taken = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    let e = refused(&addr);
    assert!(
        e.contains(&format!("--foxglove {addr}: cannot listen there:")),
        "{e}"
    );
    let e = refused("localhost:port");
    assert!(
        e.contains("--foxglove localhost:port: not an address to listen on"),
        "{e}"
    );
}
