//! Two real processes over the HNAV transport.

use std::time::Duration;

use hnav_runtime::msg::Candidate;
use hnav_runtime::transport::{run_shm_files, NodeLiveness, Qos, Transport};
use hnav_tests::{pattern, TestRun};

const PEER: &str = env!("CARGO_BIN_EXE_hnav-test-peer");
const STEP: Duration = Duration::from_secs(60);

#[test]
fn one_hundred_thousand_candidates_arrive_in_order_through_a_waitset() {
    let mut run = TestRun::new("cand");
    let count = 100_000u64;
    let mut rx = run
        .spawn(PEER, &["recv-candidates", &count.to_string()])
        .unwrap();
    rx.wait_for_line("READY", STEP).unwrap();
    let mut tx = run
        .spawn(PEER, &["pub-candidates", &count.to_string()])
        .unwrap();
    let report = rx
        .wait_for_line("RECEIVED", Duration::from_secs(300))
        .unwrap();
    assert!(rx.wait_exit(STEP).unwrap().success(), "receiver failed");
    assert!(tx.wait_exit(STEP).unwrap().success(), "sender failed");

    // RECEIVED <n> wakeups=<w> empty=<e> ms=<t>
    let field = |key: &str| -> u64 {
        report
            .split_whitespace()
            .find_map(|f| f.strip_prefix(key))
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("no {key} in {report:?}"))
    };
    let received: u64 = report.split_whitespace().nth(1).unwrap().parse().unwrap();
    assert_eq!(received, count);
    // The receiver only looks for samples when its `Waiter` wakes it: every wake-up drains the
    // queue, so wake-ups are at most one per sample and never far more than samples.
    let wakeups = field("wakeups=");
    assert!(wakeups >= 1 && wakeups <= count, "wakeups {wakeups}");
    assert!(field("empty=") <= wakeups);
}

#[test]
fn a_four_mib_slice_crosses_processes_written_in_place() {
    let mut run = TestRun::new("slice");
    let len = 4 * 1024 * 1024 / 4;
    let mut rx = run.spawn(PEER, &["recv-slice", &len.to_string()]).unwrap();
    rx.wait_for_line("READY", STEP).unwrap();
    let mut tx = run.spawn(PEER, &["pub-slice", &len.to_string()]).unwrap();
    let line = rx.wait_for_line("CHECKSUM", STEP).unwrap();
    assert!(rx.wait_exit(STEP).unwrap().success());
    assert!(tx.wait_exit(STEP).unwrap().success());
    let got = u64::from_str_radix(line.trim_start_matches("CHECKSUM ").trim(), 16).unwrap();
    assert_eq!(got, pattern::expected_checksum(len));
}

#[test]
fn two_runs_do_not_see_each_other() {
    let a = TestRun::new("iso");
    let b = TestRun::new("iso");
    let ta = Transport::builder(&a.run).node_name("a").create().unwrap();
    let tb = Transport::builder(&b.run).node_name("b").create().unwrap();
    let tx_a = ta
        .sender::<Candidate>("candidates", Qos::reliable(2))
        .unwrap();
    let rx_a = ta
        .receiver::<Candidate>("candidates", Qos::reliable(2))
        .unwrap();
    let rx_b = tb
        .receiver::<Candidate>("candidates", Qos::reliable(2))
        .unwrap();
    assert_eq!(
        tx_a.send(Candidate::default()).unwrap(),
        1,
        "only run a's subscriber"
    );
    assert_eq!(rx_a.drain(|_| {}).unwrap(), 1);
    assert_eq!(rx_b.drain(|_| {}).unwrap(), 0);

    let services_a = ta.services().unwrap();
    let services_b = tb.services().unwrap();
    assert!(services_a
        .iter()
        .all(|s| s.starts_with(&format!("hnav/{}/", a.run))));
    assert!(services_b
        .iter()
        .all(|s| s.starts_with(&format!("hnav/{}/", b.run))));
    assert!(!services_a.is_empty() && !services_b.is_empty());

    let nodes_b = tb.nodes().unwrap();
    assert_eq!(nodes_b.len(), 1);
    assert_eq!(nodes_b[0].name, "b");
    assert_eq!(nodes_b[0].liveness, NodeLiveness::Alive);

    assert!(run_shm_files(&a.run)
        .iter()
        .all(|p| !p.to_string_lossy().contains(b.run.as_str())));
}

#[test]
fn iceoryx2_logs_go_through_tracing_without_config_noise() {
    let run = TestRun::new("quiet");
    let out = std::process::Command::new(PEER)
        .args(["--run", run.run.as_str(), "probe"])
        .env_remove("RUST_LOG")
        .env_remove("HNAV_LOG")
        .output()
        .unwrap();
    assert!(out.status.success());
    assert_eq!(String::from_utf8_lossy(&out.stdout).trim(), "READY");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("No config file"), "stderr: {stderr}");
    assert!(
        stderr.trim().is_empty(),
        "a clean run prints nothing on stderr: {stderr}"
    );

    // With iceoryx2's debug logs enabled they arrive as tracing events, with tracing's format.
    let out = std::process::Command::new(PEER)
        .args(["--run", run.run.as_str(), "probe"])
        .env("HNAV_LOG", "iceoryx2_bb_loggers=trace")
        .output()
        .unwrap();
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("iceoryx2_bb_loggers::tracing"),
        "iceoryx2 logs should be tracing events: {stderr}"
    );
}

#[test]
fn qos_sized_from_the_swarm_admits_every_agent_as_a_publisher() {
    let run = TestRun::new("qos");
    let t = Transport::builder(&run.run)
        .node_name("swarm")
        .create()
        .unwrap();
    let agents = 16;
    let qos = Qos::reliable(agents);
    let rx = t.receiver::<Candidate>("candidates", qos).unwrap();
    let senders: Vec<_> = (0..agents)
        .map(|_| t.sender::<Candidate>("candidates", qos).unwrap())
        .collect();
    for (i, tx) in senders.iter().enumerate() {
        tx.send(Candidate {
            agent: i as u32,
            ..Candidate::default()
        })
        .unwrap();
    }
    let mut seen = vec![false; agents];
    rx.drain(|c| seen[c.agent as usize] = true).unwrap();
    assert!(seen.iter().all(|s| *s));
    // iceoryx2's default (two publishers per service) would have refused the third.
    let default_sized = TestRun::new("qos-default");
    let t2 = Transport::builder(&default_sized.run).create().unwrap();
    let two = Qos {
        max_publishers: 2,
        ..Qos::reliable(1)
    };
    let _a = t2.sender::<Candidate>("c", two).unwrap();
    let _b = t2.sender::<Candidate>("c", two).unwrap();
    assert!(t2.sender::<Candidate>("c", two).is_err());
}
