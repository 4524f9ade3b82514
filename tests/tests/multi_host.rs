//! Runs across hosts on one machine (issue 17): three "hosts" in Linux network namespaces
//! joined by a switch (`hnav_tests::netns`), each with its own iceoryx2 domain
//! (`HNAV_DOMAIN`) and run registry, so that only the hosts' bridges (Zenoh over TCP) link
//! them. The coordinator and the sim run on host 0, the agents are split between hosts 1
//! and 2; each host runs `hnav run --host NAME` as a robotics lab would on three computers.
//!
//! - In lockstep the consensus log is the one-host run's, record for record.
//! - In realtime with 5 ± 2 ms of delay (the bridge's test-only delay layer) and 1 % loss
//!   (nftables) on every link, every robot still gets home without a collision.
//! - A robot host cut off for 2 s stands (the sim's watchdog brakes its robots, the
//!   coordinator logs them down) and rejoins when the link is back.
//! - Three coordinator replicas on three hosts of their own (`replicas_apart`): the rounds go on
//!   with one replica host cut off, stop with the leader's cut off too, and resume when both
//!   are back; the replicas' logs agree.
//!
//! Where namespaces cannot be created (no root, a locked-down kernel) each test says so and
//! skips, unless `HNAV_REQUIRE_NETNS=1` (set by `.ci/run` where its probe could make one).

#[path = "multi_host/replicas_apart.rs"]
mod replicas_apart;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use hnav_runtime::consensus_log::{read_log, Record};
use hnav_runtime::msg::{LifecycleEvent, Role};
use hnav_runtime::transport::RunId;
use hnav_tests::across::{
    self, one_at_a_time, required, summary, Across, DomainPurge, RUN_TIMEOUT,
};
use hnav_tests::netns::Net;
use hnav_tests::swarm::{hnav_output, lifecycle_records, records_digest, repo_root, SwarmRun};
use hnav_tests::TestRun;

/// Rounds the coordinator must decide while a robot host is cut off (see the cut test).
const MIN_ROUNDS_WHILE_CUT: u64 = 5;
/// Rounds the coordinator logs before the cut test cuts a host off.
const CUT_AFTER_ROUNDS: u64 = 300;
/// The hosts' names: the base station, then two robot computers.
const HOSTS: [&str; 3] = ["base", "robots-a", "robots-b"];

/// The namespaces of the three hosts for test `tag`, or `None` where they cannot be made.
fn net_or_skip(tag: &str) -> Option<Net> {
    across::net_or_skip(tag, HOSTS.len())
}

/// The purge of every host's domain for `run`.
fn purge(run: &RunId) -> DomainPurge {
    DomainPurge {
        run: run.clone(),
        hosts: HOSTS.iter().map(|h| h.to_string()).collect(),
    }
}

/// Writes a placement of `agents` agents into `dir`: sim and coordinator on host 0 (the hub,
/// which alone listens), the first half of the agents on host 1, the rest on host 2.
fn placement(dir: &Path, agents: usize) -> PathBuf {
    let half = agents / 2;
    let host = |i: usize, what: &str| format!("[[host]]\nname = \"{}\"\n{what}\n\n", HOSTS[i]);
    let hub = format!(
        "listen = [\"tcp/{}:7447\"]\nsim = true\ncoordinator = true",
        Net::addr(0)
    );
    let text = host(0, &hub)
        + &host(1, &format!("agents = \"0-{}\"", half - 1))
        + &host(2, &format!("agents = \"{half}-{}\"", agents - 1));
    let file = dir.join("hosts.toml");
    std::fs::write(&file, text).unwrap();
    file
}

/// The demo for a realtime test, written into `dir`: its time limit doubled to 120 s. The
/// verdict is every robot home without a collision, not how fast: on a machine loaded twenty
/// times over (four builds and another test binary beside it) a realtime demo with a host cut
/// off for 2 s ran out of its 60 s with one robot short of its goal.
fn realtime_demo(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(repo_root().join("scenarios/demo.toml")).unwrap();
    assert!(
        text.contains("time_limit_s = 60\n"),
        "the demo's time limit moved"
    );
    let file = dir.join("demo.toml");
    std::fs::write(
        &file,
        text.replace("time_limit_s = 60\n", "time_limit_s = 120\n"),
    )
    .unwrap();
    file
}

