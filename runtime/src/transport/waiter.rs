//! Where a process with several event sources blocks: a [`Waiter`] around iceoryx2's
//! `WaitSet`.
//!
//! Every HNAV loop has the same shape: drain its inputs, then sleep until one of them is
//! signalled, a period ticks, a deadline passes or the process is asked to stop. The
//! [`Waiter`] is that sleep. It owns the iceoryx2 `WaitSet`, so no process crate names an
//! iceoryx2 type, and it decides once, for every loop, what a wake-up means ([`Wake`]). A
//! loop whose only source is one receiver sleeps on that receiver instead
//! ([`SingleWaiter`](super::SingleWaiter), `transport::single`): the same [`Wake`]s, the same
//! drain order and re-check, without the `WaitSet`'s cost per wake-up.
//!
//! ## Drain order
//!
//! iceoryx2 0.10 events coalesce: one wake-up may stand for many samples (and a listener's
//! event bits are per event id, not per sample). After [`Waiter::wait`] returns
//! [`Wake::Data`], a loop must, for **every** attached receiver:
//!
//! 1. consume the listener's events ([`Receiver::take_wakeup`]), then
//! 2. receive until the subscriber is empty ([`Receiver::drain`] / `receive` until `None`).
//!
//! [`Receiver::drain_pending`] does both in that order. The order matters: a [`Sender`]
//! publishes a sample before it notifies, so any sample whose notification step 1 consumed
//! is already in the queue step 2 empties. The reverse order would lose a sample that lands
//! between the drain and the consumption of its notification: the loop would go back to
//! sleep with it unread.
//!
//! ## Signals
//!
//! A blocked `epoll_wait` returns `EINTR` for any signal the process handles, and also,
//! on Linux, after SIGSTOP/SIGCONT. That is [`Wake::Data`] ("look again"), never a stop: a
//! process that was merely paused must carry on. Only a termination request (SIGINT or
//! SIGTERM, seen by iceoryx2's signal handler when the transport handles signals, see
//! [`TransportBuilder::handle_signals`](super::TransportBuilder::handle_signals)) is
//! [`Wake::Stop`], and it stays set for the rest of the process ([`stop_requested`]): iceoryx2
//! forgets the request once it has been read, and a later `Waiter` (the run's, after the
//! start-up handshake's) must still see it.
//!
//! ## Lost wake-ups
//!
//! iceoryx2 0.10's event listener can go deaf. A listener keeps a "notified" flag beside its
//! socket, and a notifier sends a datagram only when the flag is not yet set. Consuming the
//! events of a listener whose flag is *not* set (nothing signalled it, or a notifier is half
//! way) resets the flag and only then reads the socket (`iceoryx2-cal` 0.10.0,
//! `src/event/common.rs`, `Waiter::drain_events`: the `store(NOTIFICATION_STATE_IDLE)` at
//! line 457, then `drain()` and its `empty_buffer()` at line 436). A notifier that fires in
//! between sends its datagram, which that read swallows, and then sets the flag: flag set,
//! socket empty. Every later notifier sees the flag and sends nothing, so the next wait sleeps
//! with samples pending until something else makes the loop consume the listener's events
//! again. Our drain order is not the cause. Consuming only the listeners that signalled would
//! make the window rarer but not close it (it is also open while a notifier is between its
//! datagram and its flag), so the waiter bounds every sleep to
//! [`Waiter::LOST_WAKEUP_RECHECK`] and reports an elapsed re-check as [`Wake::Data`]. The
//! reproducer is `tests/tests/lost_wakeup.rs`; it turns the re-check off with
//! [`Waiter::with_recheck`]`(None)` to count the misses.
//!
//! ```no_run
//! use std::time::{Duration, Instant};
//!
//! use hnav_runtime::msg::Candidate;
//! use hnav_runtime::transport::{Qos, RunId, Transport, Wake};
//!
//! # fn main() -> Result<(), hnav_runtime::transport::TransportError> {
//! let run = RunId::new("demo-1")?;
//! let transport = Transport::builder(&run).node_name("coordinator").create()?;
//! let candidates = transport.receiver::<Candidate>("candidates", Qos::reliable(4))?;
//! let waiter = transport.waiter()?;
//! let _attached = waiter.attach(&candidates)?;
//! let deadline = Instant::now() + Duration::from_secs(5);
//! let mut seen = 0;
//! loop {
//!     seen += candidates.drain_pending(|_c| {})?.samples;
//!     if seen == 4 {
//!         break;
//!     }
//!     match waiter.wait(Some(deadline))? {
//!         Wake::Data => {}
//!         Wake::TimedOut => break, // the round closes without the missing candidates
//!         Wake::Stop => return Ok(()),
//!     }
//! }
//! # Ok(()) }
//! ```

