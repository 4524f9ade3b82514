//! Fault injection on whole swarms: the supervisor SIGKILLs a process mid-run (the scenario's
//! `[[faults]]`), restarts it, and the run still ends with every robot on its goal.
//!
//! In its own test binary because it SIGKILLs processes.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use hnav_runtime::consensus_log::{read_log, Record};
use hnav_runtime::msg::{Commit, CommitView, MapHeader};
use hnav_runtime::topics;
use hnav_runtime::transport::{RunId, Transport};
use hnav_tests::swarm::{repo_root, verify_log, SwarmRun};
use hnav_tests::TestRun;

const RUN_TIMEOUT: Duration = Duration::from_secs(600);

/// The 8-agent MovingAI scenario with `coordinator` keys added to its `[coordinator]` table
/// and a fault appended (the map path made absolute, so the scenario can live in a temporary
/// directory).
fn scenario_with_fault(dir: &Path, coordinator: &str, fault: &str) -> std::path::PathBuf {
    let root = repo_root();
    let text = std::fs::read_to_string(root.join("scenarios/random-32-32-10.toml")).unwrap();
    let map = root.join("maps/random-32-32-10.map");
    let text = text.replace(
        "file = \"../maps/random-32-32-10.map\"",
        &format!("file = {:?}", map.display().to_string()),
    );
    assert!(
        text.contains("\n[coordinator]\n"),
        "the scenario lost its [coordinator] table"
    );
    let text = text.replacen(
        "\n[coordinator]\n",
        &format!("\n[coordinator]\n{coordinator}"),
        1,
    );
    let path = dir.join("scenario.toml");
    std::fs::write(&path, format!("{text}\n{fault}\n")).unwrap();
    path
}

/// The last neural-map snapshot of agent 0: its header and the value in its target cell.
type Snapshot = Option<(MapHeader, f32, usize)>;

/// Every commit seen on the run's commit topic, by round, and agent 0's last neural-map
/// snapshot, recorded by a thread of the test.
struct Observer {
    seen: Arc<Mutex<BTreeMap<u64, Commit>>>,
    /// Every commit's receipt: (monotonic ns, round), the clock of `events.jsonl`.
    times: Arc<Mutex<Vec<(u64, u64)>>>,
    map: Arc<Mutex<Snapshot>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Observer {
    fn start(run: &RunId, agents: usize) -> Observer {
        let seen = Arc::new(Mutex::new(BTreeMap::new()));
        let times = Arc::new(Mutex::new(Vec::new()));
        let t2 = times.clone();
        let map: Arc<Mutex<Snapshot>> = Arc::new(Mutex::new(None));
        let stop = Arc::new(AtomicBool::new(false));
        let (s2, st2, m2, run) = (seen.clone(), stop.clone(), map.clone(), run.clone());
        let (ready_tx, ready_rx) = std::sync::mpsc::channel();
        let thread = std::thread::spawn(move || {
            let t = Transport::builder(&run)
                .node_name("observer")
                .create()
                .unwrap();
            let rx: topics::CommitReceiver = t
                .slice_receiver(topics::COMMIT, topics::commit_qos(agents))
                .unwrap();
            let maps = t
                .slice_receiver::<f32, MapHeader>(&topics::map(0), topics::state_qos())
                .unwrap();
            let waiter = t.waiter().unwrap();
            let _commits = waiter.attach(&rx).unwrap();
            let _maps = waiter.attach(&maps).unwrap();
            ready_tx.send(()).unwrap();
            while !st2.load(Ordering::Relaxed) {
                let _ = maps.take_wakeup();
                while let Ok(Some(s)) = maps.receive() {
                    let h = *s.user_header();
                    let v = s
                        .payload()
                        .get(h.target as usize)
                        .copied()
                        .unwrap_or(f32::NAN);
                    *m2.lock().unwrap() = Some((h, v, s.payload().len()));
                }
                let _ = rx.drain_pending(|h, d| {
                    let mut c = Commit::default();
                    c.set(CommitView::new(h, d));
                    let now = hnav_runtime::clock::monotonic_ns();
                    t2.lock().unwrap().push((now, c.round));
                    let mut m = s2.lock().unwrap();
                    let (round, term) = (c.round, c.term);
                    if let Some(mut old) = m.insert(round, c.clone()) {
                        // A new leader's resend of the last round carries its own term.
                        old.term = term;
                        assert!(old == c, "round {round} committed twice, differently");
                    }
                });
                // Bounded, so that the thread sees `stop`.
                let _ = waiter.wait(Some(Instant::now() + Duration::from_millis(100)));
            }
        });
        ready_rx
            .recv_timeout(Duration::from_secs(30))
            .expect("observer up");
        Observer {
            seen,
            times,
            map,
            stop,
            thread: Some(thread),
        }
    }

    fn finish(mut self) -> (BTreeMap<u64, Commit>, Snapshot, Vec<(u64, u64)>) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            t.join().expect("observer thread");
        }
        let map = *self.map.lock().unwrap();
        let times = std::mem::take(&mut *self.times.lock().unwrap());
        (std::mem::take(&mut *self.seen.lock().unwrap()), map, times)
    }
}

