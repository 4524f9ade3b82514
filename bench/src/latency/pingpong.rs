//! The ping-pong harness every transport runs in: two pinned threads, serialized set-up, a
//! common start, per-iteration time stamps, and an abort path so one side's failure cannot
//! leave the other blocked forever.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Result};

use super::Stamp;

/// How long a blocking receive waits before it looks whether the other side gave up.
/// Only matters on failure: in a healthy run every wait ends long before this.
pub(crate) const ABORT_POLL: Duration = Duration::from_millis(200);

/// Which half of the ping-pong a thread plays.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Role {
    /// Stamps and sends, then waits for the echo: records round trips.
    Ping,
    /// Waits, records the one-way latency from the stamp, echoes.
    Pong,
}

impl Role {
    /// The topics this side sends on and receives from.
    pub(crate) fn topics(self) -> (&'static str, &'static str) {
        match self {
            Role::Ping => ("a2b", "b2a"),
            Role::Pong => ("b2a", "a2b"),
        }
    }

    /// A node name for this side.
    pub(crate) fn node_name(self) -> &'static str {
        match self {
            Role::Ping => "bench-ping",
            Role::Pong => "bench-pong",
        }
    }
}

/// The error a side returns when it stopped because the other side failed.
#[derive(Debug)]
struct Aborted;

impl core::fmt::Display for Aborted {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("aborted because the other side failed")
    }
}

impl std::error::Error for Aborted {}

/// State shared by the two threads of one ping-pong.
pub(crate) struct PingPong {
    epoch: Instant,
    warmup: usize,
    iterations: usize,
    created: AtomicUsize,
    started: AtomicUsize,
    finished: AtomicUsize,
    abort: AtomicBool,
}

impl PingPong {
    fn new(warmup: usize, iterations: usize) -> Self {
        Self {
            epoch: Instant::now(),
            warmup,
            iterations,
            created: AtomicUsize::new(0),
            started: AtomicUsize::new(0),
            finished: AtomicUsize::new(0),
            abort: AtomicBool::new(false),
        }
    }

    /// Nanoseconds since the shared epoch; both threads read the same monotonic clock.
    #[inline]
    pub(crate) fn now_ns(&self) -> u64 {
        self.epoch.elapsed().as_nanos() as u64
    }

    /// Fails with [`Aborted`] once the other side has given up.
    #[inline]
    pub(crate) fn check(&self) -> Result<()> {
        if self.abort.load(Ordering::Relaxed) {
            return Err(Aborted.into());
        }
        Ok(())
    }

    /// Waits until both sides arrived at `point`, or fails once the other side gave up.
    ///
    /// A barrier that can be abandoned: `std::sync::Barrier` would leave one thread waiting
    /// forever if the other failed before reaching it. It sleeps briefly between checks,
    /// which only delays the start (the warm-up absorbs that), never a measured iteration.
    fn rendezvous(&self, point: &AtomicUsize) -> Result<()> {
        point.fetch_add(1, Ordering::AcqRel);
        while point.load(Ordering::Acquire) < 2 {
            self.check()?;
            std::thread::sleep(Duration::from_micros(50));
        }
        Ok(())
    }

    /// Runs `create` (port creation) with Ping strictly before Pong: Ping creates the services
    /// and Pong opens them, so the two never race in `open_or_create`.
    pub(crate) fn setup<T>(&self, role: Role, create: impl FnOnce() -> Result<T>) -> Result<T> {
        match role {
            Role::Ping => {
                let ports = create()?;
                self.rendezvous(&self.created)?;
                Ok(ports)
            }
            Role::Pong => {
                self.rendezvous(&self.created)?;
                create()
            }
        }
    }

    /// Waits for the other side, then plays `role` for warm-up + measured iterations and
    /// returns the measured latencies in ns (round trips for Ping, one-way for Pong).
    pub(crate) fn run(
        &self,
        role: Role,
        send: impl FnMut(Stamp) -> Result<()>,
        recv: impl FnMut() -> Result<Stamp>,
    ) -> Result<Vec<u64>> {
        self.rendezvous(&self.started)?;
        let samples = match role {
            Role::Ping => self.ping(send, recv)?,
            Role::Pong => self.pong(send, recv)?,
        };
        // Keep the ports alive until both sides are done: the last echo must still be
        // receivable when the pong side returns and drops its publisher.
        self.rendezvous(&self.finished)?;
        Ok(samples)
    }

    /// Passes `result` through; an error makes the other side stop waiting.
    fn give_up_on_error(&self, result: Result<Vec<u64>>) -> Result<Vec<u64>> {
        if result.is_err() {
            self.abort.store(true, Ordering::Relaxed);
        }
        result
    }

    fn ping(
        &self,
        mut send: impl FnMut(Stamp) -> Result<()>,
        mut recv: impl FnMut() -> Result<Stamp>,
    ) -> Result<Vec<u64>> {
        let mut out = Vec::with_capacity(self.iterations);
        for i in 0..self.warmup + self.iterations {
            let seq = i as u64;
            let sent = self.now_ns();
            send(Stamp {
                stamp_ns: sent,
                seq,
            })?;
            let echo = recv()?;
            let back = self.now_ns();
            if echo.seq != seq {
                bail!(
                    "ping expected echo {seq}, got {} (a sample was lost)",
                    echo.seq
                );
            }
            if i >= self.warmup {
                out.push(back - sent);
            }
        }
        Ok(out)
    }

