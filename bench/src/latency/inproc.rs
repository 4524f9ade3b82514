//! The in-process floors: what handing a sample from one thread to another costs when no
//! process boundary, no shared-memory segment and no socket is involved.
//!
//! - **crossbeam**: a `crossbeam-channel` pair carrying the payload buffer itself. Ping owns
//!   one buffer of `size` bytes, sends it, and gets the same buffer back as the echo: the
//!   payload moves by pointer (as iceoryx2's loans do), nothing is allocated or copied per
//!   iteration. `poll` spins on `try_recv`, `event` blocks in `recv`.
//! - **futex**: the bare wake-up. One 32-bit sequence word per direction; the sender stores
//!   the stamp, bumps the word and `FUTEX_WAKE`s it, the receiver `FUTEX_WAIT`s on the value
//!   it last saw. This is the least any blocking notification on Linux can cost, the
//!   reference the `event` rows of the other transports are read against.

use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

use anyhow::{bail, Context, Result};
use crossbeam_channel::{Receiver, RecvTimeoutError, Sender, TryRecvError};

use super::pingpong::{PingPong, Role, ABORT_POLL};
use super::sockets::{decode_header, encode_header, HEADER_LEN};
use super::{Mode, Stamp};
use crate::futex;

/// One direction of a crossbeam ping-pong: the buffers travel on it.
pub(crate) struct Lane {
    tx: Sender<Box<[u8]>>,
    rx: Receiver<Box<[u8]>>,
}

/// Both ends of both directions: `(ping's, pong's)`. Capacity 1 per direction, like the
/// one-sample buffer of the shared-memory services.
pub(crate) fn crossbeam_pair() -> (Lane, Lane) {
    let (a2b_tx, a2b_rx) = crossbeam_channel::bounded(1);
    let (b2a_tx, b2a_rx) = crossbeam_channel::bounded(1);
    (
        Lane {
            tx: a2b_tx,
            rx: b2a_rx,
        },
        Lane {
            tx: b2a_tx,
            rx: a2b_rx,
        },
    )
}

/// Plays `role` over `lane`, `size` payload bytes per sample, in `mode`.
pub(crate) fn crossbeam_side(
    pp: &PingPong,
    role: Role,
    lane: Lane,
    size: usize,
    mode: Mode,
) -> Result<Vec<u64>> {
    // Only Ping owns a buffer to start with; then each side holds the buffer it last
    // received until its next send (the echo sends back what it got).
    let slot = std::cell::RefCell::new(pp.setup(role, || {
        Ok((role == Role::Ping).then(|| vec![0u8; HEADER_LEN + size].into_boxed_slice()))
    })?);
    let recv_one = || -> Result<Box<[u8]>> {
        match mode {
            Mode::Poll => loop {
                match lane.rx.try_recv() {
                    Ok(buf) => return Ok(buf),
                    Err(TryRecvError::Empty) => pp.check()?,
                    Err(TryRecvError::Disconnected) => bail!("the other side hung up"),
                }
            },
            Mode::Event => loop {
                match lane.rx.recv_timeout(ABORT_POLL) {
                    Ok(buf) => return Ok(buf),
                    Err(RecvTimeoutError::Timeout) => pp.check()?,
                    Err(RecvTimeoutError::Disconnected) => bail!("the other side hung up"),
                }
            },
        }
    };
    let send = |stamp: Stamp| -> Result<()> {
        let mut buf = slot
            .borrow_mut()
            .take()
            .context("no buffer to send: the ping-pong lost one")?;
        encode_header(stamp, &mut buf);
        lane.tx
            .send(buf)
            .map_err(|_| anyhow::anyhow!("the other side hung up"))
    };
    let recv = || -> Result<Stamp> {
        let buf = recv_one()?;
        let stamp = decode_header(&buf);
        *slot.borrow_mut() = Some(buf);
        Ok(stamp)
    };
    pp.run(role, send, recv)
}

/// One direction of a futex ping-pong: the stamp and the word woken on.
#[derive(Debug, Default)]
pub(crate) struct FutexSlot {
    /// Bumped once per sample; the futex word.
    word: AtomicU32,
    stamp_ns: AtomicU64,
    seq: AtomicU64,
}

/// The two directions of a futex ping-pong, shared by both threads.
#[derive(Debug, Default)]
pub(crate) struct FutexPair {
    a2b: FutexSlot,
    b2a: FutexSlot,
}

impl FutexSlot {
    fn send(&self, stamp: Stamp) {
        self.stamp_ns.store(stamp.stamp_ns, Ordering::Relaxed);
        self.seq.store(stamp.seq, Ordering::Relaxed);
        // Release: the stamp is visible to whoever sees the new word.
        self.word.fetch_add(1, Ordering::Release);
        futex::wake(&self.word, 1);
    }

    /// Blocks until the word moves past `*seen`, then reads the stamp.
    fn recv(&self, pp: &PingPong, seen: &mut u32) -> Result<Stamp> {
        loop {
            let now = self.word.load(Ordering::Acquire);
            if now != *seen {
                *seen = now;
                return Ok(Stamp {
                    stamp_ns: self.stamp_ns.load(Ordering::Relaxed),
                    seq: self.seq.load(Ordering::Relaxed),
                });
            }
            futex::wait(&self.word, now, ABORT_POLL).context("futex wait")?;
            pp.check()?;
        }
    }
}

/// Plays `role` over `pair`. There is no payload to move: the row is the wake-up alone.
pub(crate) fn futex_side(pp: &PingPong, role: Role, pair: &FutexPair) -> Result<Vec<u64>> {
    pp.setup(role, || Ok(()))?;
    let (tx, rx) = match role {
        Role::Ping => (&pair.a2b, &pair.b2a),
        Role::Pong => (&pair.b2a, &pair.a2b),
    };
    let mut seen = rx.word.load(Ordering::Acquire);
    pp.run(
        role,
        |stamp| {
            tx.send(stamp);
            Ok(())
        },
        || rx.recv(pp, &mut seen),
    )
}

#[cfg(test)]
mod tests {
    use super::super::pingpong::run_pair;
    use super::*;

    #[test]
    fn crossbeam_moves_one_buffer_back_and_forth_in_both_modes() {
        for mode in [Mode::Poll, Mode::Event] {
            let (a, b) = crossbeam_pair();
            let s = run_pair(
                10,
                200,
                move |pp| crossbeam_side(pp, Role::Ping, a, 4096, mode),
                move |pp| crossbeam_side(pp, Role::Pong, b, 4096, mode),
            )
            .unwrap();
            assert_eq!((s.oneway.len(), s.roundtrip.len()), (200, 200));
        }
    }

    #[test]
    fn futex_ping_pong_loses_no_wake_up() {
        let pair = FutexPair::default();
        let s = run_pair(
            10,
            2000,
            |pp| futex_side(pp, Role::Ping, &pair),
            |pp| futex_side(pp, Role::Pong, &pair),
        )
        .unwrap();
        assert_eq!((s.oneway.len(), s.roundtrip.len()), (2000, 2000));
    }
}
