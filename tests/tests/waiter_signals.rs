//! Signals and the transport's `Waiter`, with `hnav-test-peer wait-echo` blocked in one: a
//! process that is paused (SIGSTOP) and resumed (SIGCONT) keeps running, SIGTERM and SIGINT
//! end it cleanly. In their own test binary because they signal processes.

use std::time::{Duration, Instant};

use hnav_runtime::transport::{Qos, Receiver, Sender, Transport, Waiter, Wake};
use hnav_tests::{Peer, TestRun};
use nix::sys::signal::Signal;

const PEER: &str = env!("CARGO_BIN_EXE_hnav-test-peer");
const STEP: Duration = Duration::from_secs(30);

/// The test's side of the echo: pings out, pongs back, through a waiter of its own (which
/// leaves signals alone, so that the test harness keeps its own handling).
struct Echo {
    pings: Sender<u64>,
    pongs: Receiver<u64>,
    transport: Transport,
}

impl Echo {
    fn open(run: &TestRun) -> Echo {
        let t = Transport::builder(&run.run)
            .node_name("test")
            .handle_signals(false)
            .create()
            .unwrap();
        let qos = Qos::reliable(2).with_buffer(256);
        Echo {
            pings: t.sender::<u64>("ping", qos).unwrap(),
            pongs: t.receiver::<u64>("pong", qos).unwrap(),
            transport: t,
        }
    }

    /// Sends `value` and waits, bounded, for its pong.
    fn round_trip(&self, waiter: &Waiter, value: u64) -> Result<(), String> {
        self.pings.send(value).map_err(|e| e.to_string())?;
        let deadline = Instant::now() + STEP;
        loop {
            let mut back = false;
            self.pongs
                .drain_pending(|v| back |= *v == value)
                .map_err(|e| e.to_string())?;
            if back {
                return Ok(());
            }
            match waiter.wait(Some(deadline)).map_err(|e| e.to_string())? {
                Wake::Data => {}
                Wake::TimedOut => return Err(format!("no pong {value} within {STEP:?}")),
                Wake::Stop => return Err("the test was asked to stop".into()),
            }
        }
    }
}

fn start(run: &mut TestRun) -> Peer {
    let mut peer = run.spawn(PEER, &["wait-echo"]).unwrap();
    peer.wait_for_line("READY", STEP).unwrap();
    peer
}

/// Ends the echo with `signal` and checks that it stopped cleanly; returns its report.
fn stop_with(peer: &mut Peer, signal: Signal) -> String {
    peer.signal(signal).unwrap();
    let line = peer.wait_for_line("STOPPED", STEP).unwrap();
    let status = peer.wait_exit(STEP).unwrap();
    assert!(
        status.success(),
        "{signal} must end the process cleanly: {status}"
    );
    assert!(
        line.contains("sticky=true"),
        "a later waiter sees the stop: {line}"
    );
    line
}

#[test]
fn a_paused_and_resumed_process_keeps_running_and_sigterm_stops_it() {
    let mut run = TestRun::new("wsigstop");
    let mut peer = start(&mut run);
    let echo = Echo::open(&run);
    let waiter = echo.transport.waiter().unwrap();
    let _attached = waiter.attach(&echo.pongs).unwrap();
    echo.round_trip(&waiter, 1).unwrap();

    // Give the peer time to block in its wait again, then pause and resume it there.
    std::thread::sleep(Duration::from_millis(200));
    peer.signal(Signal::SIGSTOP).unwrap();
    std::thread::sleep(Duration::from_millis(200));
    peer.signal(Signal::SIGCONT).unwrap();
    std::thread::sleep(Duration::from_millis(100));

    echo.round_trip(&waiter, 2).unwrap();
    echo.round_trip(&waiter, 3).unwrap();
    let line = stop_with(&mut peer, Signal::SIGTERM);
    // The resumed wait came back as data with nothing to read: the interruption, survived.
    let idle: u64 = line
        .split_whitespace()
        .find_map(|f| f.strip_prefix("idle="))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no idle= in {line:?}"));
    assert!(
        idle >= 1,
        "SIGSTOP/SIGCONT should interrupt the wait once: {line}"
    );
}

#[test]
fn sigint_stops_a_waiting_process_cleanly() {
    let mut run = TestRun::new("wsigint");
    let mut peer = start(&mut run);
    let echo = Echo::open(&run);
    let waiter = echo.transport.waiter().unwrap();
    let _attached = waiter.attach(&echo.pongs).unwrap();
    echo.round_trip(&waiter, 1).unwrap();
    stop_with(&mut peer, Signal::SIGINT);
}