use core::cell::RefCell;
use core::fmt::Debug;
use std::os::fd::RawFd;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use iceoryx2::prelude::{
    CallbackProgression, IceoryxSend, SignalHandlingMode, WaitSet, WaitSetBuilder, ZeroCopySend,
};
use iceoryx2::waitset::{WaitSetAttachmentId, WaitSetGuard, WaitSetRunResult};
use iceoryx2_bb_posix::file_descriptor_set::SynchronousMultiplexing;
use iceoryx2_bb_posix::signal::SignalHandler;

use super::bell::{take_ring, BellWatch};
use super::{Ipc, Receiver, TransportError};

/// The longest single timed sleep: iceoryx2 hands epoll the timeout in milliseconds as an
/// `i32`, which a far deadline would overflow. A wait that reaches it returns
/// [`Wake::Data`], like an elapsed re-check.
const LONGEST_TIMED_SLEEP: Duration = Duration::from_secs(3600);

/// Set once a termination request has been seen; never cleared.
static STOP: AtomicBool = AtomicBool::new(false);

/// Whether a waiter of this process has seen SIGINT or SIGTERM. Only waiters of a transport
/// that handles signals look for them, and only they return [`Wake::Stop`] once it is set.
/// Once true it stays true, so a loop that is not waiting can ask too.
pub fn stop_requested() -> bool {
    STOP.load(Ordering::Relaxed)
}

/// Reads (and so consumes) iceoryx2's termination flag and makes it sticky. The first call
/// also installs iceoryx2's handlers for SIGINT/SIGTERM, which is why only waiters of a
/// transport that handles signals call it.
pub(super) fn poll_termination() -> bool {
    if SignalHandler::termination_requested() {
        STOP.store(true, Ordering::Relaxed);
    }
    stop_requested()
}

/// How long one wait may sleep: until `deadline`, and no longer than `recheck` (the
/// lost-wake-up re-check) and [`LONGEST_TIMED_SLEEP`]. `Duration::MAX` when neither bounds
/// it: iceoryx2's "no timeout", a plain blocking wait.
pub(super) fn sleep_bound(deadline: Option<Instant>, recheck: Option<Duration>) -> Duration {
    let left = deadline.map(|d| d.saturating_duration_since(Instant::now()));
    match (left, recheck) {
        (None, None) => Duration::MAX,
        (l, r) => l
            .unwrap_or(Duration::MAX)
            .min(r.unwrap_or(Duration::MAX))
            .min(LONGEST_TIMED_SLEEP),
    }
}

/// What a wait that nothing signalled means: [`Wake::TimedOut`] when an interval `ticked` or
/// the deadline passed; otherwise the re-check (or the longest timed sleep) ended it, which
/// is [`Wake::Data`] too ("look again").
pub(super) fn slept(ticked: bool, deadline: Option<Instant>) -> Wake {
    if ticked || deadline.is_some_and(|d| Instant::now() >= d) {
        Wake::TimedOut
    } else {
        Wake::Data
    }
}

/// Why [`Waiter::wait`] (or [`SingleWaiter::wait`](super::SingleWaiter::wait)) returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wake {
    /// Go and drain every attached receiver; there may be nothing there. Returned when
    /// something attached was signalled (a receiver's listener, an exit descriptor), when a
    /// signal other than SIGINT/SIGTERM interrupted the wait (SIGSTOP/SIGCONT among them), or
    /// when the lost-wake-up re-check elapsed before the deadline.
    Data,
    /// Nothing was signalled and an attached interval ticked or the deadline passed.
    TimedOut,
    /// SIGINT or SIGTERM: the process should end its loop and exit cleanly. Every later wait
    /// of the process (of a transport that handles signals) returns it again at once.
    Stop,
}

/// Names one [`Attachment`] of a [`Waiter`]: what [`Waiter::wait_with`] reports for each
/// attachment that was signalled, to compare with [`Attachment::id`]. Only meaningful for the
/// waiter that made it.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct AttachmentId(WaitSetAttachmentId<Ipc>);

