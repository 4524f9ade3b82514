//! `hnav-bench fanout`: what waking N waiting agents costs, one commit at a time, by three
//! mechanisms (issue 16, item 3: the cheapest correct way to wake 128-256 agents per commit).
//!
//! The decision round at 128 agents spends most of its time after the first agent has its
//! commit and before the last one has (`hnav-bench round`: `last_candidate_to_first_commit`
//! against `..._to_all_commits`). That span is the fan-out: the coordinator's notifier sends
//! one datagram per listener (iceoryx2 0.10's event is a Unix datagram socket per listener,
//! `iceoryx2-cal` `event::recommended::Ipc`), and each woken agent reads its socket. This
//! benchmark isolates it: one notifying thread, N waiting threads, each with its own state as
//! an agent process has, and per commit:
//!
//! - **notify**: how long the notifying call takes (the coordinator's CPU time per commit);
//! - **first** and **last**: from just before that call until the first and the last waiter
//!   has seen the new commit (the swarm's wait for its slowest member).
//!
//! Mechanisms:
//!
//! - `hnav`: HNAV's commit path without the bell (what it was before it, and what a process
//!   started without a supervisor still does). Each waiter is a node with a commit `Receiver`
//!   blocked in its own [`Waiter`](hnav_runtime::transport::Waiter); the notifier publishes a
//!   `u64` round with `Sender::send` (loan, publish to N subscribers, notify N listeners).
//! - `hnav-bell`: the same with the commit [`Bell`] (`hnav run`'s default): bell receivers,
//!   each waiter's `Waiter` watching the bell; the notifier publishes and rings once.
//! - `eventfd`: the bare mechanism the bell is built on: one eventfd, and each waiter its own
//!   epoll instance watching it edge-triggered; the notifier stores the round in shared memory
//!   and writes the eventfd once. Edge-triggered, so no waiter needs to read (and so reset)
//!   the counter the others watch.
//! - `futex`: the floor. The round in a shared word, one `FUTEX_WAKE` for every waiter. A
//!   futex cannot join an `epoll` set, so an agent that also waits for odometry and lifecycle
//!   events could not use it as it is.
//!
//! Waiters are threads of this process, not processes: the kernel's wake-up path is the same
//! for both (a process switch adds an address-space switch per wake, which this leaves out).
//! Before each commit every waiter has announced that it is about to wait; a waiter that is
//! still on its way into the wait finds the commit already signalled and sees it at once.
//! Nothing is asserted about the numbers; they are printed (and written as CSV with `--out`).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};

use hnav_runtime::topics;
use hnav_runtime::transport::{purge_run, Bell, RunId, Transport, Wake};

use crate::futex;
use crate::latency::Summary;

/// Measured commits per point by default.
pub const ROUNDS_FULL: usize = 2000;
/// Measured commits per point with `--quick`.
pub const ROUNDS_QUICK: usize = 200;
/// Unmeasured commits before each point.
const WARMUP: usize = 50;
/// How long a waiter or the notifier sleeps at most before it looks again (a lost wake-up
/// would show as a slow commit, never as a hang).
const RECHECK: Duration = Duration::from_millis(100);
/// A point that has not finished a commit for this long is a failure.
const STUCK: Duration = Duration::from_secs(10);
/// How long the waiters may take to set up (a node, a receiver and a `Waiter` each) before
/// the first round: iceoryx2 opens one service's ports one at a time, so 256 waiters on a
/// busy machine take far longer than one commit may.
const SETUP: Duration = Duration::from_secs(120);

/// How the notifier wakes the waiters.
#[derive(Clone, Copy, PartialEq, Eq, Debug, ValueEnum)]
pub enum Mechanism {
    /// HNAV's commit path without the bell: publish + iceoryx2 notify (one datagram per
    /// listener), one `Waiter` per waiter.
    Hnav,
    /// HNAV's commit path with the bell (`hnav run`'s default): publish + one eventfd write,
    /// each waiter's `Waiter` watching the bell.
    HnavBell,
    /// One eventfd write; each waiter's own epoll watches it edge-triggered.
    Eventfd,
    /// One `FUTEX_WAKE` for all waiters (the floor; cannot join an epoll set).
    Futex,
}

impl Mechanism {
    fn name(self) -> &'static str {
        match self {
            Self::Hnav => "hnav",
            Self::HnavBell => "hnav-bell",
            Self::Eventfd => "eventfd",
            Self::Futex => "futex",
        }
    }
}

