//! Clients that join a live run from outside: a viewer subscribing to an agent's neural map
//! long after the agent built it gets the snapshot at once, and `hnav services RUN` lists the
//! run's topics with their publishers and subscribers.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use hnav_runtime::msg::MapHeader;
use hnav_runtime::topics::{self, CommitReceiver};
use hnav_runtime::transport::Transport;
use hnav_tests::swarm::{hnav_output, SwarmRun};
use hnav_tests::TestRun;
use nix::sys::signal::Signal;

/// Bound on a whole run, start-up to summary.
const RUN_TIMEOUT: Duration = Duration::from_secs(120);

/// Width of the test's room.
const WIDTH: usize = 16;
/// Height of the test's room.
const HEIGHT: usize = 4;

/// One swarm at a time: two runs at once on a 2-core machine only slow each other down.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// An empty 16 x 4 room: agent 0 moves one cell and then stands on its goal for the rest of
/// the run, so its map is built once, before round 1, and never again; agent 1 crawls along
/// the far row (15 cells at 0.5 cells/s, about 3000 lockstep rounds) and keeps the run going.
fn scenario(dir: &Path) -> PathBuf {
    let rows: Vec<String> = (0..HEIGHT)
        .map(|_| format!("{:?}", ".".repeat(WIDTH)))
        .collect();
    let text = format!(
        "name = \"observers\"\n[map]\nrows = [{}]\ncorner_cutting = false\n\n[sim]\n\
         clock = \"lockstep\"\nseed = 1\n\n[coordinator]\nrules = \"dissertation\"\ntime_limit_s = 120\n\n\
         [[agents]]\nstart = [0, 0]\ngoal = [1, 0]\n\n\
         [[agents]]\nstart = [0, 3]\ngoal = [15, 3]\nspeed = 0.5\n",
        rows.join(", ")
    );
    let path = dir.join("scenario.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// Takes commits until one of round `round` or later has been seen; returns that round.
fn wait_for_round(t: &Transport, commits: &CommitReceiver, round: u64) -> u64 {
    let waiter = t.waiter().unwrap();
    let _attached = waiter.attach(commits).unwrap();
    let deadline = Instant::now() + RUN_TIMEOUT;
    let mut last = 0;
    while last < round {
        assert!(
            Instant::now() < deadline,
            "no commit of round {round} within {RUN_TIMEOUT:?} (last {last})"
        );
        commits
            .drain_pending(|h, _| last = last.max(h.round))
            .unwrap();
        let _ = waiter.wait(Some(Instant::now() + Duration::from_millis(100)));
    }
    last
}

/// Starts the test's run; returns it with the run directory's parent.
fn start(run: &mut TestRun) -> (SwarmRun, PathBuf) {
    let tmp = tempfile::tempdir().unwrap().keep();
    let swarm = SwarmRun::start(
        run,
        &scenario(&tmp),
        &tmp.join("out"),
        &tmp.join("runs"),
        &["--mode", "lockstep"],
    )
    .expect("hnav run starts");
    (swarm, tmp)
}

/// Stops the run (SIGTERM to the supervisor): what the test needed has been seen, and on a
/// loaded machine the rest of the run could take minutes.
fn stop(swarm: &mut SwarmRun) {
    swarm.peer.signal(Signal::SIGTERM).unwrap();
    swarm.finish(RUN_TIMEOUT).expect("hnav run stops");
}

#[test]
fn a_late_viewer_gets_the_latest_map_at_once() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let mut run = TestRun::new("latemap");
    let (mut swarm, _tmp) = start(&mut run);
    let snapshot = {
        let t = Transport::builder(&run.run)
            .node_name("late-viewer")
            .create()
            .unwrap();
        let commits = t
            .slice_receiver(topics::COMMIT, topics::commit_qos(2))
            .unwrap();
        // Long after agent 0's one and only build (before round 1), and long before the run
        // ends (about round 3000).
        let seen = wait_for_round(&t, &commits, 200);
        let maps = t
            .slice_receiver::<f32, MapHeader>(&topics::map(0), topics::state_qos())
            .unwrap();
        let waiter = t.waiter().unwrap();
        let _attached = waiter.attach(&maps).unwrap();
        // Agent 0 never rebuilds: a snapshot can only come from the publisher's history.
        // Before the fix none came until the run ended.
        let deadline = Instant::now() + Duration::from_secs(10);
        let mut got = None;
        while got.is_none() && Instant::now() < deadline {
            let _ = maps.take_wakeup();
            if let Some(s) = maps.receive().unwrap() {
                got = Some((*s.user_header(), s.payload().len(), seen));
            } else {
                let _ = waiter.wait(Some(Instant::now() + Duration::from_millis(50)));
            }
        }
        got
    };
    stop(&mut swarm);
    let (header, len, seen) = snapshot.expect("no neural-map snapshot within 10 s of subscribing");
    assert_eq!(header.agent, 0);
    assert_eq!((header.width, header.height), (WIDTH as u32, HEIGHT as u32));
    assert_eq!(len, WIDTH * HEIGHT);
    assert!(
        header.round < seen,
        "the snapshot (round {}) is not the one built before the viewer joined at round {seen}",
        header.round
    );
}

/// The nodes named in a JSON port list of `hnav services --json`.
fn node_names(ports: &serde_json::Value) -> Vec<String> {
    ports
        .as_array()
        .map(|a| {
            a.iter()
                .map(|p| p["node"].as_str().unwrap_or_default().to_string())
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn services_lists_the_topics_with_their_publishers_and_subscribers() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let mut run = TestRun::new("services");
    let (mut swarm, tmp) = start(&mut run);
    let registry = tmp.join("runs");
    let id = run.run.as_str().to_string();
    let (json, text) = {
        let t = Transport::builder(&run.run)
            .node_name("services-test")
            .create()
            .unwrap();
        let commits = t
            .slice_receiver(topics::COMMIT, topics::commit_qos(2))
            .unwrap();
        wait_for_round(&t, &commits, 100);
        let ask = |json: bool| {
            let mut args = vec!["services".to_string(), id.clone()];
            if json {
                args.push("--json".into());
            }
            let out = hnav_output(&args, &registry, Duration::from_secs(30)).unwrap();
            assert!(out.status.success(), "hnav services failed: {}", out.stderr);
            out.stdout
        };
        (ask(true), ask(false))
    };
    stop(&mut swarm);

    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["run_id"], id.as_str());
    let topics = v["topics"].as_array().unwrap();
    let names: Vec<&str> = topics
        .iter()
        .map(|t| t["topic"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "candidates",
            "commit",
            "estimate",
            "heartbeat",
            "lifecycle",
            "map/0",
            "map/1",
            "odom/0",
            "odom/1",
            "progress",
            "ready",
            "truth",
            "wheels/0",
            "wheels/1"
        ],
        "{json}"
    );
    let topic = |name: &str| topics.iter().find(|t| t["topic"] == name).unwrap();
    let commit = topic("commit");
    assert_eq!(
        (commit["payload"].as_str(), commit["user_header"].as_str()),
        (Some("[hnav::Decision]"), Some("hnav::CommitHeader"))
    );
    assert_eq!(node_names(&commit["publishers"]), ["coordinator"], "{json}");
    let readers = node_names(&commit["subscribers"]);
    for n in ["agent-0", "agent-1", "services-test"] {
        assert!(
            readers.iter().any(|r| r == n),
            "{n} not a commit subscriber: {json}"
        );
    }
    assert!(
        commit["publishers"][0]["pid"].as_i64().unwrap() > 0,
        "{json}"
    );
    let map = topic("map/1");
    assert_eq!(
        (map["payload"].as_str(), map["user_header"].as_str()),
        (Some("[f32]"), Some("hnav::MapHeader"))
    );
    assert_eq!(node_names(&map["publishers"]), ["agent-1"], "{json}");
    // The truth reaches the supervisor and its recorder; the sim reads every robot's wheels.
    let mut truth_readers = node_names(&topic("truth")["subscribers"]);
    truth_readers.sort();
    assert_eq!(truth_readers, ["recorder", "supervisor"], "{json}");
    assert_eq!(
        node_names(&topic("wheels/0")["subscribers"]),
        ["sim"],
        "{json}"
    );
    let mut writers = node_names(&topic("candidates")["publishers"]);
    writers.sort();
    assert_eq!(writers, ["agent-0", "agent-1"], "{json}");
    assert!(
        text.contains(&format!(
            "hnav/{id}/commit  [[hnav::Decision], header hnav::CommitHeader]  history 1, buffer 64, latest"
        )),
        "{text}"
    );
    assert!(
        text.contains("  publishers 1/10: coordinator (pid "),
        "{text}"
    );

    // Once the run is over its id names no live run.
    let out = hnav_output(
        &["services".into(), id.clone()],
        &registry,
        Duration::from_secs(30),
    )
    .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", out.stdout);
    assert!(
        out.stderr.contains(&format!("no live run `{id}`")),
        "{}",
        out.stderr
    );
}
