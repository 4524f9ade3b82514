//! A termination request (SIGTERM at the waiting thread while it sleeps in `ppoll`) ends a
//! `SingleWaiter`'s wait with `Wake::Stop`, and every later wait of the process too. In its own test binary: the stop is sticky for the whole process, and
//! the test signals itself.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use hnav_runtime::msg::Lifecycle;
use hnav_runtime::transport::{stop_requested, PurgeOnDrop, Qos, RunId, Transport, Wake};

#[test]
fn sigterm_interrupts_a_single_wait_as_stop() {
    let run = PurgeOnDrop(RunId::unique("singlestop"));
    // The default: the transport handles SIGINT and SIGTERM.
    let t = Transport::builder(&run.0).create().unwrap();
    let rx = t.receiver::<Lifecycle>("life", Qos::reliable(4)).unwrap();
    // No re-check and a far deadline: only the signal can end the wait in time. Creating the
    // waiter installs iceoryx2's handlers, so the signals below do not kill the test.
    let waiter = t.single_waiter(&rx).with_recheck(None);
    rx.drain_pending(|_| {}).unwrap();
    assert!(!stop_requested());

    let deadline = Instant::now() + Duration::from_secs(30);
    // SAFETY: pthread_self(3) and gettid(2) have no preconditions.
    let (waiting, tid) = unsafe { (libc::pthread_self(), libc::gettid()) };
    let done = AtomicBool::new(false);
    let (wakes, signals) = std::thread::scope(|s| {
        let signaller = s.spawn(|| {
            // Only once the waiting thread sleeps in `ppoll`, so that the signal interrupts
            // the sleep (not the look for a request before it) ...
            while !in_ppoll(tid) && Instant::now() < deadline {
                std::thread::sleep(Duration::from_millis(1));
            }
            // ... at that thread, not the process, and again until the wait ends.
            let mut sent = 0u32;
            while !done.load(Ordering::Acquire) && Instant::now() < deadline {
                // SAFETY: `waiting` is alive: it joins this scope before it ends.
                unsafe { libc::pthread_kill(waiting, libc::SIGTERM) };
                sent += 1;
                std::thread::sleep(Duration::from_millis(5));
            }
            sent
        });
        let mut wakes = Vec::new();
        loop {
            let wake = waiter.wait(Some(deadline)).unwrap();
            wakes.push(wake);
            if wake != Wake::Data {
                break;
            }
        }
        done.store(true, Ordering::Release);
        (wakes, signaller.join().unwrap())
    });
    assert_eq!(wakes, [Wake::Stop], "after {signals} signals");
    assert!(Instant::now() < deadline, "ended by the signal");
    assert!(stop_requested(), "sticky");
    // A later wait, and a waiter made after the request, stop at once.
    assert_eq!(waiter.wait(None).unwrap(), Wake::Stop);
    assert_eq!(t.single_waiter(&rx).wait(None).unwrap(), Wake::Stop);
}

/// Whether thread `tid` of this process is in the `ppoll` system call now; true when that
/// cannot be read: a signal sent early ends the wait as `Stop` too, only by another path.
fn in_ppoll(tid: libc::pid_t) -> bool {
    match std::fs::read_to_string(format!("/proc/self/task/{tid}/syscall")) {
        Ok(s) => s.split_whitespace().next().and_then(|n| n.parse().ok()) == Some(libc::SYS_ppoll),
        Err(_) => true,
    }
}
