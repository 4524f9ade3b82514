//! Hang detection on whole runs: a process frozen with SIGSTOP for good is declared hung
//! within its deadline, SIGKILLed and restarted (or, for the sim, which is not restarted, the
//! run ends as one that cannot go on); a freeze continued before its deadline is no hang; a
//! paused supervisor kills nobody.
//!
//! In its own test binary because it stops and kills processes. The tests take turns (one
//! lock): each runs a swarm against 1 s hang deadlines, and several swarms at once on a
//! 2-core machine would stretch the very stalls they measure.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use hnav_runtime::clock::monotonic_ns;
use hnav_runtime::msg::{CommitView, ConflictKind, Pose, Progress};
use hnav_runtime::topics;
use hnav_runtime::transport::{RunId, Transport};
use hnav_tests::swarm::{verify_log, wait_for_ps, SwarmRun};
use hnav_tests::TestRun;
use nix::sys::signal::{kill, Signal};
use nix::unistd::Pid;

/// The hang deadline of every role in these tests' scenarios.
const HANG: Duration = Duration::from_millis(1000);
/// The heartbeat of these tests' scenarios.
const BEAT: Duration = Duration::from_millis(50);
/// How much later than its deadline a hang may be declared: the supervisor's wake-up and a
/// busy machine's scheduling.
const MARGIN: Duration = Duration::from_millis(500);
/// Bound on a whole run.
const RUN_BOUND: Duration = Duration::from_secs(120);

/// No decision for an agent in a commit.
const NONE: u8 = u8::MAX;

static TURN: Mutex<()> = Mutex::new(());

fn turn() -> MutexGuard<'static, ()> {
    TURN.lock().unwrap_or_else(|e| e.into_inner())
}

