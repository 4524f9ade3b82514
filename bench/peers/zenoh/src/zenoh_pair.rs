//! One zenoh ping-pong: two sessions in one process connected over loopback TCP, a
//! publisher and a FIFO subscriber on each, and the two sides of [`crate::pingpong`].

use std::cell::RefCell;
use std::io::{Read, Write};
use std::net::{Ipv4Addr, TcpListener};
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, ensure, Context, Result};
use zenoh::bytes::ZBytes;
use zenoh::handlers::FifoChannelHandler;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::qos::CongestionControl;
use zenoh::sample::Sample;
use zenoh::shm::{GarbageCollect, PosixShmProviderBackend, ShmProvider, ShmProviderBuilder};
use zenoh::{Config, Session, Wait};

use crate::pingpong::{run_pair, PingPong, Role, Samples, Stamp, ABORT_POLL, HEADER_LEN};

/// How the payload travels between the two sessions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variant {
    /// Serialized over the TCP link (zenoh's shared memory switched off on both sessions).
    Plain,
    /// Allocated by Ping in zenoh shared memory (POSIX backend); only a reference crosses the
    /// TCP link, and Pong echoes that same reference back.
    Shm,
}

impl Variant {
    /// The transport part of the CSV `name` column.
    pub fn name(self) -> &'static str {
        match self {
            Self::Plain => "zenoh",
            Self::Shm => "zenoh-shm",
        }
    }
}

impl core::str::FromStr for Variant {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "zenoh" | "plain" => Ok(Self::Plain),
            "zenoh-shm" | "shm" => Ok(Self::Shm),
            _ => Err(format!(
                "unknown variant {s:?} (expected zenoh or zenoh-shm)"
            )),
        }
    }
}

/// The configuration of one session, as JSON5. `listen`/`connect` are zenoh endpoints.
///
/// Everything not set here is zenoh 1.10.2's default (`zenoh-config/src/defaults.rs`).
fn config_json5(variant: Variant, listen: &[String], connect: &[String]) -> String {
    let quote = |v: &[String]| {
        v.iter()
            .map(|e| format!("\"{e}\""))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let shm = variant == Variant::Shm;
    format!(
        r#"{{
  // Peer to peer: session A listens, session B connects to it; no router in between.
  mode: "peer",
  listen: {{ endpoints: [{listen}] }},
  connect: {{ endpoints: [{connect}] }},
  scouting: {{
    // Only the explicit loopback endpoint: no multicast discovery (it would find other zenoh
    // processes on the host), no gossip.
    multicast: {{ enabled: false }},
    gossip: {{ enabled: false }},
  }},
  transport: {{
    link: {{
      tx: {{
        // Zenoh's MTU: the largest batch, 2^16-1 (also the default). Messages above it are
        // fragmented: 40 MiB is 641 fragments.
        batch_size: 65535,
        queue: {{
          congestion_control: {{
            // The publishers use CongestionControl::Block, so nothing is ever dropped; a
            // blocked sender closes the session after this long (default 5 s). Raised to 60 s
            // so a 40 MiB message on a loaded 2-CPU machine cannot kill the run.
            block: {{ wait_before_close: 60000000 }},
          }},
        }},
      }},
      rx: {{
        // Receive-batch pool: 16 batches instead of 1 (the default, 65535 bytes), so a batch
        // still referenced by a received sample (Pong echoes it) does not make the reader
        // allocate and zero a fresh 64 KiB buffer.
        buffer_size: 1048560,
        // Largest defragmented message: 1 GiB (the default), well above 40 MiB + header.
        max_message_size: 1073741824,
      }},
    }},
    shared_memory: {{
      // Plain: off on both sessions, so every byte goes through TCP (with the feature built
      // in, zenoh 1.10 otherwise copies any payload >= 3 KiB into an implicit SHM pool).
      // Shm: on, so the two sessions negotiate SHM and Ping's buffers travel by reference.
      enabled: {shm},
      // Set the SHM subsystem up when the session opens, not on the first buffer.
      mode: "{mode}",
      // No implicit copying of large plain payloads into SHM: the shm variant allocates its
      // payloads in SHM itself, the plain variant must not use SHM at all.
      transport_optimization: {{ enabled: false }},
    }},
  }},
}}"#,
        listen = quote(listen),
        connect = quote(connect),
        mode = if shm { "init" } else { "lazy" },
    )
}