/// One swarm at a time: three runs of ten processes at once on a 2-core machine would make
/// lockstep rounds crawl, and none of these tests is about contention.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// The run, every commit by round, agent 0's last map, every commit's receipt (monotonic ns,
/// round), and the test run (whose drop cleans up).
type Faulted = (
    SwarmRun,
    BTreeMap<u64, Commit>,
    Snapshot,
    Vec<(u64, u64)>,
    TestRun,
);

fn run_with_fault(tag: &str, coordinator: &str, fault: &str) -> Faulted {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap().keep();
    let scenario = scenario_with_fault(&tmp, coordinator, fault);
    let mut run = TestRun::new(tag);
    // The observer joins before the supervisor starts anything, so it sees every commit.
    let observer = Observer::start(&run.run, 8);
    let mut swarm = SwarmRun::start(
        &mut run,
        &scenario,
        &tmp.join("out"),
        &tmp.join("runs"),
        &["--mode", "lockstep"],
    )
    .expect("hnav run starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    let (seen, map, times) = observer.finish();
    assert!(
        status.success(),
        "run failed: {status}\n{}",
        swarm.log_tails()
    );
    (swarm, seen, map, times, run)
}

#[test]
fn a_killed_coordinator_restarts_from_its_log_and_loses_no_commit() {
    let (swarm, seen, map, _times, _run) = run_with_fault(
        "killcoord",
        "fsync = \"every-record\"\ntime_limit_s = 600\n",
        "[[faults]]\nat_round = 400\naction = \"kill\"\nrole = \"coordinator\"\n",
    );
    let log = swarm.dir.join("log");
    let (ok, report) = verify_log(&log);
    assert!(ok, "log does not verify after the kill:\n{report}");
    let records = read_log(&log).unwrap().records;
    let logged: BTreeMap<u64, Commit> = records
        .iter()
        .filter_map(|r| match r {
            Record::Round(rec) => Some((rec.round, rec.commit())),
            _ => None,
        })
        .collect();
    assert!(
        seen.len() > 400,
        "the observer saw only {} commits",
        seen.len()
    );
    for (round, commit) in &seen {
        assert_eq!(
            logged.get(round),
            Some(commit),
            "commit of round {round} was received but is not in the log as sent"
        );
    }
    let restarted = swarm.log_tails().contains("resumed from the consensus log");
    let coord_log =
        std::fs::read_to_string(swarm.dir.join("logs/coordinator.log")).unwrap_or_default();
    assert!(
        restarted || coord_log.contains("resumed from the consensus log"),
        "the coordinator was not restarted from its log:\n{coord_log}"
    );
    let s = swarm.summary().unwrap();
    for a in s["agents"].as_array().unwrap() {
        assert_eq!(a["reached_goal"], true, "{a}");
    }
    assert_eq!(s["collisions"], 0, "{s}");
    // Agent 0's neural map reached the observer through shared memory: one f32 per cell,
    // the header describing it, full activation at its target.
    let (h, at_target, len) = map.expect("a neural-map snapshot of agent 0");
    assert_eq!((h.agent, h.width, h.height), (0, 32, 32), "{h:?}");
    assert_eq!(len, 32 * 32);
    assert!(h.iterations > 0, "{h:?}");
    assert!(
        (at_target - 1.0).abs() < 1e-6,
        "target activation {at_target}"
    );
    println!(
        "{} commits observed, {} rounds logged, all present",
        seen.len(),
        logged.len()
    );
}

/// A frozen (SIGSTOP) Raft leader of three coordinator replicas: the two others elect a new
/// leader and the rounds go on; continued, the old leader finds a later term and stops
/// deciding (it exits as deposed, or the hang watch has killed it), and comes back as a
/// follower. Every commit the observer saw is one the cluster committed, and every replica's
/// log holds the same rounds.
#[test]
fn a_frozen_leader_is_replaced_and_steps_down_when_continued() {
    let (swarm, seen, _map, _times, _run) = run_with_fault(
        "freezeleader",
        "replicas = 3\ntime_limit_s = 600\n",
        "[[faults]]\nat_round = 300\naction = \"freeze\"\nfor_s = 1.5\nrole = \"coordinator\"\n",
    );
    let rounds = check_replicas(&swarm, &seen, &[1, 2, 3], true);
    let terms: std::collections::BTreeSet<u32> = seen.values().map(|c| c.term).collect();
    assert!(terms.len() >= 2, "commits of one term only: {terms:?}");
    let events = std::fs::read_to_string(swarm.dir.join("events.jsonl")).unwrap();
    let frozen = events
        .lines()
        .find(|l| l.contains("\"SIGSTOP\""))
        .and_then(|l| l.split("\"node\":\"").nth(1))
        .and_then(|r| r.split('"').next())
        .expect("the leader was frozen")
        .to_string();
    assert!(
        events
            .lines()
            .any(|l| l.contains("\"exited\"") && l.contains(&format!("\"{frozen}\""))),
        "the frozen leader {frozen} never stepped down:\n{events}"
    );
    println!(
        "{} commits observed in terms {terms:?}, {} rounds on every replica",
        seen.len(),
        rounds
    );
}

/// The checks of a run with `n` replicas: every robot home without a collision, every
/// replica's log verifies, every published round is committed as published on every replica
/// (the term aside: a new leader resends with its own), the replicas hold the same rounds, and
/// with `new_term` a later term than the first decided some. Returns the rounds.
fn check_replicas(
    swarm: &SwarmRun,
    seen: &BTreeMap<u64, Commit>,
    ids: &[u64],
    new_term: bool,
) -> usize {
    use hnav_runtime::consensus_log::{read_decided, read_log as raw, resolve};
    let s = swarm.summary().unwrap();
    for a in s["agents"].as_array().unwrap() {
        assert_eq!(a["reached_goal"], true, "{a}\n{}", swarm.log_tails());
    }
    assert_eq!(s["collisions"], 0, "{s}");
    let (ok, report) = verify_log(&swarm.dir.join("log"));
    assert!(ok, "a replica's log does not verify:\n{report}");
    let mut logs = Vec::new();
    for &id in ids {
        let dir = swarm.dir.join("log").join(id.to_string());
        let decided: BTreeMap<u64, Commit> = read_decided(&dir)
            .unwrap()
            .records
            .iter()
            .filter_map(|r| match r {
                Record::Round(rec) => Some((rec.round, rec.commit())),
                _ => None,
            })
            .collect();
        for (round, commit) in seen {
            let mut logged = decided.get(round).cloned();
            if let Some(l) = &mut logged {
                l.term = commit.term;
            }
            assert!(
                logged.as_ref() == Some(commit),
                "replica {id}: round {round} was published but not committed as sent"
            );
        }
        let resolved = resolve(&dir, raw(&dir).unwrap().records).unwrap();
        let top = resolved.entries.iter().map(|e| e.0).max().unwrap_or(0);
        assert!(
            !new_term || top >= 2,
            "replica {id}: no later term decided a round"
        );
        logs.push(decided);
    }
    assert!(
        logs.windows(2).all(|w| w[0] == w[1]),
        "the replicas' rounds differ"
    );
    logs[0].len()
}

/// Five replicas, two of them (1 and 2, the leader among them or not) SIGKILLed at once: the
/// other three keep a majority, and the rounds go on.
#[test]
fn five_replicas_lose_two_at_once_and_the_rounds_go_on() {
    let kill = |id: u32| {
        format!(
            "[[faults]]\nat_round = 300\naction = \"kill\"\nrole = \"coordinator\"\nindex = {id}\n"
        )
    };
    let (swarm, seen, _map, _times, _run) = run_with_fault(
        "fivelosetwo",
        "replicas = 5\ntime_limit_s = 600\n",
        &format!("{}\n{}", kill(1), kill(2)),
    );
    let rounds = check_replicas(&swarm, &seen, &[1, 2, 3, 4, 5], false);
    println!(
        "{} commits observed, {rounds} rounds on every replica",
        seen.len()
    );
}

/// Three replicas, one of them (3, the leader or not) SIGKILLed and never restarted
/// (`[restart] coordinator = { policy = "never" }`): the supervisor gives it up, and the run
/// goes on with the majority left instead of ending as one that cannot.
#[test]
fn a_replica_lost_for_good_leaves_the_majority_deciding() {
    let fault = "[restart]\ncoordinator = { policy = \"never\" }\n\n[[faults]]\nat_round = 300\n\
                 action = \"kill\"\nrole = \"coordinator\"\nindex = 3\n";
    let (swarm, seen, _map, _times, _run) =
        run_with_fault("replicalost", "replicas = 3\ntime_limit_s = 600\n", fault);
    let rounds = check_replicas(&swarm, &seen, &[1, 2], false);
    let events = std::fs::read_to_string(swarm.dir.join("events.jsonl")).unwrap();
    let gave_up: Vec<&str> = events
        .lines()
        .filter(|l| l.contains("\"coordinator-3\"") && l.contains("gave_up"))
        .collect();
    assert_eq!(gave_up.len(), 1, "{events}");
    assert!(
        gave_up[0].contains("the cluster goes on while a majority of it is left"),
        "{}",
        gave_up[0]
    );
    println!("replica 3 lost at round 300; {rounds} rounds on replicas 1 and 2");
}

/// Three replicas, two of them (1 and 2) frozen at once for 1.5 s: no majority, so nothing is
/// published from just after the freeze until one of them is back (continued, or killed as
/// hung and restarted); then the rounds resume and every robot gets home.
#[test]
fn three_replicas_without_a_majority_publish_nothing_until_one_is_back() {
    let freeze = |id: u32| {
        format!("[[faults]]\nat_round = 300\naction = \"freeze\"\nfor_s = 1.5\nrole = \"coordinator\"\nindex = {id}\n")
    };
    let (swarm, seen, _map, times, _run) = run_with_fault(
        "threelosetwo",
        "replicas = 3\ntime_limit_s = 600\n",
        &format!("{}\n{}", freeze(1), freeze(2)),
    );
    check_replicas(&swarm, &seen, &[1, 2, 3], false);
    let events = std::fs::read_to_string(swarm.dir.join("events.jsonl")).unwrap();
    let field = |line: &str, key: &str| -> Option<String> {
        let v: serde_json::Value = serde_json::from_str(line).ok()?;
        v.get(key)
            .map(|x| x.as_str().map_or_else(|| x.to_string(), str::to_string))
    };
    let frozen = |l: &&str| {
        matches!(
            field(l, "node").as_deref(),
            Some("coordinator-1" | "coordinator-2")
        )
    };
    let t = |l: &str| {
        field(l, "t_ns")
            .and_then(|t| t.parse::<u64>().ok())
            .unwrap()
    };
    let stopped = events
        .lines()
        .filter(frozen)
        .filter(|l| field(l, "signal").as_deref() == Some("SIGSTOP"))
        .map(t)
        .max()
        .expect("both replicas were frozen");
    let back = events
        .lines()
        .filter(frozen)
        .filter(|l| {
            field(l, "signal").as_deref() == Some("SIGCONT")
                || field(l, "event").as_deref() == Some("up")
        })
        .map(t)
        .filter(|&at| at > stopped)
        .min()
        .expect("a replica came back");
    // A round whose acknowledgement left before the freeze may still commit just after it.
    let quiet_from = stopped + 50_000_000;
    let published: Vec<u64> = times
        .iter()
        .filter(|&&(at, _)| at > quiet_from && at < back)
        .map(|&(_, round)| round)
        .collect();
    assert!(
        published.is_empty(),
        "rounds {published:?} published without a majority"
    );
    let after = times.iter().filter(|&&(at, _)| at > back).count();
    assert!(after > 0, "no round after the majority was back");
    println!(
        "no commit for {:.2} s without a majority; {after} commits after",
        (back - quiet_from) as f64 / 1e9
    );
}

#[test]
fn a_killed_agent_resumes_from_its_checkpoint_and_arrives() {
    let (swarm, _seen, _map, _times, _run) = run_with_fault(
        "killagent",
        "time_limit_s = 600\n",
        "[[faults]]\nat_round = 300\naction = \"kill\"\nrole = \"agent\"\nindex = 1\n",
    );
    let s = swarm.summary().unwrap();
    for a in s["agents"].as_array().unwrap() {
        assert_eq!(a["reached_goal"], true, "{a}\n{}", swarm.log_tails());
    }
    assert_eq!(s["collisions"], 0, "{s}");
    let records = read_log(swarm.dir.join("log")).unwrap().records;
    let lifecycle = records
        .iter()
        .filter(|r| matches!(r, Record::Lifecycle(l) if l.index == 1))
        .count();
    assert!(
        lifecycle >= 2,
        "agent 1's death and restart are not in the log"
    );
}

#[test]
fn sigint_stops_the_run_politely_and_leaves_nothing_behind() {
    use hnav_tests::swarm::wait_for_ps;
    use nix::sys::signal::Signal;
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let mut run = TestRun::new("sigint");
    let scenario = repo_root().join("scenarios/random-32-32-10.toml");
    let registry = tmp.path().join("runs");
    let mut swarm = SwarmRun::start(
        &mut run,
        &scenario,
        &tmp.path().join("out"),
        &registry,
        &["--mode", "realtime"],
    )
    .expect("hnav run starts");
    let listed = wait_for_ps(&registry, run.run.as_str(), Duration::from_secs(60), |r| {
        r["processes"].as_array().is_some_and(|p| p.len() == 10)
    })
    .expect("the run is listed");
    let pids: Vec<i32> = listed["processes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["pid"].as_i64().unwrap() as i32)
        .collect();
    // Interrupt a run under way: wait (bounded) until rounds are being logged.
    let seg = swarm.dir.join("log/seg-00000000.hlog");
    let deadline = Instant::now() + Duration::from_secs(60);
    while std::fs::metadata(&seg).map_or(0, |m| m.len()) < 4096 {
        assert!(
            Instant::now() < deadline,
            "no rounds logged within 60 s\n{}",
            swarm.log_tails()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    swarm.peer.signal(Signal::SIGINT).unwrap();
    let status = swarm.finish(Duration::from_secs(60)).expect("stops");
    assert_eq!(status.code(), Some(1), "interrupted runs exit 1: {status}");
    let s = swarm.summary().expect("a summary is still written");
    assert_eq!(s["end"], "stopped", "{s}");
    for pid in pids {
        let alive = nix::sys::signal::kill(nix::unistd::Pid::from_raw(pid), None).is_ok();
        assert!(!alive, "process {pid} outlived the supervisor");
    }
    assert!(
        hnav_runtime::transport::run_shm_files(&run.run).is_empty(),
        "shared memory left behind"
    );
    let (ok, report) = verify_log(&swarm.dir.join("log"));
    assert!(ok, "{report}");
}
