//! The wait of a loop with one event source: [`SingleWaiter`], a sleep on one receiver's
//! listener descriptor without iceoryx2's `WaitSet`.
//!
//! ## Why
//!
//! A [`Waiter`](super::Waiter) multiplexes: it owns a `WaitSet`, an epoll instance, and on
//! every wake-up iceoryx2 0.10 makes an `epoll_wait`, an `fcntl(F_GETFD)` for each ready
//! descriptor (`iceoryx2-bb-posix` checks that it is still valid before the callback) and a
//! heap allocation (the list of ready descriptors). A loop that waits on exactly one receiver
//! has nothing to multiplex: on a ping-pong a message cost four system calls where a
//! Unix-socket ping costs two (`docs/explanation/performance.md`, *the wake-up*).
//!
//! iceoryx2's own direct waits on a listener (`Listener::timed_wait`, `blocking_wait`) are no
//! cheaper: each one switches the listener's socket to blocking (`fcntl` `F_GETFL` and
//! `F_SETFL`), sets `SO_RCVTIMEO` (`setsockopt`) and receives, and the non-blocking read of
//! the drain that follows switches it back (two more `fcntl`) before it finds the socket empty:
//! seven system calls on the receiving side where the `WaitSet` makes three (read from
//! `iceoryx2-bb-posix` 0.10.0, `UnixDatagramReceiver::timed_receive` and `try_receive`, and
//! `iceoryx2-cal`'s `Waiter::drain_events`; not measured).
//!
//! So the single wait is `ppoll(2)` on the listener's descriptor: one system call to sleep
//! (three a message with the notifier's `sendto`, measured with `perf stat`), and the loop's
//! drain ([`Receiver::drain_pending`](super::Receiver::drain_pending)) reads the
//! datagram with one `recvfrom` on a socket iceoryx2 already left non-blocking. It keeps
//! everything else a [`Waiter`](super::Waiter) promises: the same [`Wake`] for the same
//! reasons, the same drain order after [`Wake::Data`], the same lost-wake-up re-check
//! ([`Waiter::LOST_WAKEUP_RECHECK`]).
//!
//! It is a type of its own, not a mode the `Waiter` switches into when it holds one
//! attachment: a loop either has one source or it does not, and that is known where it is
//! written. A `Waiter` that changed its system calls when a second attachment came or went
//! would make a loop's cost depend on its history; a `SingleWaiter` cannot be given a second
//! source at all.
//!
//! ## Signals
//!
//! As in the `Waiter`: `ppoll` returns `EINTR` for any signal the process handles (it is
//! never restarted, whatever the handler's `SA_RESTART`, see `signal(7)`), which is
//! [`Wake::Data`] unless it was SIGINT or SIGTERM and the transport handles signals, which is
//! [`Wake::Stop`], sticky ([`stop_requested`](super::stop_requested)).
//! A request that lands after the wait looked for one and before it sleeps does not interrupt
//! the sleep; the wait then sees it when the re-check ends that sleep, so a stop ends the
//! wait within [`Waiter::LOST_WAKEUP_RECHECK`]: the same window as the `WaitSet`'s.
//!
//! ```no_run
//! use std::time::{Duration, Instant};
//!
//! use hnav_runtime::msg::Lifecycle;
//! use hnav_runtime::transport::{Qos, RunId, Transport, Wake};
//!
//! # fn main() -> Result<(), hnav_runtime::transport::TransportError> {
//! let run = RunId::new("demo-1")?;
//! let transport = Transport::builder(&run).node_name("observer").create()?;
//! let life = transport.receiver::<Lifecycle>("lifecycle", Qos::reliable(4))?;
//! let waiter = transport.single_waiter(&life);
//! let deadline = Instant::now() + Duration::from_secs(5);
//! loop {
//!     life.drain_pending(|_l| {})?;
//!     match waiter.wait(Some(deadline))? {
//!         Wake::Data => {}
//!         Wake::TimedOut | Wake::Stop => return Ok(()),
//!     }
//! }
//! # }
//! ```

use core::fmt::Debug;
use std::os::fd::RawFd;
use std::time::{Duration, Instant};

use iceoryx2::prelude::{IceoryxSend, ZeroCopySend};
use iceoryx2_bb_posix::file_descriptor::FileDescriptorBased;

use super::waiter::{poll_termination, sleep_bound, slept};
use super::{Receiver, TransportError, Waiter, Wake};

/// A blocking wait on one receiver; see the module docs. Created by
/// [`Transport::single_waiter`](super::Transport::single_waiter) with the transport's signal
/// handling; it borrows the receiver, which must outlive it.
#[derive(Debug)]
pub struct SingleWaiter<'a> {
    /// The listener's socket; valid as long as the borrowed receiver lives.
    fd: RawFd,
    /// The receiver's service name, for error messages (and the borrow of the receiver).
    name: &'a str,
    handle_signals: bool,
    recheck: Option<Duration>,
}

