//! A small process for the multi-process transport tests: one role per subcommand.
//!
//! Every role prints `READY` on stdout once its ports exist, so the test can sequence
//! processes without sleeping, and blocks in a [`Waiter`](hnav_runtime::transport::Waiter) (never polls) while it waits.

use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::{Parser, Subcommand};
use hnav_runtime::msg::{Candidate, MapHeader};
use hnav_runtime::transport::{Qos, Receiver, RunId, Transport, Wake};
use hnav_tests::lost_wakeup;
use hnav_tests::pattern;

/// How long any role waits for its peer before giving up (a bound, not a synchronisation).
const PEER_TIMEOUT: Duration = Duration::from_secs(60);

#[derive(Parser)]
struct Args {
    /// The run id shared with the other processes of the test.
    #[arg(long)]
    run: String,
    #[command(subcommand)]
    role: Role,
}

#[derive(Subcommand)]
enum Role {
    /// Publishes `count` candidates with rounds 0..count, then waits for the receiver's ack.
    PubCandidates { count: u64 },
    /// Receives `count` candidates in order, blocked in a Waiter, then acks.
    RecvCandidates { count: u64 },
    /// Publishes one slice of `len` f32 pattern values written in place into loaned memory.
    PubSlice { len: usize },
    /// Receives one slice and checks its checksum against the pattern.
    RecvSlice { len: usize },
    /// Holds publishers and blocks until killed.
    Hold,
    /// Opens a sender and a receiver, prints READY and exits cleanly.
    Probe,
    /// Answers every `ping` with a `pong` of the same value until SIGINT/SIGTERM, then prints
    /// `STOPPED idle=<data wake-ups that found nothing> sticky=<a new waiter stops at once>`.
    WaitEcho,
    /// The lost-wake-up reproducer's receiver ([`lost_wakeup::receiver`]); prints its
    /// [`lost_wakeup::Report`].
    LostWakeupReceiver {
        /// Sending threads in the sender process.
        #[arg(long)]
        senders: u64,
        /// Rounds.
        #[arg(long)]
        rounds: u64,
        /// The waiter's lost-wake-up re-check in ms; 0 turns it off.
        #[arg(long)]
        recheck_ms: u64,
        /// How long one wait may last before it counts as timed out.
        #[arg(long, default_value_t = 1000)]
        timeout_ms: u64,
    },
    /// The lost-wake-up reproducer's senders ([`lost_wakeup::senders`]).
    LostWakeupSenders {
        /// Senders (publishers), one sample each per round.
        #[arg(long)]
        senders: u64,
        /// Threads the senders are spread over, each with its own node.
        #[arg(long)]
        threads: u64,
        /// Rounds.
        #[arg(long)]
        rounds: u64,
    },
}

fn main() -> ExitCode {
    hnav_runtime::logging::init();
    let args = Args::parse();
    match run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("hnav-test-peer: {e}");
            ExitCode::FAILURE
        }
    }
}

fn ready() {
    println!("READY");
}

fn err(e: impl std::fmt::Display) -> String {
    e.to_string()
}

