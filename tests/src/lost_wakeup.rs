//! The lost-wake-up reproducer: rounds of one sample from each of N senders to one receiver,
//! which acks every round to all of them (the coordinator's round and its commit fan-out).
//!
//! The receiver blocks in a [`Waiter`](hnav_runtime::transport::Waiter) between samples. A wait that ends without being
//! signalled while a sample is pending is a *miss*: the sample was published and its
//! notifier fired, yet the waiter slept. `tests/lost_wakeup.rs` runs both halves as
//! separate processes through `hnav-test-peer` and reads the receiver's [`Report`].

use std::fmt;
use std::sync::{Arc, Barrier};
use std::time::{Duration, Instant};

use hnav_runtime::transport::{Qos, RunId, Transport, TransportError, Wake};

/// One sample per sender per round.
const SAMPLES: &str = "lost-wakeup/samples";
/// One ack per round, from the receiver to every sender.
const ACKS: &str = "lost-wakeup/acks";
/// A sample is `round * SENDER_SPAN + sender`.
const SENDER_SPAN: u64 = 1 << 16;
/// How long a sender waits for an ack before it gives up (a bound, not a synchronisation).
const ACK_TIMEOUT: Duration = Duration::from_secs(60);

/// What the receiver counted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Report {
    /// Rounds run.
    pub rounds: u64,
    /// Senders per round.
    pub senders: u64,
    /// Samples received.
    pub samples: u64,
    /// Waits that ended unsignalled (timed out, or lasted the whole re-check) with samples
    /// pending: lost wake-ups.
    pub misses: u64,
    /// Misses after which the listener still held the data event: a notifier fired and
    /// sent the listener nothing.
    pub suppressed: u64,
    /// Waits that reached the timeout, with samples pending or not: with the re-check on,
    /// there must be none.
    pub timeouts: u64,
    /// Wall time of all rounds, in milliseconds.
    pub ms: u64,
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "LOST_WAKEUP rounds={} senders={} samples={} misses={} suppressed={} timeouts={} ms={}",
            self.rounds,
            self.senders,
            self.samples,
            self.misses,
            self.suppressed,
            self.timeouts,
            self.ms
        )
    }
}

impl Report {
    /// Parses the line [`Report`]'s `Display` writes; `None` if it is not one.
    pub fn parse(line: &str) -> Option<Report> {
        let mut fields = line.split_whitespace();
        if fields.next()? != "LOST_WAKEUP" {
            return None;
        }
        let mut r = Report::default();
        for field in fields {
            let (key, value) = field.split_once('=')?;
            let value: u64 = value.parse().ok()?;
            match key {
                "rounds" => r.rounds = value,
                "senders" => r.senders = value,
                "samples" => r.samples = value,
                "misses" => r.misses = value,
                "suppressed" => r.suppressed = value,
                "timeouts" => r.timeouts = value,
                "ms" => r.ms = value,
                _ => return None,
            }
        }
        Some(r)
    }

    /// Misses per round.
    pub fn miss_rate(&self) -> f64 {
        self.misses as f64 / self.rounds.max(1) as f64
    }
}

fn err(e: impl fmt::Display) -> String {
    e.to_string()
}