fn open(variant: Variant, listen: &[String], connect: &[String]) -> Result<Session> {
    let json = config_json5(variant, listen, connect);
    let config = Config::from_json5(&json).map_err(|e| anyhow!("zenoh config: {e}\n{json}"))?;
    zenoh::open(config)
        .wait()
        .map_err(|e| anyhow!("open zenoh session: {e}"))
}

/// A free TCP port on 127.0.0.1 (bound and released: zenoh binds it again right after).
fn free_port() -> Result<u16> {
    let l = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).context("bind 127.0.0.1:0")?;
    Ok(l.local_addr().context("local address")?.port())
}

type Sub = Subscriber<FifoChannelHandler<Sample>>;

/// One side's ports: it publishes on one key and subscribes to the other.
struct Ports {
    publisher: Publisher<'static>,
    subscriber: Sub,
}

fn declare(session: &Session, tx: String, rx: String) -> Result<Ports> {
    let publisher = session
        .declare_publisher(tx.clone())
        // Reliable delivery: block instead of dropping when the TX queue is full.
        .congestion_control(CongestionControl::Block)
        // Send each message at once instead of batching it with others (zenoh's advice for
        // latency; a ping-pong never has two messages to batch anyway).
        .express(true)
        .wait()
        .map_err(|e| anyhow!("declare publisher {tx}: {e}"))?;
    // The default handler: a FIFO channel (256 samples) with a blocking receive.
    let subscriber = session
        .declare_subscriber(rx.clone())
        .wait()
        .map_err(|e| anyhow!("declare subscriber {rx}: {e}"))?;
    Ok(Ports {
        publisher,
        subscriber,
    })
}