fn run(args: Args) -> Result<(), String> {
    let run = RunId::new(&args.run).map_err(err)?;
    let name = match &args.role {
        Role::PubCandidates { .. } | Role::PubSlice { .. } => "sender",
        Role::RecvCandidates { .. } | Role::RecvSlice { .. } => "receiver",
        Role::Hold => "holder",
        Role::Probe => "probe",
        Role::WaitEcho => "echo",
        Role::LostWakeupReceiver { .. } => "lw-receiver",
        Role::LostWakeupSenders {
            senders,
            threads,
            rounds,
        } => return lost_wakeup::senders(&run, *senders, *threads, *rounds, ready),
    };
    let t = Transport::builder(&run)
        .node_name(name)
        .create()
        .map_err(err)?;
    match args.role {
        Role::PubCandidates { count } => pub_candidates(&t, count),
        Role::RecvCandidates { count } => recv_candidates(&t, count),
        Role::PubSlice { len } => pub_slice(&t, len),
        Role::RecvSlice { len } => recv_slice(&t, len),
        Role::Hold => hold(&t),
        Role::Probe => {
            let _tx = t.sender::<Candidate>("candidates", qos()).map_err(err)?;
            let _rx = t.receiver::<Candidate>("candidates", qos()).map_err(err)?;
            ready();
            Ok(())
        }
        Role::WaitEcho => wait_echo(&t),
        Role::LostWakeupReceiver {
            senders,
            rounds,
            recheck_ms,
            timeout_ms,
        } => {
            let recheck = Some(Duration::from_millis(recheck_ms)).filter(|d| !d.is_zero());
            let timeout = Duration::from_millis(timeout_ms);
            let report = lost_wakeup::receiver(&t, recheck, senders, rounds, timeout, ready)?;
            println!("{report}");
            Ok(())
        }
        Role::LostWakeupSenders { .. } => unreachable!("handled above"),
    }
}

fn qos() -> Qos {
    Qos::reliable(2).with_buffer(256)
}

/// Blocks in a Waiter on `rx` until `on_wake` says done, or no event comes for
/// [`PEER_TIMEOUT`]. Returns the number of wake-ups.
fn wait_until<P, H>(
    t: &Transport,
    rx: &Receiver<P, H>,
    mut on_wake: impl FnMut() -> Result<bool, String>,
) -> Result<u64, String>
where
    P: std::fmt::Debug + iceoryx2::prelude::IceoryxSend + ?Sized + 'static,
    H: std::fmt::Debug + iceoryx2::prelude::ZeroCopySend + 'static,
{
    let waiter = t.waiter().map_err(err)?;
    let _attached = waiter.attach(rx).map_err(err)?;
    let mut wakeups = 0;
    loop {
        match waiter
            .wait(Some(Instant::now() + PEER_TIMEOUT))
            .map_err(err)?
        {
            Wake::Data => {
                wakeups += 1;
                if on_wake()? {
                    return Ok(wakeups);
                }
            }
            Wake::TimedOut => return Err(format!("no event within {PEER_TIMEOUT:?}")),
            Wake::Stop => return Err("interrupted".into()),
        }
    }
}

fn pub_candidates(t: &Transport, count: u64) -> Result<(), String> {
    let tx = t.sender::<Candidate>("candidates", qos()).map_err(err)?;
    let ack = t.receiver::<u64>("ack", qos()).map_err(err)?;
    ready();
    for round in 0..count {
        tx.send(Candidate {
            round,
            agent: (round % 7) as u32,
            current: round as u32,
            ..Candidate::default()
        })
        .map_err(err)?;
    }
    let mut acked = None;
    wait_until(t, &ack, || {
        ack.take_wakeup().map_err(err)?;
        ack.drain(|v| acked = Some(*v)).map_err(err)?;
        Ok(acked.is_some())
    })?;
    if acked != Some(count) {
        return Err(format!("receiver acked {acked:?}, sent {count}"));
    }
    Ok(())
}

fn recv_candidates(t: &Transport, count: u64) -> Result<(), String> {
    let rx = t.receiver::<Candidate>("candidates", qos()).map_err(err)?;
    let ack = t.sender::<u64>("ack", qos()).map_err(err)?;
    ready();
    let mut expected = 0u64;
    let mut empty_receives = 0u64;
    let mut bad: Option<String> = None;
    let started = Instant::now();
    let wakeups = wait_until(t, &rx, || {
        rx.take_wakeup().map_err(err)?;
        let n = rx
            .drain(|c| {
                if bad.is_none() && (c.round != expected || c.current != expected as u32) {
                    bad = Some(format!("expected round {expected}, got {}", c.round));
                }
                expected += 1;
            })
            .map_err(err)?;
        if n == 0 {
            empty_receives += 1;
        }
        if let Some(b) = &bad {
            return Err(b.clone());
        }
        Ok(expected >= count)
    })?;
    if expected != count {
        return Err(format!("received {expected} candidates, expected {count}"));
    }
    ack.send(expected).map_err(err)?;
    println!(
        "RECEIVED {expected} wakeups={wakeups} empty={empty_receives} ms={}",
        started.elapsed().as_millis()
    );
    Ok(())
}