/// Starts `hnav run SCENARIO --host H` on each of the three hosts, placed by [`placement`]
/// for the `--agents` of `extra` (6 without).
fn start(
    run: &mut TestRun,
    net: &Net,
    scenario: &Path,
    tmp: &Path,
    extra: &[&str],
    env: &[(&str, &Path)],
) -> Across {
    let agents = extra
        .windows(2)
        .find(|w| w[0] == "--agents")
        .map_or(6, |w| w[1].parse().unwrap());
    let hosts = placement(tmp, agents);
    Across::start(run, net, &HOSTS, &hosts, scenario, tmp, extra, env)
}

/// [`start`] in realtime.
fn realtime(
    run: &mut TestRun,
    net: &Net,
    scenario: &Path,
    tmp: &Path,
    env: &[(&str, &Path)],
) -> Across {
    start(run, net, scenario, tmp, &["--mode", "realtime"], env)
}

/// A one-host run of `scenario` with `extra` arguments into `dir`; returns its wall time.
fn one_host(tag: &str, scenario: &Path, dir: &Path, extra: &[&str]) -> f64 {
    let mut run = TestRun::new(tag);
    let registry = dir.with_extension("runs");
    let mut args = vec!["--no-record"];
    args.extend_from_slice(extra);
    let mut swarm = SwarmRun::start(&mut run, scenario, dir, &registry, &args).unwrap();
    let status = swarm.finish(RUN_TIMEOUT).unwrap();
    assert!(status.success(), "{status}\n{}", swarm.log_tails());
    let s = swarm.summary().unwrap();
    assert_eq!(s["end"], "all-at-goal", "{s}");
    s["wall_time_s"].as_f64().unwrap()
}

/// In lockstep, `scenario` across the three hosts logs what it logs on one host.
fn same_log_as_one_host(tag: &str, scenario: &Path, extra: &[&str]) {
    let _one = one_at_a_time();
    let Some(net) = net_or_skip(tag) else { return };
    let tmp = tempfile::tempdir().unwrap();
    let mut args = vec!["--mode", "lockstep"];
    args.extend_from_slice(extra);
    let one = tmp.path().join("one");
    one_host(&format!("{tag}1"), scenario, &one, &args);
    let reference = read_log(one.join("log")).unwrap().records;
    assert!(reference.len() > 10, "a suspiciously short log");

    let mut run = TestRun::new(tag);
    let _purge = purge(&run.run);
    let mut across = start(&mut run, &net, scenario, tmp.path(), &args, &[]);
    across.finish();
    let got = read_log(across.dirs[0].join("log")).unwrap().records;
    assert_eq!(
        got.len(),
        reference.len(),
        "records across hosts vs one host"
    );
    if let Some(i) = (0..got.len()).find(|&i| got[i] != reference[i]) {
        panic!("record {i} differs:\n{:?}\n{:?}", got[i], reference[i]);
    }
    println!(
        "{tag}: {} records, digest {} (one host and three)",
        got.len(),
        records_digest(&got)
    );
}

#[test]
fn sixteen_agents_across_three_hosts_log_what_one_host_logs() {
    let scenario = repo_root().join("scenarios/random-32-32-10.toml");
    same_log_as_one_host("r16", &scenario, &["--agents", "16"]);
}

/// A fault plan across hosts: agent 4 (on `robots-b`) killed at round 100 in lockstep. Every
/// host reads the plan, `robots-b` kills and restarts it and resumes the sim's hold: the log
/// is the one-host run's with the same kill, record for record. (Before, a plan was refused
/// in a run across hosts.)
#[test]
fn a_lockstep_kill_on_a_robot_host_logs_what_it_logs_on_one_host() {
    let scenario = repo_root().join("scenarios/demo.toml");
    same_log_as_one_host("dkill", &scenario, &["--kill", "agent:4@round:100"]);
}

