//! The transport's `Waiter` in one process: what wakes it, and how long it sleeps.

use std::time::{Duration, Instant};

use hnav_runtime::transport::{Qos, Transport, Wake};
use hnav_tests::TestRun;

/// Generous upper bound on a wait that should end at once or after a few milliseconds.
const PROMPT: Duration = Duration::from_secs(5);

fn transport(run: &TestRun, name: &str) -> Transport {
    Transport::builder(&run.run)
        .node_name(name)
        .handle_signals(false)
        .create()
        .unwrap()
}

#[test]
fn a_published_sample_wakes_the_waiter_with_data() {
    let run = TestRun::new("wdata");
    let t = transport(&run, "rx");
    let rx = t.receiver::<u64>("topic", Qos::reliable(2)).unwrap();
    let tx = t.sender::<u64>("topic", Qos::reliable(2)).unwrap();
    let waiter = t.waiter().unwrap().with_recheck(None);
    let _attached = waiter.attach(&rx).unwrap();
    rx.drain_pending(|_| {}).unwrap();

    tx.send(7).unwrap();
    let started = Instant::now();
    assert_eq!(
        waiter.wait(Some(Instant::now() + PROMPT)).unwrap(),
        Wake::Data
    );
    assert!(started.elapsed() < PROMPT);
    let mut got = Vec::new();
    let drained = rx.drain_pending(|v| got.push(*v)).unwrap();
    assert!(drained.wakeup.data);
    assert_eq!((drained.samples, got), (1, vec![7]));
}

#[test]
fn a_sample_from_another_thread_ends_a_blocked_wait() {
    let run = TestRun::new("wthread");
    let t = transport(&run, "rx");
    let rx = t.receiver::<u64>("topic", Qos::reliable(2)).unwrap();
    let waiter = t.waiter().unwrap().with_recheck(None);
    let _attached = waiter.attach(&rx).unwrap();
    let id = run.run.clone();
    let sender = std::thread::spawn(move || {
        let t = Transport::builder(&id)
            .node_name("tx")
            .handle_signals(false)
            .create()
            .unwrap();
        let tx = t.sender::<u64>("topic", Qos::reliable(2)).unwrap();
        std::thread::sleep(Duration::from_millis(100));
        tx.send(42).unwrap();
    });
    let deadline = Instant::now() + Duration::from_secs(30);
    let mut got = None;
    // The sender's notifier appearing is an event too: wait until the sample itself is in.
    while got.is_none() {
        assert_eq!(waiter.wait(Some(deadline)).unwrap(), Wake::Data);
        rx.drain_pending(|v| got = Some(*v)).unwrap();
    }
    assert_eq!(got, Some(42));
    sender.join().unwrap();
}

#[test]
fn a_deadline_times_out_in_bounded_time() {
    let run = TestRun::new("wdeadline");
    let t = transport(&run, "rx");
    let rx = t.receiver::<u64>("topic", Qos::reliable(2)).unwrap();
    let waiter = t.waiter().unwrap().with_recheck(None);
    let _attached = waiter.attach(&rx).unwrap();
    rx.drain_pending(|_| {}).unwrap();

    let started = Instant::now();
    let deadline = started + Duration::from_millis(100);
    assert_eq!(waiter.wait(Some(deadline)).unwrap(), Wake::TimedOut);
    let slept = started.elapsed();
    assert!(slept >= Duration::from_millis(100), "woke early: {slept:?}");
    assert!(slept < PROMPT, "slept {slept:?}");

    // A deadline already passed looks without sleeping.
    let started = Instant::now();
    assert_eq!(waiter.wait(Some(started)).unwrap(), Wake::TimedOut);
    assert!(started.elapsed() < PROMPT);
}

#[test]
fn an_interval_ticks_as_a_time_out() {
    let run = TestRun::new("wtick");
    let t = transport(&run, "rx");
    let rx = t.receiver::<u64>("topic", Qos::reliable(2)).unwrap();
    let waiter = t.waiter().unwrap().with_recheck(None);
    let _attached = waiter.attach(&rx).unwrap();
    let _tick = waiter.attach_interval(Duration::from_millis(20)).unwrap();
    rx.drain_pending(|_| {}).unwrap();

    let started = Instant::now();
    for _ in 0..3 {
        assert_eq!(
            waiter.wait(Some(Instant::now() + PROMPT)).unwrap(),
            Wake::TimedOut
        );
    }
    let slept = started.elapsed();
    assert!(
        slept >= Duration::from_millis(40),
        "three ticks in {slept:?}"
    );
    assert!(slept < PROMPT, "three ticks in {slept:?}");
}

#[test]
fn the_lost_wakeup_recheck_ends_a_quiet_wait_as_data() {
    let run = TestRun::new("wrecheck");
    let t = transport(&run, "rx");
    let rx = t.receiver::<u64>("topic", Qos::reliable(2)).unwrap();
    let waiter = t.waiter().unwrap();
    let _attached = waiter.attach(&rx).unwrap();
    rx.drain_pending(|_| {}).unwrap();

    // Nothing is signalled and the deadline is far: the re-check ends the wait, as data.
    let started = Instant::now();
    let far = started + Duration::from_secs(600);
    assert_eq!(waiter.wait(Some(far)).unwrap(), Wake::Data);
    let slept = started.elapsed();
    assert!(slept >= hnav_runtime::transport::Waiter::LOST_WAKEUP_RECHECK);
    assert!(slept < PROMPT, "slept {slept:?}");
}

#[test]
fn a_waiter_with_nothing_attached_is_an_error_not_a_hang() {
    let run = TestRun::new("wempty");
    let t = transport(&run, "rx");
    let waiter = t.waiter().unwrap();
    assert!(waiter.wait(None).is_err());
    let rx = t.receiver::<u64>("topic", Qos::reliable(2)).unwrap();
    let attached = waiter.attach(&rx).unwrap();
    drop(attached);
    assert!(waiter.wait(None).is_err(), "a dropped attachment detaches");
}

#[test]
fn drain_pending_consumes_the_events_then_every_sample() {
    let run = TestRun::new("wdrain");
    let t = transport(&run, "rx");
    let rx = t.receiver::<u64>("topic", Qos::reliable(2)).unwrap();
    let tx = t.sender::<u64>("topic", Qos::reliable(2)).unwrap();
    for v in 0..5 {
        tx.send(v).unwrap();
    }
    let mut got = Vec::new();
    let d = rx.drain_pending(|v| got.push(*v)).unwrap();
    assert!(
        d.wakeup.data,
        "five notifications, coalesced into one event"
    );
    assert_eq!((d.samples, got), (5, vec![0, 1, 2, 3, 4]));
    let again = rx.drain_pending(|_| {}).unwrap();
    assert_eq!(again.samples, 0);
    assert!(!again.wakeup.data);
}