/// The command line of `hnav-bench fanout`.
#[derive(Debug, Args)]
pub struct FanoutArgs {
    /// Numbers of waiting agents.
    #[arg(long, value_delimiter = ',', default_value = "1,8,32,128,256")]
    pub listeners: Vec<usize>,
    /// Mechanisms to measure.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "hnav,hnav-bell,eventfd,futex"
    )]
    pub mechanisms: Vec<Mechanism>,
    /// Measured commits per point (default 2000, 200 with --quick).
    #[arg(long)]
    pub rounds: Option<usize>,
    /// The smoke-check variant: 200 commits a point.
    #[arg(long)]
    pub quick: bool,
    /// Also write DIR/fanout.csv.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// One measured point.
#[derive(Debug)]
pub struct FanoutPoint {
    /// The mechanism.
    pub mechanism: Mechanism,
    /// Waiting agents.
    pub listeners: usize,
    /// The notifying call.
    pub notify: Summary,
    /// Until the first waiter saw the commit.
    pub first: Summary,
    /// Until the last waiter saw the commit.
    pub last: Summary,
}

/// Runs `hnav-bench fanout`: prints the table, writes the CSV if asked.
pub fn run(args: &FanoutArgs) -> Result<Vec<FanoutPoint>> {
    if args.listeners.is_empty() || args.listeners.contains(&0) {
        bail!("--listeners must be a non-empty list of positive counts");
    }
    let rounds = args.rounds.unwrap_or(if args.quick {
        ROUNDS_QUICK
    } else {
        ROUNDS_FULL
    });
    if rounds == 0 {
        bail!("--rounds must be positive");
    }
    println!("{}", header());
    let mut points = Vec::new();
    for &n in &args.listeners {
        for &m in &args.mechanisms {
            let point = measure(m, n, rounds).with_context(|| format!("{} x {n}", m.name()))?;
            println!("{}", point.row());
            points.push(point);
        }
    }
    if let Some(dir) = &args.out {
        std::fs::create_dir_all(dir).with_context(|| format!("create {}", dir.display()))?;
        let path = dir.join("fanout.csv");
        let mut csv = String::from(
            "mechanism,listeners,n,notify_p50_us,notify_p99_us,first_p50_us,last_p50_us,last_p90_us,last_p99_us,last_max_us\n",
        );
        for p in &points {
            csv.push_str(&format!(
                "{},{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3}\n",
                p.mechanism.name(),
                p.listeners,
                p.last.n,
                p.notify.p50_us(),
                p.notify.p99_us(),
                p.first.p50_us(),
                p.last.p50_us(),
                p.last.p90_us(),
                p.last.p99_us(),
                p.last.max_us()
            ));
        }
        std::fs::write(&path, csv).with_context(|| format!("write {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(points)
}

/// The table's header.
pub fn header() -> String {
    format!(
        "{:<8} {:>9} {:>6} {:>12} {:>12} {:>11} {:>11} {:>11} {:>11}",
        "mech",
        "listeners",
        "n",
        "notify_p50",
        "notify_p99",
        "first_p50",
        "last_p50",
        "last_p99",
        "last_max"
    )
}

impl FanoutPoint {
    /// The table row (µs).
    pub fn row(&self) -> String {
        format!(
            "{:<8} {:>9} {:>6} {:>12.1} {:>12.1} {:>11.1} {:>11.1} {:>11.1} {:>11.1}",
            self.mechanism.name(),
            self.listeners,
            self.last.n,
            self.notify.p50_us(),
            self.notify.p99_us(),
            self.first.p50_us(),
            self.last.p50_us(),
            self.last.p99_us(),
            self.last.max_us()
        )
    }
}

/// What the notifier and the waiters share.
struct Shared {
    epoch: Instant,
    /// The commit: its round number (what `eventfd` and `futex` waiters read; `hnav` waiters
    /// get it as the sample).
    round: AtomicU64,
    /// The futex word of the `futex` mechanism: bumped per commit.
    seq: AtomicU32,
    /// Waiters that announced they are about to wait for the next commit.
    armed: AtomicU32,
    /// Waiters that have seen the current commit.
    done: AtomicU32,
    /// When each waiter saw the current commit (ns since `epoch`).
    seen_ns: Vec<AtomicU64>,
    /// Set when a waiter failed: everyone leaves.
    abort: AtomicBool,
}

impl Shared {
    fn now_ns(&self) -> u64 {
        self.epoch.elapsed().as_nanos() as u64
    }

    /// Counts `counter` up; the last of `n` wakes the notifier.
    fn arrive(&self, counter: &AtomicU32, n: usize) {
        if counter.fetch_add(1, Ordering::AcqRel) + 1 == n as u32 {
            futex::wake(counter, 1);
        }
    }

    /// The notifier waits until `counter` reaches `n`, for at most `bound`.
    fn await_all(&self, counter: &AtomicU32, n: usize, bound: Duration) -> Result<()> {
        let since = Instant::now();
        loop {
            let c = counter.load(Ordering::Acquire);
            if c as usize >= n {
                return Ok(());
            }
            check(self)?;
            if since.elapsed() > bound {
                bail!("{c} of {n} waiters after {} s", bound.as_secs());
            }
            futex::wait(counter, c, RECHECK)?;
        }
    }
}

/// Measures one point: `n` waiters, `rounds` commits after the warm-up.
fn measure(mechanism: Mechanism, n: usize, rounds: usize) -> Result<FanoutPoint> {
    let run = RunId::unique("fanout");
    let result = measure_in(&run, mechanism, n, rounds);
    let purged = purge_run(&run);
    let point = result?;
    purged.context("purge the benchmark's iceoryx2 resources")?;
    Ok(point)
}

fn measure_in(run: &RunId, mechanism: Mechanism, n: usize, rounds: usize) -> Result<FanoutPoint> {
    let shared = Arc::new(Shared {
        epoch: Instant::now(),
        round: AtomicU64::new(0),
        seq: AtomicU32::new(0),
        armed: AtomicU32::new(0),
        done: AtomicU32::new(0),
        seen_ns: (0..n).map(|_| AtomicU64::new(0)).collect(),
        abort: AtomicBool::new(false),
    });
    let bell = match mechanism {
        Mechanism::HnavBell => Some(Bell::create()?),
        _ => None,
    };
    let notifier = Notifier::open(mechanism, run, n, bell.as_ref())?;
    let total = (WARMUP + rounds) as u64;
    std::thread::scope(|s| {
        let mut handles = Vec::with_capacity(n);
        // Only the descriptor crosses to the waiters (iceoryx2 ports stay on their thread).
        let side = WaiterSide {
            mechanism,
            run,
            eventfd: notifier.eventfd(),
            bell: bell.as_ref(),
        };
        for k in 0..n {
            let shared = &shared;
            handles.push(s.spawn(move || {
                let r = waiter(side, shared, k, n, total);
                if r.is_err() {
                    shared.abort.store(true, Ordering::Relaxed);
                    // Wake the notifier wherever it waits.
                    futex::wake(&shared.armed, 1);
                    futex::wake(&shared.done, 1);
                }
                r
            }));
        }
        let measured = notify_rounds(&notifier, &shared, n, total);
        if measured.is_err() {
            shared.abort.store(true, Ordering::Relaxed);
            // Release the waiters: a last commit past the end.
            let _ = notifier.notify(&shared, u64::MAX);
        }
        // A waiter's own failure is the cause; `Aborted` only says another side gave up.
        let mut failed = None;
        for h in handles {
            let r = h
                .join()
                .unwrap_or_else(|_| Err(anyhow::anyhow!("waiter panicked")));
            match r {
                Err(e) if !e.is::<Aborted>() => {
                    failed.get_or_insert(e);
                }
                _ => {}
            }
        }
        let (notify, first, last) = match (failed, measured) {
            (Some(e), _) | (None, Err(e)) => return Err(e),
            (None, Ok(m)) => m,
        };
        Ok(FanoutPoint {
            mechanism,
            listeners: n,
            notify: Summary::from_ns(&notify)?,
            first: Summary::from_ns(&first)?,
            last: Summary::from_ns(&last)?,
        })
    })
}

/// The notifier's side: per commit, waits for every waiter to be armed, notifies, waits for
/// every waiter to have seen it, and keeps the three times of the measured commits.
fn notify_rounds(
    notifier: &Notifier,
    shared: &Shared,
    n: usize,
    total: u64,
) -> Result<(Vec<u64>, Vec<u64>, Vec<u64>)> {
    let measured = total as usize - WARMUP;
    let (mut notify, mut first, mut last) = (
        Vec::with_capacity(measured),
        Vec::with_capacity(measured),
        Vec::with_capacity(measured),
    );
    for r in 1..=total {
        // The first round's arrivals wait for every waiter's set-up.
        let bound = if r == 1 { SETUP } else { STUCK };
        shared.await_all(&shared.armed, n, bound)?;
        shared.armed.store(0, Ordering::Release);
        shared.done.store(0, Ordering::Release);
        let t0 = shared.now_ns();
        notifier.notify(shared, r)?;
        let t1 = shared.now_ns();
        shared.await_all(&shared.done, n, STUCK)?;
        if r as usize > WARMUP {
            let seen = shared.seen_ns.iter().map(|s| s.load(Ordering::Acquire));
            let (lo, hi) = seen.fold((u64::MAX, 0), |(lo, hi), t| (lo.min(t), hi.max(t)));
            notify.push(t1 - t0);
            first.push(lo.saturating_sub(t0));
            last.push(hi.saturating_sub(t0));
        }
    }
    // The waiters leave after the last round; nothing more to wake.
    Ok((notify, first, last))
}

/// What a waiter needs to set up its side of the mechanism.
#[derive(Clone, Copy)]
struct WaiterSide<'a> {
    mechanism: Mechanism,
    run: &'a RunId,
    /// The `eventfd` mechanism's descriptor (only the number crosses threads).
    eventfd: libc::c_int,
    /// The `hnav-bell` mechanism's bell.
    bell: Option<&'a Bell>,
}

/// One waiter: sets up its side of `mechanism`, then per commit announces it is armed,
/// waits until it sees the commit, and stamps when it did.
fn waiter(side: WaiterSide<'_>, shared: &Shared, k: usize, n: usize, total: u64) -> Result<()> {
    let rounds = |wait: &mut dyn FnMut(u64) -> Result<()>| -> Result<()> {
        for r in 1..=total {
            shared.arrive(&shared.armed, n);
            wait(r)?;
            shared.seen_ns[k].store(shared.now_ns(), Ordering::Release);
            shared.arrive(&shared.done, n);
        }
        Ok(())
    };
    let WaiterSide {
        mechanism,
        run,
        eventfd,
        bell,
    } = side;
    match mechanism {
        Mechanism::Hnav | Mechanism::HnavBell => {
            // An agent's commit receiver in its own node and `Waiter`, attached once; with
            // the bell, its listener is a bell listener and the waiter watches the bell.
            let transport = Transport::builder(run)
                .node_name(&format!("fanout-{k}"))
                .create()?;
            let qos = topics::commit_qos(n);
            let (receiver, watch) = match bell {
                Some(bell) => (
                    transport.bell_receiver::<u64>(topics::COMMIT, qos)?,
                    Some(bell.watch()?),
                ),
                None => (transport.receiver::<u64>(topics::COMMIT, qos)?, None),
            };
            let waiter = transport.waiter()?;
            let _attached = waiter.attach(&receiver)?;
            let _bell = watch.as_ref().map(|w| waiter.attach_bell(w)).transpose()?;
            let mut seen = 0;
            rounds(&mut |r| loop {
                receiver.drain_pending(|&v| seen = seen.max(v))?;
                if seen >= r {
                    return Ok(());
                }
                check(shared)?;
                if waiter.wait(Some(Instant::now() + RECHECK))? == Wake::Stop {
                    bail!("stopped by a signal");
                }
            })
        }
        Mechanism::Eventfd => {
            let epoll = edge_triggered_epoll(eventfd)?;
            rounds(&mut |r| eventfd_wait(&epoll, shared, r))
        }
        Mechanism::Futex => rounds(&mut |r| futex_wait(shared, r)),
    }
}

/// The notifying half of each mechanism.
enum Notifier {
    Hnav {
        // Declared before the transport so it is dropped first; boxed, a node is large.
        sender: Box<hnav_runtime::transport::Sender<u64>>,
        _transport: Box<Transport>,
    },
    Eventfd(Fd),
    Futex,
}

impl Notifier {
    fn open(mechanism: Mechanism, run: &RunId, n: usize, bell: Option<&Bell>) -> Result<Self> {
        Ok(match mechanism {
            Mechanism::Hnav | Mechanism::HnavBell => {
                let transport = Transport::builder(run)
                    .node_name("fanout-notifier")
                    .create()?;
                let mut sender = transport.sender::<u64>(topics::COMMIT, topics::commit_qos(n))?;
                if let Some(bell) = bell {
                    sender = sender.ringing(bell.try_clone()?);
                }
                Notifier::Hnav {
                    sender: Box::new(sender),
                    _transport: Box::new(transport),
                }
            }
            Mechanism::Eventfd => {
                // SAFETY: eventfd(2) with valid flags; the result is checked below.
                let fd = unsafe { libc::eventfd(0, libc::EFD_NONBLOCK | libc::EFD_CLOEXEC) };
                Notifier::Eventfd(Fd::checked(fd, "eventfd")?)
            }
            Mechanism::Futex => Notifier::Futex,
        })
    }

    /// The eventfd (only for the `eventfd` mechanism).
    fn eventfd(&self) -> libc::c_int {
        match self {
            Notifier::Eventfd(fd) => fd.0,
            _ => -1,
        }
    }

    /// Publishes commit `r` and wakes every waiter.
    fn notify(&self, shared: &Shared, r: u64) -> Result<()> {
        match self {
            Notifier::Hnav { sender, .. } => {
                sender.send(r)?;
            }
            Notifier::Eventfd(fd) => {
                shared.round.store(r, Ordering::Release);
                let one: u64 = 1;
                // SAFETY: writes the 8 bytes of a live local to an eventfd this value owns.
                let w = unsafe { libc::write(fd.0, (&one as *const u64).cast(), 8) };
                if w != 8 {
                    return Err(std::io::Error::last_os_error()).context("write eventfd");
                }
            }
            Notifier::Futex => {
                shared.round.store(r, Ordering::Release);
                shared.seq.fetch_add(1, Ordering::Release);
                futex::wake(&shared.seq, i32::MAX);
            }
        }
        Ok(())
    }
}

/// An owned file descriptor, closed on drop.
struct Fd(libc::c_int);

impl Fd {
    fn checked(fd: libc::c_int, what: &str) -> Result<Self> {
        if fd < 0 {
            return Err(std::io::Error::last_os_error()).context(what.to_string());
        }
        Ok(Fd(fd))
    }
}

impl Drop for Fd {
    fn drop(&mut self) {
        // SAFETY: the descriptor is owned by this value and closed once.
        unsafe {
            libc::close(self.0);
        }
    }
}

/// Another thread gave up; this one stops too.
#[derive(Debug)]
struct Aborted;

impl std::fmt::Display for Aborted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("stopped because another thread failed")
    }
}