#[test]
fn delay_and_loss_on_every_link_still_bring_every_robot_home() {
    let _one = one_at_a_time();
    // The loss is nftables': without `nft` the test skips and says so (unless CI, which
    // installs it, requires the namespace tests).
    if let Err(e) = Net::loss_tool() {
        if required() {
            panic!("HNAV_REQUIRE_NETNS=1 but {e}");
        }
        eprintln!("skipped: {e}");
        return;
    }
    let Some(net) = net_or_skip("lossy") else {
        return;
    };
    net.set_loss(1).expect("nftables makes the loss");
    let tmp = tempfile::tempdir().unwrap();
    let scenario = realtime_demo(tmp.path());
    // The same run on one host, to compare the rates with, is `hnav run` of this scenario
    // in realtime: a measurement, not this test's verdict, so it is not repeated here.
    let mut run = TestRun::new("lossy");
    let _purge = purge(&run.run);
    let delay = PathBuf::from("5:2");
    let env = [("HNAV_BRIDGE_DELAY_MS", delay.as_path())];
    let mut across = realtime(&mut run, &net, &scenario, tmp.path(), &env);
    across.finish();
    let s = summary(&across.dirs[0]);
    let rounds = s["rounds"].as_u64().unwrap();
    let wall = s["wall_time_s"].as_f64().unwrap();
    println!(
        "realtime demo: three hosts with 5 +- 2 ms delay and 1 % loss per link {rounds} rounds \
         in {wall:.1} s ({:.1}/s)",
        rounds as f64 / wall
    );
}

/// `hnav ps` on host 1 lists every process of the run: its own running, the others on
/// their hosts.
fn every_host_shows_the_whole_run(tmp: &Path) {
    let registry = tmp.join(format!("runs-{}", HOSTS[1]));
    let ps = |json: bool| {
        let mut args = vec!["ps".to_string()];
        if json {
            args.push("--json".into());
        }
        hnav_output(&args, &registry, Duration::from_secs(60))
            .unwrap()
            .stdout
    };
    let v: serde_json::Value = serde_json::from_str(&ps(true)).unwrap();
    let procs = v["runs"][0]["processes"].as_array().unwrap().clone();
    let state = |role: &str, index: u32| {
        let p = procs
            .iter()
            .find(|p| p["role"] == role && p["index"] == index)
            .unwrap_or_else(|| panic!("no {role} {index} in {procs:?}"));
        (
            p["state"].as_str().unwrap().to_string(),
            p["host"].as_str().map(str::to_string),
        )
    };
    assert_eq!(state("sim", 0), ("remote".into(), Some("base".into())));
    assert_eq!(
        state("coordinator", 0),
        ("remote".into(), Some("base".into()))
    );
    assert_eq!(state("bridge", 1), ("running".into(), None));
    for a in 0..3 {
        assert_eq!(state("agent", a), ("running".into(), None));
    }
    for a in 3..6 {
        assert_eq!(
            state("agent", a),
            ("remote".into(), Some("robots-b".into()))
        );
    }
    assert_eq!(
        procs.len(),
        9,
        "sim, coordinator, 6 agents and the bridge: {procs:?}"
    );
    println!("hnav ps on host {}:\n{}", HOSTS[1], ps(false));
}