/// Two robots on a 7 x 3 room: agent 0 drives slowly from [3, 1] to [3, 0]; agent 1 from
/// [1, 1] to [6, 1], through agent 0's start cell, so it meets agent 0 while that one is
/// frozen.
fn scenario(dir: &Path, mode: &str, agent_hang: Duration) -> PathBuf {
    let text = format!(
        "name = \"hang\"\n\
         [map]\nrows = [\".......\", \".......\", \".......\"]\n\
         [sim]\nclock = \"{mode}\"\nseed = 3\n\
         [coordinator]\nrules = \"dissertation\"\ntime_limit_s = 120\n\
         [health]\nheartbeat_ms = {}\nagent_hang_ms = {}\ncoordinator_hang_ms = {h}\n\
         sim_hang_ms = {h}\n\
         [[agents]]\nstart = [3, 1]\ngoal = [3, 0]\nspeed = 0.3\n\
         [[agents]]\nstart = [1, 1]\ngoal = [6, 1]\nspeed = 1.5\n",
        BEAT.as_millis(),
        agent_hang.as_millis(),
        h = HANG.as_millis(),
    );
    let path = dir.join("hang.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// When a commit was read, its round, and agents 0 and 1's (verdict, conflict kind).
type SeenCommit = (u64, u64, [(u8, u8); 2]);

/// What a test's observer thread saw on the run's topics, each stamped with
/// [`monotonic_ns`] when it was read.
#[derive(Default)]
struct Seen {
    /// Commit round, and agent 0's and agent 1's verdict and conflict kind ([`NONE`]: no
    /// decision, the agent asked for nothing).
    commits: Vec<SeenCommit>,
    /// Robot 0's pose.
    poses: Vec<(u64, Pose)>,
    round: u64,
}

struct Observer {
    seen: Arc<Mutex<Seen>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Observer {
    fn start(run: &RunId) -> Observer {
        let seen = Arc::new(Mutex::new(Seen::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let (seen2, stop2, run) = (seen.clone(), stop.clone(), run.clone());
        let (ready_tx, ready_rx) = std::sync::mpsc::channel();
        let thread = std::thread::spawn(move || {
            let t = Transport::builder(&run)
                .node_name("observer")
                .handle_signals(false)
                .create()
                .unwrap();
            let commits: topics::CommitReceiver = t
                .slice_receiver(topics::COMMIT, topics::commit_qos(2))
                .unwrap();
            let truth: topics::TruthReceiver = t
                .slice_receiver(topics::TRUTH, topics::truth_qos())
                .unwrap();
            let progress = t
                .receiver::<Progress>(topics::PROGRESS, topics::progress_qos())
                .unwrap();
            let waiter = t.waiter().unwrap();
            let _a = waiter.attach(&commits).unwrap();
            let _b = waiter.attach(&truth).unwrap();
            let _c = waiter.attach(&progress).unwrap();
            ready_tx.send(()).unwrap();
            while !stop2.load(Ordering::Relaxed) {
                let now = monotonic_ns();
                let mut s = seen2.lock().unwrap_or_else(|e| e.into_inner());
                let _ = commits.drain_pending(|h, d| {
                    let c = CommitView::new(h, d);
                    let of = |agent: u32| {
                        c.decisions()
                            .iter()
                            .find(|d| d.agent == agent)
                            .map_or((NONE, NONE), |d| (d.verdict, d.kind))
                    };
                    s.commits.push((now, c.round(), [of(0), of(1)]));
                    s.round = s.round.max(c.round());
                });
                let _ = truth.drain_pending(|_, poses| s.poses.push((now, poses[0])));
                let _ = progress.drain_pending(|p| s.round = s.round.max(p.round));
                drop(s);
                let _ = waiter.wait(Some(Instant::now() + Duration::from_millis(100)));
            }
        });
        ready_rx
            .recv_timeout(Duration::from_secs(30))
            .expect("the observer subscribes");
        Observer {
            seen,
            stop,
            thread: Some(thread),
        }
    }

    /// Waits up to `timeout` until `what` holds for what was seen.
    fn wait_for(&self, timeout: Duration, what: impl Fn(&Seen) -> bool) -> bool {
        let deadline = Instant::now() + timeout;
        while Instant::now() < deadline {
            if what(&self.seen.lock().unwrap_or_else(|e| e.into_inner())) {
                return true;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        false
    }
}

impl Drop for Observer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// One run of a test: the swarm, its registry and its observer.
struct Case {
    _tmp: tempfile::TempDir,
    swarm: SwarmRun,
    registry: PathBuf,
    observer: Observer,
    // Dropped last: kills what is left and purges the run's shared memory.
    run: TestRun,
}

impl Case {
    fn start(tag: &str, mode: &str) -> Case {
        Self::start_with(tag, mode, HANG)
    }

    /// [`Case::start`] with another agent hang deadline.
    fn start_with(tag: &str, mode: &str, agent_hang: Duration) -> Case {
        let tmp = tempfile::tempdir().unwrap();
        let mut run = TestRun::new(tag);
        let registry = tmp.path().join("runs");
        let swarm = SwarmRun::start(
            &mut run,
            &scenario(tmp.path(), mode, agent_hang),
            &tmp.path().join("out"),
            &registry,
            &[],
        )
        .expect("hnav run starts");
        let observer = Observer::start(&run.run);
        Case {
            _tmp: tmp,
            swarm,
            registry,
            observer,
            run,
        }
    }

    /// The pid of `node` (`agent-0`, `coordinator`, `sim`) once every process runs.
    fn pid(&self, node: &str) -> i32 {
        let run = wait_for_ps(&self.registry, self.run.run.as_str(), RUN_BOUND, |r| {
            r["processes"]
                .as_array()
                .is_some_and(|p| p.len() == 4 && p.iter().all(|p| p["state"] == "running"))
        })
        .unwrap();
        let p = run["processes"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| {
                let name = match p["role"].as_str().unwrap() {
                    "agent" => format!("agent-{}", p["index"]),
                    other => other.to_string(),
                };
                name == node
            })
            .unwrap_or_else(|| panic!("no {node} in {run}"));
        p["pid"].as_i64().unwrap() as i32
    }

    /// Waits until the coordinator has committed `round`.
    fn until_round(&self, round: u64) {
        assert!(
            self.observer.wait_for(RUN_BOUND, |s| s.round >= round),
            "round {round} not reached\n{}",
            self.swarm.log_tails()
        );
    }

    /// The run's `events.jsonl`, one JSON value per line.
    fn events(&self) -> Vec<serde_json::Value> {
        std::fs::read_to_string(self.swarm.dir.join("events.jsonl"))
            .unwrap_or_default()
            .lines()
            .filter_map(|l| serde_json::from_str(l).ok())
            .collect()
    }

    /// Waits (bounded) for the `hung` event of `node` and returns its time.
    fn hung_at(&self, node: &str, within: Duration) -> u64 {
        let deadline = Instant::now() + within;
        loop {
            let found = self
                .events()
                .into_iter()
                .find(|e| e["event"] == "hung" && e["node"] == node);
            if let Some(e) = found {
                return e["t_ns"].as_u64().unwrap();
            }
            assert!(
                Instant::now() < deadline,
                "{node} not declared hung within {within:?}: {:?}\n{}",
                self.events(),
                self.swarm.log_tails()
            );
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// Waits for the run's end and returns its exit code.
    fn finish(&mut self) -> i32 {
        let status = self.swarm.finish(RUN_BOUND).unwrap();
        status.code().unwrap_or(-1)
    }

    /// Ends the run successfully: exit 0, every robot at its goal, an intact log.
    fn finishes_at_goal(&mut self) {
        let code = self.finish();
        assert_eq!(code, 0, "{:?}\n{}", self.events(), self.swarm.log_tails());
        let s = self.swarm.summary().unwrap();
        assert_eq!(s["collisions"], 0, "{s}");
        assert!(
            s["agents"]
                .as_array()
                .unwrap()
                .iter()
                .all(|a| a["reached_goal"] == true),
            "{s}"
        );
        let (ok, out) = verify_log(&self.swarm.dir.join("log"));
        assert!(ok, "{out}");
    }

    /// The nodes of the `event` entries in the journal.
    fn nodes_with(&self, event: &str) -> Vec<String> {
        self.events()
            .into_iter()
            .filter(|e| e["event"] == event)
            .map(|e| e["node"].as_str().unwrap_or_default().to_string())
            .collect()
    }
}

fn signal(pid: i32, s: Signal) {
    kill(Pid::from_raw(pid), s).unwrap();
}

/// Waits (bounded) until `pid`, just continued, is asleep again: it has handled its wake-up
/// and blocks in its next wait.
fn until_asleep(pid: i32) {
    let deadline = Instant::now() + Duration::from_secs(10);
    while Instant::now() < deadline {
        let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
        // The state follows the parenthesised command name.
        let state = stat
            .rsplit(')')
            .next()
            .and_then(|r| r.split_whitespace().next());
        if state == Some("S") {
            return;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    panic!("pid {pid} did not go back to sleep");
}

/// Freezes `node` for good once round 20 is committed, checks it is declared hung within
/// its deadline and returns (case, freeze time, hung time).
fn freeze_for_good(tag: &str, mode: &str, node: &str) -> (Case, u64, u64) {
    let case = Case::start(tag, mode);
    let pid = case.pid(node);
    case.until_round(20);
    let frozen = monotonic_ns();
    signal(pid, Signal::SIGSTOP);
    let hung = case.hung_at(node, HANG + MARGIN + Duration::from_secs(5));
    let took = Duration::from_nanos(hung.saturating_sub(frozen));
    eprintln!(
        "{mode} {node}: freeze -> hung declared {:.0} ms (deadline {} ms, beat {} ms)",
        took.as_secs_f64() * 1e3,
        HANG.as_millis(),
        BEAT.as_millis()
    );
    // The last beat came at most one beat (plus a scheduling delay) before the freeze.
    assert!(took + 2 * BEAT >= HANG, "declared after only {took:?}");
    assert!(took <= HANG + MARGIN, "declared after {took:?}");
    (case, frozen, hung)
}

#[test]
fn a_realtime_agent_frozen_for_good_brakes_is_standing_then_hung_killed_and_restarted() {
    let _turn = turn();
    // A longer deadline here, so that agent 1 reaches agent 0's cell while agent 0 is frozen.
    let agent_hang = 3 * HANG;
    let mut case = Case::start_with("hangrt", "realtime", agent_hang);
    let pid = case.pid("agent-0");
    // Freeze it while its robot moves (turns toward its goal or drives).
    let moving = case.observer.wait_for(RUN_BOUND, |s| {
        s.poses.windows(2).last().is_some_and(|w| w[0].1 != w[1].1)
    });
    assert!(moving, "robot 0 never moved\n{}", case.swarm.log_tails());
    let frozen = monotonic_ns();
    signal(pid, Signal::SIGSTOP);
    // Its robot brakes (the sim's watchdog) well before the hang deadline: two poses 200 ms
    // apart, both after the freeze, are the same.
    let still = case.observer.wait_for(agent_hang, |s| {
        let after: Vec<&(u64, Pose)> = s.poses.iter().filter(|p| p.0 > frozen).collect();
        after.last().is_some_and(|last| {
            after
                .iter()
                .any(|p| last.0 - p.0 >= 200_000_000 && p.1 == last.1)
        })
    });
    let hung = case.hung_at("agent-0", agent_hang + MARGIN + Duration::from_secs(5));
    assert!(still, "robot 0 did not stop while its agent was frozen");
    let took = Duration::from_nanos(hung - frozen);
    eprintln!(
        "realtime agent-0: freeze -> hung declared {:.0} ms (deadline {} ms)",
        took.as_secs_f64() * 1e3,
        agent_hang.as_millis()
    );
    assert!(
        took + 2 * BEAT >= agent_hang && took <= agent_hang + MARGIN,
        "{took:?}"
    );
    {
        // Meanwhile rounds closed without it (no candidate, no decision), and agent 1, driving into
        // its cell, was refused by a standing robot (conflict type d).
        let s = case.observer.seen.lock().unwrap_or_else(|e| e.into_inner());
        let during: Vec<_> = s
            .commits
            .iter()
            .filter(|c| c.0 > frozen + 2 * BEAT.as_nanos() as u64 && c.0 < hung)
            .collect();
        assert!(
            during.len() >= 5,
            "only {} rounds while frozen",
            during.len()
        );
        assert!(
            during.iter().all(|c| c.2[0].0 == NONE),
            "agent 0 decided while frozen: {during:?}"
        );
        assert!(
            during
                .iter()
                .any(|c| c.2[1].1 == ConflictKind::StableCell as u8),
            "agent 1 was never refused by the standing robot: {during:?}"
        );
    }
    case.finishes_at_goal();
    assert_eq!(case.nodes_with("up"), ["agent-0"], "{:?}", case.events());
}

#[test]
fn a_lockstep_agent_frozen_for_good_is_hung_killed_and_restarted() {
    let _turn = turn();
    let (mut case, _, _) = freeze_for_good("hangls", "lockstep", "agent-0");
    case.finishes_at_goal();
    let killed = case
        .events()
        .into_iter()
        .any(|e| e["event"] == "signalled" && e["node"] == "agent-0" && e["fault"].is_null());
    assert!(killed, "{:?}", case.events());
    assert_eq!(case.nodes_with("up"), ["agent-0"], "{:?}", case.events());
}

#[test]
fn a_freeze_continued_before_the_deadline_is_no_hang() {
    let _turn = turn();
    let mut case = Case::start("hangcont", "lockstep");
    let pid = case.pid("agent-0");
    case.until_round(20);
    signal(pid, Signal::SIGSTOP);
    std::thread::sleep(HANG / 3);
    signal(pid, Signal::SIGCONT);
    case.finishes_at_goal();
    assert!(case.nodes_with("hung").is_empty(), "{:?}", case.events());
    assert!(case.nodes_with("exited").is_empty(), "{:?}", case.events());
}

#[test]
fn a_frozen_coordinator_is_hung_killed_and_restarted() {
    let _turn = turn();
    let (mut case, _, _) = freeze_for_good("hangco", "lockstep", "coordinator");
    case.finishes_at_goal();
    assert_eq!(
        case.nodes_with("up"),
        ["coordinator"],
        "{:?}",
        case.events()
    );
}

/// A frozen sim is declared hung and killed like any process; the sim restarts by default
/// (from its checkpoint), so the run finishes.
#[test]
fn a_frozen_sim_is_hung_killed_and_restarted() {
    let _turn = turn();
    let (mut case, _, _) = freeze_for_good("hangsim", "lockstep", "sim");
    case.finishes_at_goal();
    assert_eq!(case.nodes_with("hung"), ["sim"], "{:?}", case.events());
    assert_eq!(case.nodes_with("up"), ["sim"], "{:?}", case.events());
}

/// Ctrl-Z then `fg` (here SIGSTOP and SIGCONT) of the supervisor alone: its children kept
/// beating, and it judges them by their beats' own times.
#[test]
fn a_supervisor_paused_past_the_deadline_kills_nobody() {
    let _turn = turn();
    let mut case = Case::start("hangsup", "lockstep");
    case.pid("agent-0");
    case.until_round(20);
    let sup = case.swarm.peer.pid as i32;
    signal(sup, Signal::SIGSTOP);
    std::thread::sleep(HANG * 2);
    signal(sup, Signal::SIGCONT);
    case.finishes_at_goal();
    assert!(case.nodes_with("hung").is_empty(), "{:?}", case.events());
}

/// The whole run paused (children first, then the supervisor) past the deadline and
/// continued supervisor first: the children's last beats are as old as the pause, but the
/// supervisor sees that it woke far later than it asked to and gives everyone a fresh
/// deadline instead of killing them all.
#[test]
fn a_whole_run_paused_past_the_deadline_kills_nobody() {
    let _turn = turn();
    let mut case = Case::start("hangall", "lockstep");
    let nodes = ["sim", "coordinator", "agent-0", "agent-1"];
    let pids: Vec<i32> = nodes.iter().map(|n| case.pid(n)).collect();
    case.until_round(20);
    let sup = case.swarm.peer.pid as i32;
    for &p in &pids {
        signal(p, Signal::SIGSTOP);
    }
    signal(sup, Signal::SIGSTOP);
    std::thread::sleep(HANG * 2);
    signal(sup, Signal::SIGCONT);
    // The supervisor looks at its children's stale beats before they beat again.
    until_asleep(sup);
    for &p in &pids {
        signal(p, Signal::SIGCONT);
    }
    case.finishes_at_goal();
    assert!(case.nodes_with("hung").is_empty(), "{:?}", case.events());
}
