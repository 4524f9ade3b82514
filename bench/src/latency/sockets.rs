//! Unix domain socket and TCP loopback: the copying baselines, with the same ping-pong; and a
//! Unix datagram pair, the floor of a wake-up by datagram.
//!
//! Each message is a 16-byte header (stamp, sequence number; little endian) followed by the
//! payload. Buffers are allocated once per side and reused, so the numbers are the kernel's
//! copy and wake-up cost, not the allocator's. Reads block, so these are `event` mode only.

use std::io::{ErrorKind, Read, Write};
use std::net::{Ipv4Addr, TcpListener, TcpStream};
use std::os::unix::net::{UnixDatagram, UnixStream};

use anyhow::{Context, Result};

use super::pingpong::{PingPong, Role, ABORT_POLL};
use super::Stamp;

/// Bytes of the header in front of every payload.
pub const HEADER_LEN: usize = 16;

/// A connected pair of Unix domain stream sockets.
pub(crate) fn uds_pair() -> Result<(UnixStream, UnixStream)> {
    UnixStream::pair().context("create unix socket pair")
}

/// A connected pair of TCP sockets over 127.0.0.1 on an ephemeral port, Nagle off (a
/// ping-pong of small messages would otherwise wait for delayed ACKs).
pub(crate) fn tcp_pair() -> Result<(TcpStream, TcpStream)> {
    let listener =
        TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).context("bind 127.0.0.1 ephemeral port")?;
    let addr = listener.local_addr().context("listener address")?;
    let client = TcpStream::connect(addr).with_context(|| format!("connect {addr}"))?;
    let (server, _) = listener.accept().context("accept")?;
    for s in [&client, &server] {
        s.set_nodelay(true).context("set TCP_NODELAY")?;
    }
    Ok((client, server))
}

/// Writes `stamp` into the first [`HEADER_LEN`] bytes of `buf`.
pub fn encode_header(stamp: Stamp, buf: &mut [u8]) {
    buf[..8].copy_from_slice(&stamp.stamp_ns.to_le_bytes());
    buf[8..HEADER_LEN].copy_from_slice(&stamp.seq.to_le_bytes());
}

/// Reads the stamp from the first [`HEADER_LEN`] bytes of `buf`.
pub fn decode_header(buf: &[u8]) -> Stamp {
    let word = |r: core::ops::Range<usize>| {
        let mut b = [0u8; 8];
        b.copy_from_slice(&buf[r]);
        u64::from_le_bytes(b)
    };
    Stamp {
        stamp_ns: word(0..8),
        seq: word(8..HEADER_LEN),
    }
}

/// Plays `role` over one end of a connected stream, `size` payload bytes per message.
///
/// Generic over the stream type so that UDS and TCP run identical code; `&S` must be
/// readable and writable (as `&UnixStream` and `&TcpStream` are), so sending and receiving
/// can borrow the one socket at the same time.
pub(crate) fn side<S>(pp: &PingPong, role: Role, stream: S, size: usize) -> Result<Vec<u64>>
where
    for<'a> &'a S: Read + Write,
{
    // Nothing to create: the pair was connected before the threads started. The set-up step
    // still runs, so both sides start together as with iceoryx2.
    let (mut tx_buf, mut rx_buf) = pp.setup(role, || {
        Ok((vec![0u8; HEADER_LEN + size], vec![0u8; HEADER_LEN + size]))
    })?;
    let send = |stamp: Stamp| -> Result<()> {
        encode_header(stamp, &mut tx_buf);
        (&stream).write_all(&tx_buf).context("write")
    };
    let recv = || -> Result<Stamp> {
        // A peer that failed drops its socket, so this read ends with an error, not a hang.
        (&stream).read_exact(&mut rx_buf).context("read")?;
        Ok(decode_header(&rx_buf))
    };
    pp.run(role, send, recv)
}

/// A connected pair of Unix datagram sockets whose blocking `recv` gives up after
/// [`ABORT_POLL`]: a peer that failed does not end a datagram socket's reads, as it ends a
/// stream's.
pub(crate) fn uds_dgram_pair() -> Result<(UnixDatagram, UnixDatagram)> {
    let (a, b) = UnixDatagram::pair().context("create unix datagram pair")?;
    for s in [&a, &b] {
        s.set_read_timeout(Some(ABORT_POLL))
            .context("set the receive timeout")?;
    }
    Ok((a, b))
}

/// Plays `role` over one end of a datagram pair: one datagram of header and `size` payload
/// bytes per message, received by one blocking `recv` (the timeout set once, not per call).
pub(crate) fn dgram_side(
    pp: &PingPong,
    role: Role,
    socket: UnixDatagram,
    size: usize,
) -> Result<Vec<u64>> {
    let (mut tx_buf, mut rx_buf) = pp.setup(role, || {
        Ok((vec![0u8; HEADER_LEN + size], vec![0u8; HEADER_LEN + size]))
    })?;
    let send = |stamp: Stamp| -> Result<()> {
        encode_header(stamp, &mut tx_buf);
        let sent = socket.send(&tx_buf).context("send")?;
        anyhow::ensure!(
            sent == tx_buf.len(),
            "sent {sent} of {} bytes",
            tx_buf.len()
        );
        Ok(())
    };
    let recv = || -> Result<Stamp> {
        loop {
            match socket.recv(&mut rx_buf) {
                Ok(n) if n == rx_buf.len() => return Ok(decode_header(&rx_buf)),
                Ok(n) => anyhow::bail!("received {n} of {} bytes", rx_buf.len()),
                // The timeout: look whether the other side gave up.
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                    pp.check()?;
                }
                Err(e) => return Err(e).context("recv"),
            }
        }
    };
    pp.run(role, send, recv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_round_trips() {
        let mut buf = [0u8; HEADER_LEN + 4];
        let stamp = Stamp {
            stamp_ns: 0x0102_0304_0506_0708,
            seq: 42,
        };
        encode_header(stamp, &mut buf);
        let back = decode_header(&buf);
        assert_eq!((back.stamp_ns, back.seq), (stamp.stamp_ns, stamp.seq));
    }
}
