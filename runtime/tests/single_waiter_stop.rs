//! A termination request ends a `SingleWaiter`'s wait with `Wake::Stop`, and every later wait
//! of the process too. In its own test binary: the stop is sticky for the whole process, and
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
    // SAFETY: pthread_self(3) has no preconditions.
    let waiting = unsafe { libc::pthread_self() };
    let done = AtomicBool::new(false);
    let (wakes, signals) = std::thread::scope(|s| {
        let signaller = s.spawn(|| {
            // At this thread, not the process: the wait's `ppoll` must see EINTR. Again and
            // again until the wait ends: a signal that lands after the wait looked for a
            // request and before it slept does not interrupt that sleep; the next one does.
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
    assert_eq!(
        wakes.last(),
        Some(&Wake::Stop),
        "{wakes:?} after {signals} signals"
    );
    assert!(Instant::now() < deadline, "ended by the signal");
    assert!(stop_requested(), "sticky");
    // A later wait, and a waiter made after the request, stop at once.
    assert_eq!(waiter.wait(None).unwrap(), Wake::Stop);
    assert_eq!(t.single_waiter(&rx).wait(None).unwrap(), Wake::Stop);
}
