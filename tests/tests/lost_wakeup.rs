//! The lost wake-up, reproduced with two processes (`hnav-test-peer lost-wakeup-receiver`
//! and `lost-wakeup-senders`, see `hnav_tests::lost_wakeup`).
//!
//! The receiver counts *misses*: waits that ended without a notification while a sample was
//! pending. A miss after which the listener still holds the data event is iceoryx2's: a
//! notifier fired and sent the listener nothing (the race in `iceoryx2-cal` 0.10.0
//! `event/common.rs`, `Waiter::drain_events`, described in the transport's `waiter` module).
//! A miss without it would be ours: a notification consumed and its sample left unread. The
//! tests run each configuration without the re-check (raw misses, printed; none may be ours)
//! and with it (what every process runs: every sample arrives, no wait reaches the timeout;
//! its "misses" are waits the re-check ended, an upper bound on the wake-ups it rescued).
//!
//! The race needs a notifier to fire inside a window of well under a microsecond in the
//! receiver's `take_wakeup`, so at test sizes the raw count is usually 0 (`hnav-bench round`
//! met it about once in 5 000 rounds at 128 agents, under load). To force it, run the
//! receiver under gdb, stop it at the second `recvfrom` of a `take_wakeup` on a listener that
//! nothing signalled (the `empty_buffer` call in iceoryx2-cal's `drain_events`), let a sender
//! publish, continue: that sample arrives, and the next one's notification is lost.

use std::time::Duration;

use hnav_tests::lost_wakeup::Report;
use hnav_tests::TestRun;

const PEER: &str = env!("CARGO_BIN_EXE_hnav-test-peer");
/// A wait longer than this is a hang, whatever the load (the receiver's own bound).
const TIMEOUT_MS: &str = "1000";

/// Runs `rounds` rounds of `senders` senders spread over `threads` threads against a
/// receiver whose re-check is `recheck_ms` (0: off) and returns the receiver's report.
fn reproduce(senders: u64, threads: u64, rounds: u64, recheck_ms: u64) -> Report {
    let mut run = TestRun::new("lostwake");
    let (s, th, r, rc) = (
        senders.to_string(),
        threads.to_string(),
        rounds.to_string(),
        recheck_ms.to_string(),
    );
    let mut rx = run
        .spawn(
            PEER,
            &[
                "lost-wakeup-receiver",
                "--senders",
                &s,
                "--rounds",
                &r,
                "--recheck-ms",
                &rc,
                "--timeout-ms",
                TIMEOUT_MS,
            ],
        )
        .unwrap();
    rx.wait_for_line("READY", Duration::from_secs(60)).unwrap();
    let mut tx = run
        .spawn(
            PEER,
            &[
                "lost-wakeup-senders",
                "--senders",
                &s,
                "--threads",
                &th,
                "--rounds",
                &r,
            ],
        )
        .unwrap();
    let line = rx
        .wait_for_line("LOST_WAKEUP", Duration::from_secs(300))
        .unwrap();
    assert!(rx.wait_exit(Duration::from_secs(60)).unwrap().success());
    assert!(tx.wait_exit(Duration::from_secs(60)).unwrap().success());
    let report = Report::parse(&line).unwrap_or_else(|| panic!("unreadable report {line:?}"));
    let what = if recheck_ms == 0 {
        "lost wake-ups (waits timed out with a sample pending)"
    } else {
        "waits the re-check ended with a sample pending (at most that many rescued)"
    };
    println!(
        "senders={senders} threads={threads} recheck={recheck_ms}ms: {} {what} in {} rounds \
         ({:.5} per round), {} with the notification suppressed, {} timeouts; {} ms",
        report.misses,
        report.rounds,
        report.miss_rate(),
        report.suppressed,
        report.timeouts,
        report.ms
    );
    assert_eq!(report.samples, senders * rounds, "{report:?}");
    report
}

/// Both runs of one configuration: raw (no re-check), then as the processes run.
fn with_and_without_recheck(senders: u64, threads: u64, rounds: u64) {
    let raw = reproduce(senders, threads, rounds, 0);
    assert_eq!(
        raw.misses, raw.suppressed,
        "a wake-up lost with no notification pending is a drain-order bug of ours: {raw:?}"
    );
    let rechecked = reproduce(
        senders,
        threads,
        rounds,
        hnav_runtime::transport::Waiter::LOST_WAKEUP_RECHECK.as_millis() as u64,
    );
    assert_eq!(
        rechecked.timeouts, 0,
        "with the re-check no wait may reach the timeout: {rechecked:?}"
    );
}

#[test]
fn one_sender_ping_pong() {
    with_and_without_recheck(1, 1, 20_000);
}

#[test]
fn many_sender_threads_each_one_sample_per_round() {
    with_and_without_recheck(32, 32, 1_500);
}

#[test]
fn one_thread_of_many_senders_like_the_round_benchmark() {
    with_and_without_recheck(128, 1, 300);
}