/// Something attached to a [`Waiter`]. Keep it alive as long as the waiter should watch it;
/// dropping it detaches.
#[must_use = "dropping an attachment detaches it at once"]
pub struct Attachment<'w, 'a> {
    guard: WaitSetGuard<'w, 'a, Ipc>,
    /// The waiter whose interval or bell list names this attachment, if it is one of those.
    listed_by: Option<&'w Waiter>,
}

impl Debug for Attachment<'_, '_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Attachment")
            .field("listed", &self.listed_by.is_some())
            .finish_non_exhaustive()
    }
}

impl Attachment<'_, '_> {
    /// The id [`Waiter::wait_with`] reports when this attachment is signalled.
    pub fn id(&self) -> AttachmentId {
        AttachmentId(WaitSetAttachmentId::from_guard(&self.guard))
    }
}

impl Drop for Attachment<'_, '_> {
    fn drop(&mut self) {
        if let Some(waiter) = self.listed_by {
            let id = WaitSetAttachmentId::from_guard(&self.guard);
            waiter.intervals.borrow_mut().retain(|t| *t != id);
            waiter.bells.borrow_mut().retain(|(b, _)| *b != id);
        }
    }
}

/// A process's blocking wait on its receivers, an optional interval and a deadline. Created
/// by [`Transport::waiter`](super::Transport::waiter) with the transport's signal handling.
pub struct Waiter {
    waitset: WaitSet<Ipc>,
    /// For error messages: the run the waiter belongs to.
    run: String,
    handle_signals: bool,
    recheck: Option<Duration>,
    /// The attachment ids of attached intervals, to tell a tick from a signalled input.
    intervals: RefCell<Vec<WaitSetAttachmentId<Ipc>>>,
    /// Attached bell watches and their epoll descriptors, whose rings the wait takes.
    bells: RefCell<Vec<(WaitSetAttachmentId<Ipc>, RawFd)>>,
}

impl Debug for Waiter {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Waiter")
            .field("run", &self.run)
            .field("handle_signals", &self.handle_signals)
            .field("recheck", &self.recheck)
            .field("attachments", &self.waitset.len())
            .finish()
    }
}

impl Waiter {
    /// The longest one [`Waiter::wait`] sleeps with nothing signalled before it returns
    /// [`Wake::Data`] so that the loop looks at its inputs again.
    ///
    /// A bound on iceoryx2 0.10's lost wake-up (see the `transport::waiter` module docs), not
    /// a timer: lockstep loops wait on data, never on time, so re-checking changes no
    /// decision; it only bounds a stall (`hnav-bench round` saw one in about 5 000 rounds at 128 agents)
    /// to this long.
    pub const LOST_WAKEUP_RECHECK: Duration = Duration::from_millis(50);

    pub(crate) fn create(run: &str, signals: SignalHandlingMode) -> Result<Self, TransportError> {
        let waitset = WaitSetBuilder::new()
            .signal_handling_mode(signals)
            .create::<Ipc>()
            .map_err(|e| TransportError::ipc("create waitset", run, e))?;
        let handle_signals = signals == SignalHandlingMode::HandleTerminationRequests;
        if handle_signals {
            // Installs the handlers now: a SIGTERM between here and the first wait must end
            // the process cleanly, not kill it.
            poll_termination();
        }
        Ok(Self {
            waitset,
            run: run.to_string(),
            handle_signals,
            recheck: Some(Self::LOST_WAKEUP_RECHECK),
            intervals: RefCell::new(Vec::new()),
            bells: RefCell::new(Vec::new()),
        })
    }

    /// Replaces the lost-wake-up re-check ([`Waiter::LOST_WAKEUP_RECHECK`]); `None` turns it
    /// off, so that a wait sleeps until something is signalled or the deadline passes. Only
    /// tests want that: the reproducer of the lost wake-up (`tests/tests/lost_wakeup.rs`), and
    /// one that must tell an interrupted wait from an elapsed re-check.
    pub fn with_recheck(mut self, recheck: Option<Duration>) -> Self {
        self.recheck = recheck.filter(|d| !d.is_zero());
        self
    }