    fn pong(
        &self,
        mut send: impl FnMut(Stamp) -> Result<()>,
        mut recv: impl FnMut() -> Result<Stamp>,
    ) -> Result<Vec<u64>> {
        let mut out = Vec::with_capacity(self.iterations);
        for i in 0..self.warmup + self.iterations {
            let ping = recv()?;
            let arrived = self.now_ns();
            if ping.seq != i as u64 {
                bail!(
                    "pong expected ping {i}, got {} (a sample was lost)",
                    ping.seq
                );
            }
            if i >= self.warmup {
                out.push(arrived.saturating_sub(ping.stamp_ns));
            }
            send(ping)?;
        }
        Ok(out)
    }
}

/// The measured latencies of one ping-pong.
#[derive(Debug)]
pub(crate) struct Samples {
    /// Send-to-receive, measured by Pong from Ping's stamp.
    pub oneway: Vec<u64>,
    /// Send-to-echo-received, measured by Ping.
    pub roundtrip: Vec<u64>,
}

/// Whether the two sides get a CPU each: only with at least two CPUs.
pub(crate) fn pinning_possible() -> bool {
    std::thread::available_parallelism().is_ok_and(|n| n.get() >= 2)
}

fn pin_to(cpu: usize) {
    let mut set = nix::sched::CpuSet::new();
    // Pid 0 = the calling thread, so each side pins only itself.
    let pinned = set
        .set(cpu)
        .and_then(|()| nix::sched::sched_setaffinity(nix::unistd::Pid::from_raw(0), &set));
    if let Err(e) = pinned {
        tracing::warn!(cpu, %e, "could not pin the benchmark thread; running unpinned");
    }
}

/// Runs `ping` and `pong` on two threads (pinned to CPUs 0 and 1 when there are two) and
/// collects their samples. Each side creates its own ports on its own thread, because
/// iceoryx2 `ipc` ports are `!Send`.
pub(crate) fn run_pair<A, B>(warmup: usize, iterations: usize, ping: A, pong: B) -> Result<Samples>
where
    A: FnOnce(&PingPong) -> Result<Vec<u64>> + Send,
    B: FnOnce(&PingPong) -> Result<Vec<u64>> + Send,
{
    let pp = PingPong::new(warmup, iterations);
    let pin = pinning_possible();
    let (a, b) = std::thread::scope(|s| {
        let pp = &pp;
        let a = s.spawn(move || {
            if pin {
                pin_to(0);
            }
            pp.give_up_on_error(ping(pp))
        });
        let b = s.spawn(move || {
            if pin {
                pin_to(1);
            }
            pp.give_up_on_error(pong(pp))
        });
        let join = |h: std::thread::ScopedJoinHandle<'_, Result<Vec<u64>>>| {
            h.join()
                .unwrap_or_else(|_| Err(anyhow!("benchmark thread panicked")))
        };
        (join(a), join(b))
    });
    match (a, b) {
        (Ok(roundtrip), Ok(oneway)) => Ok(Samples { oneway, roundtrip }),
        // Report the side that failed first, not the one that stopped because of it.
        (Err(e), Err(other)) if e.is::<Aborted>() => Err(other),
        (Err(e), _) | (_, Err(e)) => Err(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An in-memory "transport": one slot per direction.
    struct Slot(std::sync::Mutex<Option<Stamp>>);

    impl Slot {
        fn put(&self, s: Stamp) -> Result<()> {
            *self.0.lock().unwrap() = Some(s);
            Ok(())
        }

        fn take(&self, pp: &PingPong) -> Result<Stamp> {
            loop {
                if let Some(s) = self.0.lock().unwrap().take() {
                    return Ok(s);
                }
                pp.check()?;
                std::thread::yield_now();
            }
        }
    }

    #[test]
    fn a_ping_pong_keeps_exactly_the_measured_iterations() {
        let (a2b, b2a) = (Slot(Default::default()), Slot(Default::default()));
        let side = |pp: &PingPong, role: Role| {
            let (tx, rx) = if role == Role::Ping {
                (&a2b, &b2a)
            } else {
                (&b2a, &a2b)
            };
            pp.setup(role, || Ok(()))?;
            pp.run(role, |s| tx.put(s), || rx.take(pp))
        };
        let s = run_pair(5, 20, |pp| side(pp, Role::Ping), |pp| side(pp, Role::Pong)).unwrap();
        assert_eq!((s.oneway.len(), s.roundtrip.len()), (20, 20));
    }

    #[test]
    fn a_failing_side_stops_the_other_and_its_error_is_reported() {
        let blocked_forever = Slot(Default::default());
        let ping = |pp: &PingPong| {
            pp.setup(Role::Ping, || Ok(()))?;
            pp.run(Role::Ping, |_| Ok(()), || blocked_forever.take(pp))
        };
        let pong = |pp: &PingPong| {
            pp.setup(Role::Pong, || -> Result<()> { bail!("cannot open ports") })?;
            unreachable!()
        };
        let err = run_pair(1, 1, ping, pong).unwrap_err();
        assert!(err.to_string().contains("cannot open ports"), "{err}");
    }
}