#[test]
fn a_robot_host_cut_off_for_two_seconds_stands_and_rejoins() {
    let _one = one_at_a_time();
    let Some(net) = net_or_skip("cut") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let scenario = realtime_demo(tmp.path());
    let mut run = TestRun::new("cut");
    let _purge = purge(&run.run);
    let mut across = realtime(&mut run, &net, &scenario, tmp.path(), &[]);
    // Early in the run: once the coordinator has logged CUT_AFTER_ROUNDS rounds (3 s in on a
    // quiet machine, about 10 s on one loaded 10-fold; the robots need 30 to 45 s to get
    // home). A run that ends first fails at once, not at the timeout.
    let log = across.dirs[0].join("log");
    let deadline = Instant::now() + RUN_TIMEOUT;
    let cut_at = loop {
        let rounds = read_log(&log).map_or(0, |l| {
            l.records
                .iter()
                .filter(|r| matches!(r, Record::Round(_)))
                .count() as u64
        });
        if rounds >= CUT_AFTER_ROUNDS {
            break rounds;
        }
        if let Ok(status) = across.supervisors[0].wait_exit(Duration::ZERO) {
            panic!(
                "the base station ended ({status}) after {rounds} rounds, before the cut\n{}",
                across.tails()
            );
        }
        assert!(
            Instant::now() < deadline,
            "the run never reached round {CUT_AFTER_ROUNDS}"
        );
        std::thread::sleep(Duration::from_millis(100));
    };
    every_host_shows_the_whole_run(tmp.path());
    net.cut(2, false).unwrap();
    // The partition itself lasts 2 s: this sleep is the fault, not a synchronisation.
    std::thread::sleep(Duration::from_secs(2));
    net.cut(2, true).unwrap();
    across.finish();

    // No put to Zenoh held a bridge's loop (every topic of its host waits behind it); a put
    // that waits for the dead link is logged by the bridge and fails the test here.
    for (host, dir) in HOSTS.iter().zip(&across.dirs) {
        let bridge_log = std::fs::read_to_string(dir.join("logs/bridge.log")).unwrap_or_default();
        for l in bridge_log.lines().filter(|l| l.contains("held the bridge")) {
            println!("{host} bridge: {l}");
            let held_ms = l
                .split("held_ms=")
                .nth(1)
                .and_then(|r| r.split_whitespace().next()?.parse::<f64>().ok())
                .unwrap_or(0.0);
            assert!(
                !(l.contains("loop thread") && held_ms >= 200.0),
                "a put held {host}'s bridge loop: {l}"
            );
        }
    }
    // Host 2 runs agents 3, 4 and 5: each logged down once the cut came (after round
    // `cut_at`), then back.
    let events = lifecycle_records(&log);
    for agent in 3..6u32 {
        let of: Vec<_> = events
            .iter()
            .filter(|e| e.1 == Some(Role::Agent) && e.2 == agent)
            .map(|e| (e.0, e.3))
            .collect();
        println!("agent {agent}: lifecycle records (round, event) {of:?}");
        let down = of
            .iter()
            .rposition(|e| e.0 >= cut_at && e.1 == Some(LifecycleEvent::Down))
            .unwrap_or_else(|| panic!("agent {agent} never down after round {cut_at}: {of:?}"));
        let back = of[down..]
            .iter()
            .find(|e| e.1 == Some(LifecycleEvent::Restarted))
            .unwrap_or_else(|| panic!("agent {agent} never back after the cut: {of:?}"));
        // The cut host must not stop the others: while it is away the coordinator goes on
        // deciding rounds for the robots of the other hosts. Counted in rounds, not seconds,
        // so that a busy machine does not change the verdict: a base station held by the
        // dead link decided 1 round in the 1.2 s it stood (seen once in 11 runs of the
        // binary under load); a working
        // one decides 55 to 125 in that time.
        let decided = back.0 - of[down].0;
        assert!(
            decided >= MIN_ROUNDS_WHILE_CUT,
            "only {decided} rounds decided while agent {agent}'s host was cut off: {of:?}"
        );
    }
    // The sim's watchdog braked each robot of the cut host.
    let sim_log = std::fs::read_to_string(across.dirs[0].join("logs/sim.log")).unwrap();
    for robot in 3..6 {
        let braked = sim_log
            .lines()
            .any(|l| l.contains("braking") && l.contains(&format!("robot={robot} ")));
        assert!(braked, "robot {robot} never braked:\n{sim_log}");
    }
    for l in sim_log.lines().filter(|l| l.contains("watchdog")) {
        println!("sim: {l}");
    }
    // How long the robots of the other robot host stood at most, for the record: on a busy
    // machine an agent process may miss its 100 ms watchdog by itself, so the verdict on
    // them is the rounds decided above, not this.
    for robot in 0..3 {
        println!(
            "robot {robot} stood at most {:.3} s",
            longest_brake_s(&sim_log, robot)
        );
    }
    let s = summary(&across.dirs[0]);
    println!(
        "cut run: {} rounds in {} s, end {}",
        s["rounds"], s["wall_time_s"], s["end"]
    );
}

/// The longest time robot `robot` stood braked, from the sim's log: from a `braking` line to
/// the next `wheel commands again`, in sim seconds.
fn longest_brake_s(sim_log: &str, robot: u32) -> f64 {
    let field = |l: &str, key: &str| -> Option<f64> {
        let rest = &l[l.find(key)? + key.len()..];
        rest.split_whitespace().next()?.parse().ok()
    };
    let tag = format!("robot={robot} ");
    let (mut since, mut longest) = (None, 0.0f64);
    for l in sim_log.lines().filter(|l| l.contains(&tag)) {
        let Some(t) = field(l, "sim_time_s=") else {
            continue;
        };
        if l.contains("braking") {
            since = Some(t);
        } else if let Some(s) = since.take() {
            longest = longest.max(t - s);
        }
    }
    longest
}
