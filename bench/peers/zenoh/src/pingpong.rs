//! The ping-pong of HNAV's latency suite (`bench/src/latency/pingpong.rs`), method for method:
//! two threads pinned to CPUs 0 and 1 when there are two, a common start, a shared
//! [`Instant`] epoch, warm-up iterations discarded, every measured iteration kept, sequence
//! numbers checked on both sides, and an abort flag so one side's failure cannot leave the
//! other blocked forever.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Result};

/// How long a blocking receive waits before it looks whether the other side gave up. Only
/// matters on failure: in a healthy run every wait ends long before this.
pub const ABORT_POLL: Duration = Duration::from_millis(200);

/// Bytes of the header in front of every payload: `stamp_ns` then `seq`, both u64 LE.
pub const HEADER_LEN: usize = 16;

/// The header of every sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stamp {
    /// Send time, ns since the ping-pong's shared epoch.
    pub stamp_ns: u64,
    /// Iteration number, checked by both sides so a lost sample fails the run.
    pub seq: u64,
}

impl Stamp {
    pub fn encode(self) -> [u8; HEADER_LEN] {
        let mut b = [0u8; HEADER_LEN];
        b[..8].copy_from_slice(&self.stamp_ns.to_le_bytes());
        b[8..].copy_from_slice(&self.seq.to_le_bytes());
        b
    }

    pub fn decode(b: &[u8; HEADER_LEN]) -> Self {
        let word = |i: usize| u64::from_le_bytes(b[i..i + 8].try_into().expect("8 bytes"));
        Self {
            stamp_ns: word(0),
            seq: word(8),
        }
    }
}

/// Which half of the ping-pong a thread plays.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// Stamps and sends, then waits for the echo: records round trips.
    Ping,
    /// Waits, records the one-way latency from the stamp, echoes.
    Pong,
}

#[derive(Debug)]
struct Aborted;

impl core::fmt::Display for Aborted {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("aborted because the other side failed")
    }
}

impl std::error::Error for Aborted {}

/// State shared by the two threads of one ping-pong.
pub struct PingPong {
    epoch: Instant,
    warmup: usize,
    iterations: usize,
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
            started: AtomicUsize::new(0),
            finished: AtomicUsize::new(0),
            abort: AtomicBool::new(false),
        }
    }

    /// Nanoseconds since the shared epoch; both threads read the same monotonic clock.
    #[inline]
    pub fn now_ns(&self) -> u64 {
        self.epoch.elapsed().as_nanos() as u64
    }

    /// Fails once the other side has given up.
    #[inline]
    pub fn check(&self) -> Result<()> {
        if self.abort.load(Ordering::Relaxed) {
            return Err(Aborted.into());
        }
        Ok(())
    }

    /// A barrier that can be abandoned (sleeps between checks: delays only the start).
    fn rendezvous(&self, point: &AtomicUsize) -> Result<()> {
        point.fetch_add(1, Ordering::AcqRel);
        while point.load(Ordering::Acquire) < 2 {
            self.check()?;
            std::thread::sleep(Duration::from_micros(50));
        }
        Ok(())
    }

    /// Waits for the other side, plays `role` for warm-up + measured iterations and returns
    /// the measured latencies in ns (round trips for Ping, one-way for Pong).
    pub fn run(
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
        // Both sides stay until both are done: the last echo must still be receivable.
        self.rendezvous(&self.finished)?;
        Ok(samples)
    }

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
pub struct Samples {
    /// Send-to-receive, measured by Pong from Ping's stamp.
    pub oneway: Vec<u64>,
    /// Send-to-echo-received, measured by Ping.
    pub roundtrip: Vec<u64>,
}

/// Whether the two sides get a CPU each: only with at least two CPUs.
pub fn pinning_possible() -> bool {
    std::thread::available_parallelism().is_ok_and(|n| n.get() >= 2)
}

fn pin_to(cpu: usize) {
    let mut set = nix::sched::CpuSet::new();
    // Pid 0 = the calling thread, so each side pins only itself.
    let pinned = set
        .set(cpu)
        .and_then(|()| nix::sched::sched_setaffinity(nix::unistd::Pid::from_raw(0), &set));
    if let Err(e) = pinned {
        eprintln!(
            "warning: could not pin the benchmark thread to CPU {cpu} ({e}); running unpinned"
        );
    }
}

/// Runs `ping` and `pong` on two threads (pinned to CPUs 0 and 1 when there are two) and
/// collects their samples.
pub fn run_pair<A, B>(warmup: usize, iterations: usize, ping: A, pong: B) -> Result<Samples>
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

    #[test]
    fn header_round_trips() {
        let s = Stamp {
            stamp_ns: 0x0102_0304_0506_0708,
            seq: 42,
        };
        assert_eq!(Stamp::decode(&s.encode()), s);
    }
}