    /// Wakes the waiter when `receiver` is notified (a sample, or a publisher that appeared,
    /// left or died). Works for fixed-size and slice receivers alike.
    pub fn attach<'a, P, H>(
        &self,
        receiver: &'a Receiver<P, H>,
    ) -> Result<Attachment<'_, 'a>, TransportError>
    where
        P: Debug + IceoryxSend + ?Sized + 'static,
        H: Debug + ZeroCopySend + 'static,
    {
        self.attach_named(receiver.listener(), receiver.name())
    }

    /// Makes the waiter return [`Wake::TimedOut`] every `period` (measured from now), unless
    /// something was signalled too, which makes it [`Wake::Data`]: a periodic loop checks its
    /// own clock after every wake-up.
    pub fn attach_interval(
        &self,
        period: Duration,
    ) -> Result<Attachment<'_, 'static>, TransportError> {
        let guard = self
            .waitset
            .attach_interval(period)
            .map_err(|e| TransportError::ipc("attach interval", &self.run, e))?;
        self.intervals
            .borrow_mut()
            .push(WaitSetAttachmentId::from_guard(&guard));
        Ok(Attachment {
            guard,
            listed_by: Some(self),
        })
    }

    /// Wakes the waiter when the bell rings (see [`Bell`](super::Bell)). The wait takes each
    /// ring it reports ([`BellWatch::take`]), before the loop drains its commits; a
    /// ring left untaken would keep every later wait from sleeping.
    pub fn attach_bell<'a>(
        &self,
        watch: &'a BellWatch,
    ) -> Result<Attachment<'_, 'a>, TransportError> {
        let mut attachment = self.attach_named(watch, "commit bell")?;
        self.bells.borrow_mut().push((
            WaitSetAttachmentId::from_guard(&attachment.guard),
            watch.raw_fd(),
        ));
        attachment.listed_by = Some(self);
        Ok(attachment)
    }

    /// Wakes the waiter when `fd` becomes readable (the supervisor's child exit descriptors, a
    /// recorder's stop pipe).
    pub fn attach_fd<'a, T>(&self, fd: &'a T) -> Result<Attachment<'_, 'a>, TransportError>
    where
        T: SynchronousMultiplexing + Debug + ?Sized,
    {
        self.attach_named(fd, &self.run)
    }

    /// Attaches `fd`; `what` names it in the error.
    fn attach_named<'a, T>(
        &self,
        fd: &'a T,
        what: &str,
    ) -> Result<Attachment<'_, 'a>, TransportError>
    where
        T: SynchronousMultiplexing + Debug + ?Sized,
    {
        let guard = self
            .waitset
            .attach_notification(fd)
            .map_err(|e| TransportError::ipc("attach to waiter", what, e))?;
        Ok(Attachment {
            guard,
            listed_by: None,
        })
    }

    /// Blocks until something attached is signalled, an interval ticks, `deadline` passes, the
    /// lost-wake-up re-check elapses or a signal arrives; see [`Wake`] for what each means. A
    /// deadline already passed still looks, without sleeping, at what is signalled.
    ///
    /// Errors when nothing is attached (the wait could never end) or iceoryx2's wait fails.
    pub fn wait(&self, deadline: Option<Instant>) -> Result<Wake, TransportError> {
        self.wait_with(deadline, |_| {})
    }

    /// [`Waiter::wait`], calling `signalled` with the [`AttachmentId`] of every receiver or
    /// descriptor that was signalled (intervals are not reported; they make the wait
    /// [`Wake::TimedOut`]). For loops whose inputs are not interchangeable: a benchmark that
    /// timestamps each receiver's wake-up, a supervisor that must know which child exited.
    ///
    /// A [`Wake::Data`] with no call means nothing was signalled (an interrupted wait or an
    /// elapsed lost-wake-up re-check): a loop that only drains what was reported must then
    /// drain every receiver, or a lost wake-up stays lost.
    pub fn wait_with(
        &self,
        deadline: Option<Instant>,
        mut signalled: impl FnMut(AttachmentId),
    ) -> Result<Wake, TransportError> {
        if self.handle_signals && stop_requested() {
            return Ok(Wake::Stop);
        }
        let timeout = sleep_bound(deadline, self.recheck);
        let (mut any_signalled, mut ticked) = (false, false);
        let intervals = self.intervals.borrow();
        let bells = self.bells.borrow();
        let result = self.waitset.wait_and_process_once_with_timeout(
            |id| {
                if intervals.contains(&id) {
                    ticked = true;
                } else {
                    if let Some(&(_, fd)) = bells.iter().find(|(b, _)| *b == id) {
                        take_ring(fd);
                    }
                    any_signalled = true;
                    signalled(AttachmentId(id));
                }
                CallbackProgression::Continue
            },
            timeout,
        );
        match result {
            Ok(WaitSetRunResult::TerminationRequest) => {
                STOP.store(true, Ordering::Relaxed);
                Ok(Wake::Stop)
            }
            Ok(WaitSetRunResult::Interrupt) => {
                if self.handle_signals && poll_termination() {
                    Ok(Wake::Stop)
                } else {
                    Ok(Wake::Data)
                }
            }
            Ok(WaitSetRunResult::AllEventsHandled | WaitSetRunResult::StopRequest) => {
                Ok(if any_signalled {
                    Wake::Data
                } else {
                    slept(ticked, deadline)
                })
            }
            Err(e) => Err(TransportError::ipc("wait", &self.run, e)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::{PurgeOnDrop, RunId, Transport};

    #[test]
    fn wait_with_names_the_receiver_that_was_signalled() {
        use crate::msg::{Lifecycle, Role};
        use crate::transport::Qos;
        let run = PurgeOnDrop(RunId::unique("waitwith"));
        let t = Transport::builder(&run.0)
            .handle_signals(false)
            .create()
            .unwrap();
        let quiet = t.receiver::<Lifecycle>("quiet", Qos::reliable(4)).unwrap();
        let busy = t.receiver::<Lifecycle>("busy", Qos::reliable(4)).unwrap();
        let tx = t.sender::<Lifecycle>("busy", Qos::reliable(4)).unwrap();
        let waiter = t.waiter().unwrap().with_recheck(None);
        let quiet_at = waiter.attach(&quiet).unwrap();
        let busy_at = waiter.attach(&busy).unwrap();
        assert_ne!(quiet_at.id(), busy_at.id());
        // The sender's connection may already have signalled `busy`; consume that first.
        busy.drain_pending(|_| {}).unwrap();
        tx.send(Lifecycle::up(Role::Sim, 0)).unwrap();
        let mut fired = Vec::new();
        let deadline = Instant::now() + Duration::from_secs(30);
        let wake = waiter
            .wait_with(Some(deadline), |id| fired.push(id))
            .unwrap();
        assert_eq!(wake, Wake::Data);
        assert_eq!(fired, vec![busy_at.id()]);
        assert_eq!(busy.drain_pending(|_| {}).unwrap().samples, 1);
    }

    /// A ring wakes the waiter and is taken by the wait: the next wait sleeps until its
    /// deadline instead of returning at once for ever (the watch is level-triggered in the
    /// `WaitSet`), and a later ring wakes it again.
    #[test]
    fn a_bell_ring_wakes_the_waiter_once() {
        use crate::transport::Bell;
        let run = PurgeOnDrop(RunId::unique("waitbell"));
        let t = Transport::builder(&run.0)
            .handle_signals(false)
            .create()
            .unwrap();
        let waiter = t.waiter().unwrap().with_recheck(None);
        let bell = Bell::create().unwrap();
        let watch = bell.watch().unwrap();
        let at = waiter.attach_bell(&watch).unwrap();
        let long = Instant::now() + Duration::from_secs(30);
        bell.ring().unwrap();
        let mut fired = Vec::new();
        assert_eq!(
            waiter.wait_with(Some(long), |id| fired.push(id)).unwrap(),
            Wake::Data
        );
        assert_eq!(fired, vec![at.id()]);
        assert!(!watch.take(), "the wait took the ring");
        let short = Instant::now() + Duration::from_millis(50);
        assert_eq!(waiter.wait(Some(short)).unwrap(), Wake::TimedOut);
        bell.ring().unwrap();
        assert_eq!(waiter.wait(Some(long)).unwrap(), Wake::Data);
        drop(at);
        assert!(waiter.bells.borrow().is_empty(), "detached");
    }

    #[test]
    fn a_dropped_interval_no_longer_counts_as_a_tick() {
        let run = PurgeOnDrop(RunId::unique("waittick"));
        let t = Transport::builder(&run.0)
            .handle_signals(false)
            .create()
            .unwrap();
        let waiter = t.waiter().unwrap();
        let tick = waiter.attach_interval(Duration::from_millis(10)).unwrap();
        assert_eq!(waiter.intervals.borrow().len(), 1);
        drop(tick);
        assert!(waiter.intervals.borrow().is_empty());
    }
}