/// Receives `rounds` rounds of one sample from each of `senders`, acking each round; calls
/// `ready` once its ports exist. A wait lasts at most `timeout`; `recheck` is the waiter's
/// lost-wake-up re-check (`None`: off, so a wait ends only when signalled or timed out).
///
/// Like the process loops, it consumes its listener's events before every drain, also right
/// after the ack, when nothing has signalled it yet (the coordinator looks for candidates
/// right after its commit): that is when iceoryx2's race can strike.
pub fn receiver(
    t: &Transport,
    recheck: Option<Duration>,
    senders: u64,
    rounds: u64,
    timeout: Duration,
    ready: impl FnOnce(),
) -> Result<Report, String> {
    let q = Qos::reliable(senders as usize);
    let rx = t.receiver::<u64>(SAMPLES, q).map_err(err)?;
    let acks = t.sender::<u64>(ACKS, q).map_err(err)?;
    let waiter = t.waiter().map_err(err)?.with_recheck(recheck);
    let _attached = waiter.attach(&rx).map_err(err)?;
    ready();
    // A data wake-up after this long was (most likely) the re-check, not a notification.
    let unsignalled_after = recheck.map_or(Duration::MAX, |r| r.mul_f64(0.9));
    let mut n = Report {
        rounds,
        senders,
        ..Report::default()
    };
    let started = Instant::now();
    for round in 0..rounds {
        let mut got = 0;
        let mut bad = None;
        let mut check = |v: &u64| {
            if v / SENDER_SPAN != round && bad.is_none() {
                bad = Some(format!("round {round}: got sample {v}"));
            }
        };
        let mut unsignalled = false;
        loop {
            let wake = rx.take_wakeup().map_err(err)?;
            let drained = rx.drain(&mut check).map_err(err)? as u64;
            got += drained;
            if unsignalled && drained > 0 {
                n.misses += 1;
                n.suppressed += u64::from(wake.data);
            }
            if got == senders {
                break;
            }
            let before = Instant::now();
            let wait = waiter.wait(Some(before + timeout)).map_err(err)?;
            unsignalled = match wait {
                Wake::Data => before.elapsed() >= unsignalled_after,
                Wake::TimedOut => {
                    n.timeouts += 1;
                    true
                }
                Wake::Stop => return Err("stopped by a signal".into()),
            };
        }
        if let Some(b) = bad {
            return Err(b);
        }
        n.samples += got;
        acks.send(round).map_err(err)?;
    }
    n.ms = started.elapsed().as_millis() as u64;
    Ok(n)
}

/// Runs `senders` senders on `threads` threads, each thread with its own node, and calls
/// `ready` once all of them have their ports. Every round, each thread sends one sample
/// through each of its senders' publishers, back to back (one thread with every sender is
/// `hnav-bench round`'s swarm), and waits for the round's ack.
pub fn senders(
    run: &RunId,
    senders: u64,
    threads: u64,
    rounds: u64,
    ready: impl FnOnce(),
) -> Result<(), String> {
    let threads = threads.clamp(1, senders.max(1));
    let barrier = Arc::new(Barrier::new(threads as usize + 1));
    let handles: Vec<_> = (0..threads)
        .map(|k| {
            let (run, barrier) = (run.clone(), Arc::clone(&barrier));
            let mine: Vec<u64> = (k..senders).step_by(threads as usize).collect();
            std::thread::spawn(move || sender_thread(&run, k, &mine, senders, rounds, &barrier))
        })
        .collect();
    barrier.wait();
    ready();
    for h in handles {
        h.join().map_err(|_| "a sender thread panicked")??;
    }
    Ok(())
}

fn sender_thread(
    run: &RunId,
    thread: u64,
    mine: &[u64],
    senders: u64,
    rounds: u64,
    barrier: &Barrier,
) -> Result<(), String> {
    let ports = (|| {
        let t = Transport::builder(run)
            .node_name(&format!("lw-senders-{thread}"))
            .create()?;
        let q = Qos::reliable(senders as usize);
        let txs = mine
            .iter()
            .map(|_| t.sender::<u64>(SAMPLES, q))
            .collect::<Result<Vec<_>, _>>()?;
        let acks = t.receiver::<u64>(ACKS, q)?;
        Ok::<_, TransportError>((t, txs, acks))
    })();
    // Every thread reaches the barrier, also one that failed, so that none waits forever.
    barrier.wait();
    let (t, txs, acks) = ports.map_err(err)?;
    let waiter = t.waiter().map_err(err)?;
    let _attached = waiter.attach(&acks).map_err(err)?;
    let mut acked: Option<u64> = None;
    for round in 0..rounds {
        for (tx, &i) in txs.iter().zip(mine) {
            tx.send(round * SENDER_SPAN + i).map_err(err)?;
        }
        let deadline = Instant::now() + ACK_TIMEOUT;
        loop {
            acks.drain_pending(|r| acked = acked.max(Some(*r)))
                .map_err(err)?;
            if acked >= Some(round) {
                break;
            }
            match waiter.wait(Some(deadline)).map_err(err)? {
                Wake::Data => {}
                Wake::TimedOut => return Err(format!("no ack of round {round}")),
                Wake::Stop => return Err("stopped by a signal".into()),
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_round_trip_through_their_line() {
        let r = Report {
            rounds: 10,
            senders: 3,
            samples: 30,
            misses: 2,
            suppressed: 1,
            timeouts: 2,
            ms: 1234,
        };
        assert_eq!(Report::parse(&r.to_string()), Some(r));
        assert_eq!(Report::parse("READY"), None);
    }
}
