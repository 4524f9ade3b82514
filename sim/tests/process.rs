//! The `hnav-sim` process in lockstep: this test plays two agents over the transport (wheel
//! commands in, odometry and truth out) and checks that two runs with one seed give identical
//! Truth streams, and that a robot whose agent never sends is braked rather than waited for.

use hnav_runtime::hash::Fnv1a64;
use hnav_runtime::msg::{Truth, TruthView, WheelCommand, WheelsHeader};
use hnav_runtime::scenario::params::RobotParams;
use hnav_runtime::topics;
use hnav_runtime::transport::{purge_run, RunId, Transport};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const SIM: &str = env!("CARGO_BIN_EXE_hnav-sim");
const PERIODS: u64 = 40;

/// The x of the start cells' centres (column 1), m.
fn start_x() -> f64 {
    1.5 * RobotParams::default().cell_size_m
}

const SCENARIO: &str = r#"
name = "sim-process-test"
[map]
rows = [
  "..........",
  "..........",
  "..........",
  "..........",
]
[sim]
clock = "lockstep"
seed = 9
slip_std = 0.02
[[agents]]
start = [1, 1]
goal = [8, 1]
[[agents]]
start = [1, 2]
goal = [8, 2]
"#;

fn hash(h: &mut Fnv1a64, t: &Truth) {
    h.u64(t.sim_time_ns).u64(t.period);
    h.u64((t.poses.len() as u64) << 32 | u64::from(t.collisions));
    for p in t.poses() {
        h.f64(p.x_m).f64(p.y_m).f64(p.theta_rad);
    }
}

/// One lockstep run; `agents` of the two robots are driven by this test. Returns the hash
/// of the Truth stream and the last truth.
fn run_once(tag: &str, agents: usize, scenario: &str) -> (u64, Truth) {
    let dir = std::env::temp_dir().join(format!("hnav-sim-test-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("scenario.toml");
    std::fs::write(&file, scenario).unwrap();
    let guard = RunGuard {
        run: RunId::unique(tag),
        dir,
        child: None,
    };
    drive(guard, &file, agents)
}

/// Kills the sim if it still runs and removes the run's shared memory and files, also when
/// the test fails half-way.
struct RunGuard {
    run: RunId,
    dir: std::path::PathBuf,
    child: Option<std::process::Child>,
}

impl Drop for RunGuard {
    fn drop(&mut self) {
        if let Some(child) = &mut self.child {
            if child.try_wait().ok().flatten().is_none() {
                let _ = child.kill();
                let _ = child.wait();
            }
        }
        let _ = purge_run(&self.run);
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// Plays `agents` agents against a spawned `hnav-sim` for [`PERIODS`] periods.
fn drive(mut guard: RunGuard, file: &std::path::Path, agents: usize) -> (u64, Truth) {
    let run = guard.run.clone();
    let t = Transport::builder(&run)
        .node_name("agents")
        .create()
        .unwrap();
    let q = topics::state_qos();
    // One robot a process (the scenario's default): each robot's own `wheels/<i>`, `odom/<i>`.
    let wheels: Vec<topics::WheelsSender> = (0..agents)
        .map(|i| t.slice_sender(&topics::wheels(i), 1, q).unwrap())
        .collect();
    let odom: Vec<topics::OdometryReceiver> = (0..2)
        .map(|i| t.slice_receiver(&topics::odometry(i), q).unwrap())
        .collect();
    let truth: topics::TruthReceiver = t
        .slice_receiver(topics::TRUTH, topics::truth_qos())
        .unwrap();
    let send = |period: u64| {
        for (i, tx) in wheels.iter().enumerate() {
            let k = i as f64;
            let header = WheelsHeader {
                first: i as u32,
                count: 1,
            };
            tx.send_from_fn(header, 1, |_| WheelCommand {
                period,
                agent: i as u32,
                flags: 0,
                left_rad_s: 8.0 + k,
                right_rad_s: 10.0 - k,
            })
            .unwrap();
        }
    };
    // Period 0's commands are kept as history for the sim's late-joining subscribers.
    send(0);
    let child = Command::new(SIM)
        .args(["--run", run.as_str(), "--scenario"])
        .arg(file)
        .args(["--periods", &PERIODS.to_string(), "--standalone"])
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let child = guard.child.insert(child);
    // No lost-wake-up re-check: the loop below resends the current period's commands after
    // every wake-up, and every 50 ms they would keep the sim's lockstep deadline (measured
    // from the last input) from ever passing. The 1 s deadline bounds a lost wake-up instead.
    let waiter = t.waiter().unwrap().with_recheck(None);
    let _attached = waiter.attach(&truth).unwrap();
    let (mut h, mut last, mut next) = (Fnv1a64::new(), Truth::default(), 0u64);
    let started = Instant::now();
    while next < PERIODS {
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "sim stalled at {next}"
        );
        waiter
            .wait(Some(Instant::now() + Duration::from_secs(1)))
            .unwrap();
        truth
            .drain_pending(|header, poses| {
                // In order; realtime may overwrite an unread sample (latest-only QoS), lockstep
                // cannot (the sim waits for the commands this loop sends).
                assert!(header.period >= next, "truth periods arrive in order");
                last.set(TruthView::new(header, poses));
                hash(&mut h, &last);
                next = header.period + 1;
            })
            .unwrap();
        for rx in &odom {
            rx.drain_pending(|_, _| {}).unwrap();
        }
        if next < PERIODS {
            send(next);
        }
    }
    assert!(child.wait().unwrap().success());
    // `guard`, a parameter, is dropped after every port of this function: purge then finds
    // no live node of the run.
    (h.finish(), last)
}

#[test]
fn lockstep_runs_with_one_seed_give_identical_truth_streams() {
    let (a, ta) = run_once("lockstep-a", 2, SCENARIO);
    let (b, _) = run_once("lockstep-b", 2, SCENARIO);
    assert_eq!(a, b);
    assert_eq!(ta.poses.len(), 2);
    assert!(
        ta.poses()[0].x_m > start_x(),
        "robot 0 drove: {:?}",
        ta.poses()[0]
    );
}

#[test]
fn a_robot_without_an_agent_brakes_and_does_not_stall_the_run() {
    // No publisher ever appears for robot 1, so no peer event marks it down: the deadline
    // fallback does.
    let scenario = SCENARIO.replace("[sim]\n", "[sim]\nlockstep_deadline_ms = 500\n");
    let (_, t) = run_once("lockstep-down", 1, &scenario);
    // Robot 1 never got a command: it stands at its start cell's centre.
    let c = RobotParams::default().cell_size_m;
    assert_eq!((t.poses()[1].x_m, t.poses()[1].y_m), (1.5 * c, 2.5 * c));
    assert!(t.poses()[0].x_m > start_x());
}

#[test]
fn realtime_follows_the_wall_clock() {
    let scenario = SCENARIO.replace("clock = \"lockstep\"", "clock = \"realtime\"");
    let started = Instant::now();
    let (_, t) = run_once("realtime", 2, &scenario);
    let wall = started.elapsed();
    // 40 periods of 10 ms: at least 0.4 s of wall time, and the robots moved.
    assert!(wall >= Duration::from_millis(390), "{wall:?}");
    assert_eq!(t.sim_time_ns, 400_000_000);
    assert!(t.poses()[0].x_m > start_x() && t.poses()[1].x_m > start_x());
}