impl<'a> SingleWaiter<'a> {
    pub(crate) fn new<P, H>(receiver: &'a Receiver<P, H>, handle_signals: bool) -> Self
    where
        P: Debug + IceoryxSend + ?Sized + 'static,
        H: Debug + ZeroCopySend + 'static,
    {
        if handle_signals {
            // Installs iceoryx2's handlers now, as `Waiter::create` does: a SIGTERM before
            // the first wait must end the process cleanly, not kill it.
            poll_termination();
        }
        // SAFETY: only the number is kept; the descriptor stays open while `receiver` (which
        // owns the listener) lives, and `'a` ties this waiter to that borrow.
        let fd = unsafe { receiver.listener().file_descriptor().native_handle() };
        Self {
            fd,
            name: receiver.name(),
            handle_signals,
            recheck: Some(Waiter::LOST_WAKEUP_RECHECK),
        }
    }

    /// Replaces the lost-wake-up re-check, as [`Waiter::with_recheck`] does; `None` turns it
    /// off (tests only), and with it the bound on a stop request that lands just before a
    /// sleep.
    pub fn with_recheck(mut self, recheck: Option<Duration>) -> Self {
        self.recheck = recheck.filter(|d| !d.is_zero());
        self
    }

    /// Blocks until the receiver is notified, `deadline` passes, the lost-wake-up re-check
    /// elapses or a signal arrives; see [`Wake`]. After [`Wake::Data`] the loop drains the
    /// receiver ([`Receiver::drain_pending`](super::Receiver::drain_pending)): the wait
    /// consumes nothing, so an undrained notification makes the next wait return at once.
    /// A deadline already passed still looks, without sleeping, whether a notification waits.
    pub fn wait(&self, deadline: Option<Instant>) -> Result<Wake, TransportError> {
        if self.handle_signals && poll_termination() {
            return Ok(Wake::Stop);
        }
        let bound = sleep_bound(deadline, self.recheck);
        let timeout = (bound != Duration::MAX).then(|| libc::timespec {
            // At most LONGEST_TIMED_SLEEP (an hour): no overflow.
            tv_sec: bound.as_secs() as libc::time_t,
            tv_nsec: bound.subsec_nanos().into(),
        });
        let mut ready = libc::pollfd {
            fd: self.fd,
            events: libc::POLLIN,
            revents: 0,
        };
        // SAFETY: one live `pollfd` for the whole call, a live timespec or null (no timeout),
        // and a null signal mask (the thread's own is kept).
        let n = unsafe {
            libc::ppoll(
                &mut ready,
                1,
                timeout.as_ref().map_or(core::ptr::null(), |t| t),
                core::ptr::null(),
            )
        };
        match n {
            0 => Ok(slept(false, deadline)),
            n if n > 0 && ready.revents & libc::POLLNVAL != 0 => Err(TransportError::ipc(
                "wait",
                self.name,
                "the listener's descriptor is not open",
            )),
            // Readable, or an error or hang-up the drain will report.
            n if n > 0 => Ok(Wake::Data),
            _ => self.interrupted(std::io::Error::last_os_error()),
        }
    }

    /// What a failed `ppoll` means: a signal is [`Wake::Data`] or [`Wake::Stop`] (see the
    /// module docs); anything else is an error.
    fn interrupted(&self, e: std::io::Error) -> Result<Wake, TransportError> {
        if e.raw_os_error() != Some(libc::EINTR) {
            return Err(TransportError::ipc("wait", self.name, e));
        }
        Ok(if self.handle_signals && poll_termination() {
            Wake::Stop
        } else {
            Wake::Data
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msg::{Lifecycle, Role};
    use crate::transport::{PurgeOnDrop, Qos, RunId, Transport};

    /// A bound on every wait that should end at once: long, so a slow machine does not fail.
    const LONG: Duration = Duration::from_secs(30);

    /// A transport of `run` that leaves signals to the test harness.
    fn transport(run: &PurgeOnDrop) -> Transport {
        Transport::builder(&run.0)
            .handle_signals(false)
            .create()
            .unwrap()
    }

    #[test]
    fn a_notification_is_data_and_a_quiet_receiver_times_out_at_the_deadline() {
        let run = PurgeOnDrop(RunId::unique("single"));
        let t = transport(&run);
        let rx = t.receiver::<Lifecycle>("life", Qos::reliable(4)).unwrap();
        let tx = t.sender::<Lifecycle>("life", Qos::reliable(4)).unwrap();
        let waiter = t.single_waiter(&rx).with_recheck(None);
        // The sender's appearance may have signalled the listener; consume it first.
        rx.drain_pending(|_| {}).unwrap();

        // Nothing pending: the wait sleeps to its deadline, not a re-check, not less.
        let asked = Instant::now();
        let deadline = asked + Duration::from_millis(30);
        assert_eq!(waiter.wait(Some(deadline)).unwrap(), Wake::TimedOut);
        assert!(Instant::now() >= deadline);

        tx.send(Lifecycle::up(Role::Sim, 0)).unwrap();
        let long = Instant::now() + LONG;
        assert_eq!(waiter.wait(Some(long)).unwrap(), Wake::Data);
        assert!(Instant::now() < long, "woken by the notification");
        // The wait consumed nothing: until the loop drains, every wait returns at once.
        assert_eq!(waiter.wait(Some(long)).unwrap(), Wake::Data);
        assert_eq!(rx.drain_pending(|_| {}).unwrap().samples, 1);

        // Drained: a deadline already passed looks without sleeping and finds nothing.
        assert_eq!(waiter.wait(Some(Instant::now())).unwrap(), Wake::TimedOut);
    }

    #[test]
    fn the_recheck_ends_a_quiet_wait_as_data() {
        let run = PurgeOnDrop(RunId::unique("singlerecheck"));
        let t = transport(&run);
        let rx = t.receiver::<Lifecycle>("life", Qos::reliable(4)).unwrap();
        let waiter = t
            .single_waiter(&rx)
            .with_recheck(Some(Duration::from_millis(10)));
        rx.drain_pending(|_| {}).unwrap();
        let long = Instant::now() + LONG;
        assert_eq!(waiter.wait(Some(long)).unwrap(), Wake::Data);
        assert!(Instant::now() < long);
        assert_eq!(waiter.wait(None).unwrap(), Wake::Data, "no deadline either");
    }
}