fn pub_slice(t: &Transport, len: usize) -> Result<(), String> {
    let tx = t
        .slice_sender::<f32, MapHeader>("map/0", len, Qos::latest())
        .map_err(err)?;
    let ack = t.receiver::<u64>("ack", qos()).map_err(err)?;
    ready();
    let header = MapHeader {
        width: len as u32,
        height: 1,
        ..MapHeader::default()
    };
    tx.send_from_fn(header, len, pattern::slice_value)
        .map_err(err)?;
    let mut acked = None;
    wait_until(t, &ack, || {
        ack.take_wakeup().map_err(err)?;
        ack.drain(|v| acked = Some(*v)).map_err(err)?;
        Ok(acked.is_some())
    })?;
    Ok(())
}

fn recv_slice(t: &Transport, len: usize) -> Result<(), String> {
    let rx = t
        .slice_receiver::<f32, MapHeader>("map/0", Qos::latest())
        .map_err(err)?;
    let ack = t.sender::<u64>("ack", qos()).map_err(err)?;
    ready();
    let mut sum = None;
    wait_until(t, &rx, || {
        rx.take_wakeup().map_err(err)?;
        if let Some(sample) = rx.receive().map_err(err)? {
            let header = *sample.user_header();
            let values: &[f32] = sample.payload();
            if values.len() != len || header.width as usize != len {
                return Err(format!(
                    "slice of {} elements (header width {}), expected {len}",
                    values.len(),
                    header.width
                ));
            }
            sum = Some(pattern::checksum(values));
        }
        Ok(sum.is_some())
    })?;
    let sum = sum.ok_or("no slice")?;
    ack.send(sum).map_err(err)?;
    println!("CHECKSUM {sum:016x}");
    Ok(())
}

fn hold(t: &Transport) -> Result<(), String> {
    let _candidates = t.sender::<Candidate>("candidates", qos()).map_err(err)?;
    let _map = t
        .slice_sender::<f32, MapHeader>("map/0", 4096, Qos::latest())
        .map_err(err)?;
    let never = t.receiver::<u64>("never", qos()).map_err(err)?;
    ready();
    // Blocks until the test kills this process (or PEER_TIMEOUT passes).
    wait_until(t, &never, || Ok(false)).map(|_| ())
}

fn wait_echo(t: &Transport) -> Result<(), String> {
    let pings = t.receiver::<u64>("ping", qos()).map_err(err)?;
    let pongs = t.sender::<u64>("pong", qos()).map_err(err)?;
    // No re-check: a data wake-up that finds nothing is then the interrupted wait itself.
    let waiter = t.waiter().map_err(err)?.with_recheck(None);
    let attached = waiter.attach(&pings).map_err(err)?;
    ready();
    let mut idle = 0u64;
    let mut woke = false;
    loop {
        pings.take_wakeup().map_err(err)?;
        let mut answered = 0;
        while let Some(ping) = pings.receive().map_err(err)? {
            pongs.send(*ping.payload()).map_err(err)?;
            answered += 1;
        }
        if woke && answered == 0 {
            idle += 1;
        }
        match waiter
            .wait(Some(Instant::now() + PEER_TIMEOUT))
            .map_err(err)?
        {
            Wake::Data => woke = true,
            Wake::TimedOut => return Err(format!("no ping within {PEER_TIMEOUT:?}")),
            Wake::Stop => break,
        }
    }
    drop(attached);
    let again = t.waiter().map_err(err)?;
    let _attached = again.attach(&pings).map_err(err)?;
    let sticky = again
        .wait(Some(Instant::now() + PEER_TIMEOUT))
        .map_err(err)?
        == Wake::Stop;
    println!("STOPPED idle={idle} sticky={sticky}");
    Ok(())
}