/// Waits until `publisher` sees the other session's subscriber, so the first put is not
/// sent to nobody.
fn wait_matching(publisher: &Publisher<'_>) -> Result<()> {
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let status = publisher
            .matching_status()
            .wait()
            .map_err(|e| anyhow!("matching status: {e}"))?;
        if status.matching() {
            return Ok(());
        }
        if Instant::now() > deadline {
            bail!(
                "publisher {} found no subscriber within 10 s",
                publisher.key_expr()
            );
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// How long a side may hear nothing before it counts the message as lost and fails the run.
/// In a ping-pong one message is in flight, so both sides would otherwise wait for ever (seen
/// once with zenoh-shm at 64 KiB); the dora peer has the same bound.
const LOST_AFTER: Duration = Duration::from_secs(10);

/// Waits for the next sample (blocking, waking up every [`ABORT_POLL`] to see whether the
/// other side gave up), fails after [`LOST_AFTER`] of silence, and checks the sample's length
/// and how it travelled.
fn receive(pp: &PingPong, sub: &Sub, variant: Variant, size: usize) -> Result<(Stamp, ZBytes)> {
    let mut silent = Duration::ZERO;
    let sample = loop {
        match sub
            .recv_timeout(ABORT_POLL)
            .map_err(|e| anyhow!("receive: {e}"))?
        {
            Some(s) => break s,
            None => {
                pp.check()?;
                silent += ABORT_POLL;
                ensure!(
                    silent < LOST_AFTER,
                    "{}: nothing received for {} s at size {size} B (a message was lost)",
                    variant.name(),
                    LOST_AFTER.as_secs()
                );
            }
        }
    };
    let payload = sample.payload();
    ensure!(
        payload.len() == HEADER_LEN + size,
        "received {} bytes, expected {}",
        payload.len(),
        HEADER_LEN + size
    );
    let in_shm = payload.as_shm().is_some();
    match variant {
        Variant::Shm => ensure!(
            in_shm,
            "zenoh-shm: a sample arrived as a copy, not as a shared-memory buffer \
             (SHM not negotiated between the sessions?)"
        ),
        Variant::Plain => ensure!(!in_shm, "zenoh: a sample arrived in shared memory"),
    }
    let mut header = [0u8; HEADER_LEN];
    payload
        .reader()
        .read_exact(&mut header)
        .context("read header")?;
    Ok((Stamp::decode(&header), payload.clone()))
}

/// Bytes of the SHM pool for messages of `len` bytes: room for four at once (Ping's next
/// buffer is allocated while the last one may still be referenced), page-rounded.
fn shm_pool_size(len: usize) -> usize {
    (4 * len).div_ceil(4096).max(16) * 4096
}

/// Runs one ping-pong of `size`-byte payloads (plus the header) and returns its samples.
pub fn measure(variant: Variant, size: usize, warmup: usize, iterations: usize) -> Result<Samples> {
    // Open both sessions and declare everything on this (unpinned) thread: zenoh starts its
    // runtime threads lazily, and a thread inherits its creator's CPU affinity, so creating
    // them from a pinned benchmark thread would squeeze zenoh's I/O onto that one CPU.
    let port = free_port()?;
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let a = open(variant, std::slice::from_ref(&endpoint), &[])
        .with_context(|| format!("session A listening on {endpoint}"))?;
    let b = open(variant, &[], std::slice::from_ref(&endpoint))
        .with_context(|| format!("session B connecting to {endpoint}"))?;
    let key = |dir: &str| format!("hnav/bench/{size}/{dir}");
    let ping = declare(&a, key("a2b"), key("b2a"))?;
    let pong = declare(&b, key("b2a"), key("a2b"))?;
    wait_matching(&ping.publisher)?;
    wait_matching(&pong.publisher)?;
    let provider = match variant {
        Variant::Plain => None,
        Variant::Shm => Some(
            ShmProviderBuilder::default_backend(shm_pool_size(HEADER_LEN + size))
                .wait()
                .map_err(|e| {
                    // Zenoh mlocks its SHM segments: without CAP_IPC_LOCK (root) the pool
                    // must fit in RLIMIT_MEMLOCK.
                    anyhow!(
                        "create a {} byte SHM provider: {e} (zenoh mlocks SHM: raise \
                         `ulimit -l` above that or run as root)",
                        shm_pool_size(HEADER_LEN + size)
                    )
                })?,
        ),
    };
    // Plain: the payload is allocated once and shared (a `ZBytes` clone is a reference
    // count); each message is a fresh 16-byte header followed by it, without copying.
    let payload = ZBytes::from(vec![0u8; size]);

    let samples = run_pair(
        warmup,
        iterations,
        |pp| ping_side(pp, &ping, provider.as_ref(), &payload, variant, size),
        |pp| pong_side(pp, &pong, variant, size),
    );
    drop((ping, pong));
    let closed = [a.close().wait(), b.close().wait()];
    let samples = samples?;
    for c in closed {
        c.map_err(|e| anyhow!("close zenoh session: {e}"))?;
    }
    Ok(samples)
}

fn ping_side(
    pp: &PingPong,
    ports: &Ports,
    provider: Option<&ShmProvider<PosixShmProviderBackend>>,
    payload: &ZBytes,
    variant: Variant,
    size: usize,
) -> Result<Vec<u64>> {
    let send = |stamp: Stamp| -> Result<()> {
        let message: ZBytes = match provider {
            None => {
                let mut w = ZBytes::writer();
                w.write_all(&stamp.encode()).context("write header")?;
                w.append(payload.clone());
                w.finish()
            }
            Some(provider) => {
                // A new SHM buffer per message, as zenoh requires: a buffer handed to `put`
                // is shared and immutable. The payload is not filled (as in HNAV: transfer,
                // not memset); GarbageCollect reclaims the buffers the echo released.
                let mut buf = provider
                    .alloc(HEADER_LEN + size)
                    .with_policy::<GarbageCollect>()
                    .wait()
                    .map_err(|e| anyhow!("allocate {} bytes of SHM: {e:?}", HEADER_LEN + size))?;
                buf[..HEADER_LEN].copy_from_slice(&stamp.encode());
                buf.into()
            }
        };
        ports
            .publisher
            .put(message)
            .wait()
            .map_err(|e| anyhow!("put: {e}"))
    };
    let recv = || receive(pp, &ports.subscriber, variant, size).map(|(stamp, _)| stamp);
    pp.run(Role::Ping, send, recv)
}

fn pong_side(pp: &PingPong, ports: &Ports, variant: Variant, size: usize) -> Result<Vec<u64>> {
    // The echo is the received payload itself: the same bytes (plain: re-serialized onto
    // the link; shm: the same shared-memory reference), no copy on our side.
    let last = RefCell::new(None::<ZBytes>);
    let send = |_: Stamp| -> Result<()> {
        let echo = last.borrow_mut().take().context("nothing to echo")?;
        ports
            .publisher
            .put(echo)
            .wait()
            .map_err(|e| anyhow!("put echo: {e}"))
    };
    let recv = || -> Result<Stamp> {
        let (stamp, payload) = receive(pp, &ports.subscriber, variant, size)?;
        *last.borrow_mut() = Some(payload);
        Ok(stamp)
    };
    pp.run(Role::Pong, send, recv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_configs_parse() {
        for v in [Variant::Plain, Variant::Shm] {
            let json = config_json5(v, &["tcp/127.0.0.1:7447".into()], &[]);
            Config::from_json5(&json).unwrap_or_else(|e| panic!("{e}\n{json}"));
        }
    }
}
