//! What the restart tests share: scenarios derived from the demo, a run through `hnav run`,
//! an observer of every robot's odometry, and the consensus log's records.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::ExitStatus;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use hnav_runtime::consensus_log::{read_log, Record};
use hnav_runtime::msg::{LifecycleEvent, Odometry, Role};
use hnav_runtime::topics;
use hnav_runtime::transport::{RunId, Transport};
use hnav_tests::swarm::{repo_root, verify_log, SwarmRun};
use hnav_tests::TestRun;

/// Robots of the demo scenario.
pub const AGENTS: usize = 6;

/// The demo scenario with `replace` applied and `extra` appended, written to `dir/name.toml`.
pub fn demo(dir: &Path, name: &str, replace: &[(&str, &str)], extra: &str) -> PathBuf {
    let mut text = std::fs::read_to_string(repo_root().join("scenarios/demo.toml")).unwrap();
    for (from, to) in replace {
        assert!(text.contains(from), "the demo scenario has no {from:?}");
        text = text.replace(from, to);
    }
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, format!("{text}\n{extra}\n")).unwrap();
    path
}

/// The demo with every robot at 2 cells/s, so that a realtime run takes seconds, not a
/// minute.
pub const FAST: [(&str, &str); 2] = [
    ("speed = 0.5", "speed = 2.0"),
    ("speed = 1.5", "speed = 2.0"),
];

/// A finished run: the supervisor's exit, its directory, and what the observer saw.
pub struct Finished {
    pub swarm: SwarmRun,
    pub status: ExitStatus,
    pub odometry: Vec<Vec<Odometry>>,
    pub wall: Duration,
    /// Kept so that the run's shared memory is cleaned when the test ends.
    pub run: TestRun,
}

impl Finished {
    pub fn summary(&self) -> serde_json::Value {
        self.swarm.summary().unwrap()
    }

    pub fn records(&self) -> Vec<Record> {
        read_log(self.swarm.dir.join("log")).unwrap().records
    }

    /// `(round, role, index, event, restarts)` of every lifecycle record.
    pub fn lifecycle(&self) -> Vec<(u64, Role, u32, LifecycleEvent, u32)> {
        self.records()
            .iter()
            .filter_map(|r| match r {
                Record::Lifecycle(l) => Some((
                    l.round,
                    Role::from_u8(l.role)?,
                    l.index,
                    LifecycleEvent::from_u8(l.event)?,
                    l.restarts,
                )),
                _ => None,
            })
            .collect()
    }

    /// The log verifies, and the summary's robots at goal are the end record's.
    pub fn check_log_and_summary(&self) {
        let (ok, report) = verify_log(&self.swarm.dir.join("log"));
        assert!(ok, "log does not verify:\n{report}");
        let end = self
            .records()
            .iter()
            .find_map(|r| match r {
                Record::End(e) => Some(*e),
                _ => None,
            })
            .expect("the log is closed");
        let s = self.summary();
        let at_goal = s["agents"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|a| a["reached_goal"] == true)
            .count();
        assert_eq!(
            at_goal, end.at_goal as usize,
            "summary {s} vs log end {end:?}"
        );
        assert_eq!(s["end"], end.reason.name(), "{s}");
    }

    /// Each robot's odometry, as the observer saw it, never goes back: its period never
    /// decreases, a period seen twice has the same ticks, and between two readings the ticks
    /// move no more than the wheels can turn in that time (a counter started over would jump
    /// back by the whole distance driven).
    pub fn check_odometry_continuous(&self) {
        for (i, seen) in self.odometry.iter().enumerate() {
            assert!(
                seen.len() > 10,
                "robot {i}: only {} readings seen",
                seen.len()
            );
            for w in seen.windows(2) {
                let (a, b) = (w[0], w[1]);
                assert!(
                    b.period >= a.period,
                    "robot {i}: period {} after {}",
                    b.period,
                    a.period
                );
                let gap = (b.period - a.period).max(1) as i64;
                // 20 rad/s for 10 ms is 1.4 ticks of 42 per revolution.
                let bound = 2 * gap + 1;
                for (x, y) in [(a.ticks_left, b.ticks_left), (a.ticks_right, b.ticks_right)] {
                    assert!(
                        (y - x).abs() <= bound,
                        "robot {i}: ticks {x} -> {y} from period {} to {}",
                        a.period,
                        b.period
                    );
                }
                if a.period == b.period {
                    assert_eq!((a.ticks_left, a.ticks_right), (b.ticks_left, b.ticks_right));
                }
            }
        }
    }

    /// The log of process `node` (`sim`, `coordinator`, `agent-3`).
    pub fn process_log(&self, node: &str) -> String {
        std::fs::read_to_string(self.swarm.dir.join(format!("logs/{node}.log"))).unwrap_or_default()
    }
}

/// Runs `scenario` through `hnav run --mode MODE` into `dir/out`, with an observer of every
/// robot's odometry joined before anything starts; waits at most `bound`.
pub fn run(tag: &str, scenario: &Path, dir: &Path, mode: &str, bound: Duration) -> Finished {
    let mut run = TestRun::new(tag);
    let observer = OdometryObserver::start(&run.run, AGENTS);
    let started = Instant::now();
    let mut swarm = SwarmRun::start(
        &mut run,
        scenario,
        &dir.join("out"),
        &dir.join("runs"),
        &["--mode", mode],
    )
    .expect("hnav run starts");
    let status = swarm.finish(bound);
    let wall = started.elapsed();
    // Before anything can fail: the observer's node must be gone for the run's clean-up.
    let odometry = observer.finish();
    let status = status.expect("hnav run ends within its bound");
    Finished {
        swarm,
        status,
        odometry,
        wall,
        run,
    }
}

/// Every odometry reading of every robot, in the order they came, from a thread of the test.
struct OdometryObserver {
    seen: Arc<Mutex<Vec<Vec<Odometry>>>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl OdometryObserver {
    fn start(run: &RunId, robots: usize) -> Self {
        let seen = Arc::new(Mutex::new(vec![Vec::new(); robots]));
        let stop = Arc::new(AtomicBool::new(false));
        let (seen2, stop2, run) = (seen.clone(), stop.clone(), run.clone());
        let (ready_tx, ready_rx) = std::sync::mpsc::channel();
        let thread = std::thread::spawn(move || {
            let t = Transport::builder(&run)
                .node_name("odom-observer")
                .create()
                .unwrap();
            // One robot a process (the restart scenarios'): `odom/<i>` is robot i's.
            let rx: Vec<topics::OdometryReceiver> = (0..robots)
                .map(|i| {
                    t.slice_receiver(&topics::odometry(i), topics::state_qos())
                        .unwrap()
                })
                .collect();
            let waiter = t.waiter().unwrap();
            let _attached: Vec<_> = rx.iter().map(|r| waiter.attach(r).unwrap()).collect();
            ready_tx.send(()).unwrap();
            while !stop2.load(Ordering::Relaxed) {
                for (i, r) in rx.iter().enumerate() {
                    let _ = r.drain_pending(|_, os| seen2.lock().unwrap()[i].extend_from_slice(os));
                }
                // Bounded, so that the thread sees `stop`.
                let _ = waiter.wait(Some(Instant::now() + Duration::from_millis(100)));
            }
        });
        ready_rx
            .recv_timeout(Duration::from_secs(30))
            .expect("observer up");
        Self {
            seen,
            stop,
            thread: Some(thread),
        }
    }

    fn finish(mut self) -> Vec<Vec<Odometry>> {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            t.join().expect("observer thread");
        }
        std::mem::take(&mut *self.seen.lock().unwrap())
    }
}
