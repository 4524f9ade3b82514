//! HNAV between hosts: a ping-pong whose two sides live in two iceoryx2 domains joined only
//! by two `hnav-bridge`s ([`hnav_bridge::Bridge`], one thread each) over Zenoh on loopback
//! TCP. A sample goes iceoryx2 → bridge → Zenoh → bridge → iceoryx2 each way, so the
//! row sits beside the peers' raw `zenoh` row (same method, `bench/peers/zenoh`) to show what
//! the bridge adds.
//!
//! The payload is the neural-map topic's (`f32` activations with a `MapHeader`), the one
//! large payload a run forwards; the stamp rides in the header.

use std::net::{Ipv4Addr, TcpListener};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context, Result};

use hnav_bridge::session::Endpoints;
use hnav_bridge::topics::{Payload, TopicSpec};
use hnav_bridge::{Bridge, Stopper};
use hnav_runtime::msg::MapHeader;
use hnav_runtime::topics;
use hnav_runtime::transport::{purge_run, RunId, SliceReceiver, SliceSender, Transport};

use super::pingpong::{run_pair, PingPong, Role, Samples, ABORT_POLL};
use super::Stamp;

/// How long the two bridges get to find each other.
const CONNECT_TIMEOUT: Duration = Duration::from_secs(20);

/// The domains of the two "hosts".
const DOMAINS: [&str; 2] = ["lat-ping", "lat-pong"];

fn encode(stamp: Stamp) -> MapHeader {
    MapHeader {
        round: stamp.stamp_ns,
        iterations: stamp.seq as u32,
        target: (stamp.seq >> 32) as u32,
        ..MapHeader::default()
    }
}

fn decode(h: &MapHeader) -> Stamp {
    Stamp {
        stamp_ns: h.round,
        seq: u64::from(h.iterations) | (u64::from(h.target) << 32),
    }
}

/// Measures `size`-byte samples (a multiple of 4) through the bridges on topics
/// `<prefix>/{a2b,b2a}` of `run`.
pub(crate) fn measure(
    run: &RunId,
    prefix: &str,
    size: usize,
    warmup: usize,
    iterations: usize,
) -> Result<Samples> {
    let runs: Vec<RunId> = DOMAINS
        .iter()
        .map(|d| run.clone().in_domain(d))
        .collect::<Result<_, _>>()?;
    let specs: Vec<TopicSpec> = ["a2b", "b2a"]
        .iter()
        .map(|t| TopicSpec {
            topic: format!("{prefix}/{t}"),
            payload: Payload::Map,
            qos: topics::state_qos(),
            // Every sample is measured: none may be dropped.
            droppable: false,
        })
        .collect();
    let port = {
        let l = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).context("bind 127.0.0.1:0")?;
        l.local_addr()?.port()
    };
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let ends = [
        Endpoints {
            listen: vec![endpoint.clone()],
            ..Endpoints::default()
        },
        Endpoints {
            connect: vec![endpoint],
            ..Endpoints::default()
        },
    ];
    let out = std::thread::scope(|s| -> Result<Samples> {
        let (tx, rx) = mpsc::channel::<Result<Stopper>>();
        let mut threads = Vec::new();
        for (r, e) in runs.iter().zip(&ends) {
            let (tx, specs) = (tx.clone(), &specs);
            // Spawned from this (unpinned) thread: the bridges and Zenoh's own threads are
            // free to run on either CPU beside the two pinned benchmark sides.
            threads.push(s.spawn(move || -> Result<()> {
                let mut bridge = match Bridge::open(r, specs, e, None) {
                    Ok(b) => b,
                    Err(err) => {
                        let _ = tx.send(Err(anyhow!("open the bridge: {err}")));
                        return Ok(());
                    }
                };
                let connected = bridge.wait_connected(CONNECT_TIMEOUT);
                let _ = tx.send(if connected {
                    Ok(bridge.stopper())
                } else {
                    Err(anyhow!(
                        "the bridges did not connect within {CONNECT_TIMEOUT:?}"
                    ))
                });
                if connected {
                    bridge.run(None)?;
                }
                Ok(())
            }));
        }
        drop(tx);
        let mut stoppers = Vec::new();
        let mut failed = None;
        for _ in 0..2 {
            match rx.recv_timeout(CONNECT_TIMEOUT + Duration::from_secs(10)) {
                Ok(Ok(stop)) => stoppers.push(stop),
                Ok(Err(e)) => failed = Some(e),
                Err(_) => failed = Some(anyhow!("a bridge did not come up")),
            }
        }
        let samples = match failed {
            Some(e) => Err(e),
            None => run_pair(
                warmup,
                iterations,
                |pp| side(pp, Role::Ping, &runs[0], prefix, size),
                |pp| side(pp, Role::Pong, &runs[1], prefix, size),
            ),
        };
        for stop in &stoppers {
            stop.stop();
        }
        for t in threads {
            t.join()
                .map_err(|_| anyhow!("a bridge thread panicked"))??;
        }
        samples
    });
    for r in &runs {
        let _ = purge_run(r);
    }
    out
}

/// One side's ports; the transport (node) is declared last so it is dropped last.
struct Ports {
    tx: SliceSender<f32, MapHeader>,
    rx: SliceReceiver<f32, MapHeader>,
    transport: Transport,
}

fn side(pp: &PingPong, role: Role, run: &RunId, prefix: &str, size: usize) -> Result<Vec<u64>> {
    if !size.is_multiple_of(4) {
        bail!("{size} B is no whole number of f32 activations");
    }
    let len = size / 4;
    let (tx_topic, rx_topic) = role.topics();
    let ports = pp.setup(role, || -> Result<Ports> {
        let transport = Transport::builder(run)
            .node_name(role.node_name())
            .handle_signals(false)
            .create()?;
        let q = topics::state_qos();
        Ok(Ports {
            tx: transport.slice_sender(&format!("{prefix}/{tx_topic}"), len, q)?,
            rx: transport.slice_receiver(&format!("{prefix}/{rx_topic}"), q)?,
            transport,
        })
    })?;
    let send = |stamp: Stamp| -> Result<()> {
        let mut loan = ports.tx.loan(len)?;
        *loan.header_mut() = encode(stamp);
        // SAFETY: every bit pattern is an `f32`, and the chunk is shared memory the OS mapped
        // zero-filled that only ever held earlier samples, so every byte is initialised. Not
        // filling it is deliberate, as in the `hnav` row: we measure transfer, not memset.
        unsafe { loan.assume_init_and_send() }?;
        Ok(())
    };
    let waiter = ports.transport.waiter()?;
    let _attached = waiter.attach(&ports.rx)?;
    pp.run(role, send, || loop {
        waiter.wait(Some(Instant::now() + ABORT_POLL))?;
        ports.rx.take_wakeup()?;
        if let Some(s) = ports.rx.receive()? {
            return Ok(decode(s.user_header()));
        }
        pp.check()?;
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stamp_survives_the_map_header() {
        let s = Stamp {
            stamp_ns: 123_456_789,
            seq: (7 << 32) | 9,
        };
        let back = decode(&encode(s));
        assert_eq!((back.stamp_ns, back.seq), (s.stamp_ns, s.seq));
    }
}