impl std::error::Error for Aborted {}

/// Fails with [`Aborted`] when another thread gave up.
fn check(shared: &Shared) -> Result<()> {
    if shared.abort.load(Ordering::Relaxed) {
        return Err(Aborted.into());
    }
    Ok(())
}

/// An agent's own epoll watching the shared eventfd edge-triggered.
fn edge_triggered_epoll(eventfd: libc::c_int) -> Result<Fd> {
    // SAFETY: epoll_create1(2) with a valid flag; checked below.
    let epoll = Fd::checked(unsafe { libc::epoll_create1(libc::EPOLL_CLOEXEC) }, "epoll")?;
    let mut ev = libc::epoll_event {
        events: (libc::EPOLLIN | libc::EPOLLET) as u32,
        u64: 0,
    };
    // SAFETY: both descriptors are open; `ev` is a live local the kernel copies.
    let r = unsafe { libc::epoll_ctl(epoll.0, libc::EPOLL_CTL_ADD, eventfd, &mut ev) };
    if r != 0 {
        return Err(std::io::Error::last_os_error()).context("epoll_ctl");
    }
    Ok(epoll)
}

/// Waits in `epoll` until commit `r` is out. The round is stored before the eventfd write
/// and checked before each wait: a write after the check leaves an edge pending, which the
/// wait returns at once.
fn eventfd_wait(epoll: &Fd, shared: &Shared, r: u64) -> Result<()> {
    let mut ev = [libc::epoll_event { events: 0, u64: 0 }; 1];
    while shared.round.load(Ordering::Acquire) < r {
        check(shared)?;
        // SAFETY: `ev` is a live buffer of one event for the whole call.
        let got =
            unsafe { libc::epoll_wait(epoll.0, ev.as_mut_ptr(), 1, RECHECK.as_millis() as i32) };
        if got < 0 {
            let e = std::io::Error::last_os_error();
            if e.raw_os_error() != Some(libc::EINTR) {
                return Err(e).context("epoll_wait");
            }
        }
    }
    Ok(())
}

/// `FUTEX_WAIT` on the shared sequence word until commit `r` is out.
fn futex_wait(shared: &Shared, r: u64) -> Result<()> {
    loop {
        let s = shared.seq.load(Ordering::Acquire);
        if shared.round.load(Ordering::Acquire) >= r {
            return Ok(());
        }
        check(shared)?;
        futex::wait(&shared.seq, s, RECHECK)?;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every mechanism delivers every commit to every waiter (a lost wake-up would show as a
    /// 100 ms re-check, not a failure, so this checks delivery and the shape, not speed).
    #[test]
    fn every_mechanism_wakes_every_waiter_for_every_commit() {
        for m in [
            Mechanism::Hnav,
            Mechanism::HnavBell,
            Mechanism::Eventfd,
            Mechanism::Futex,
        ] {
            let p = measure(m, 3, 20).unwrap();
            assert_eq!(p.listeners, 3);
            assert_eq!(p.last.n, 20);
            assert!(p.first.p50_us() <= p.last.p50_us(), "{m:?}: {}", p.row());
        }
    }
}
