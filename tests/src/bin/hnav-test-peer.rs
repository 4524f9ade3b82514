//! A small process for the multi-process transport tests: one role per subcommand.
//!
//! Every role prints `READY` on stdout once its ports exist, so the test can sequence
//! processes without sleeping, and blocks in a WaitSet (never polls) while it waits.

use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::{Parser, Subcommand};
use hnav_runtime::msg::{Candidate, MapHeader};
use hnav_runtime::transport::{Qos, RunId, Transport};
use hnav_tests::pattern;
use iceoryx2::prelude::CallbackProgression;

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
    /// Receives `count` candidates in order, blocked in a WaitSet, then acks.
    RecvCandidates { count: u64 },
    /// Publishes one slice of `len` f32 pattern values written in place into loaned memory.
    PubSlice { len: usize },
    /// Receives one slice and checks its checksum against the pattern.
    RecvSlice { len: usize },
    /// Holds publishers and blocks until killed.
    Hold,
    /// Opens a sender and a receiver, prints READY and exits cleanly.
    Probe,
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

fn run(args: Args) -> Result<(), String> {
    let run = RunId::new(&args.run).map_err(|e| e.to_string())?;
    let name = match &args.role {
        Role::PubCandidates { .. } | Role::PubSlice { .. } => "sender",
        Role::RecvCandidates { .. } | Role::RecvSlice { .. } => "receiver",
        Role::Hold => "holder",
        Role::Probe => "probe",
    };
    let t = Transport::builder(&run)
        .node_name(name)
        .create()
        .map_err(|e| e.to_string())?;
    match args.role {
        Role::PubCandidates { count } => pub_candidates(&t, count),
        Role::RecvCandidates { count } => recv_candidates(&t, count),
        Role::PubSlice { len } => pub_slice(&t, len),
        Role::RecvSlice { len } => recv_slice(&t, len),
        Role::Hold => hold(&t),
        Role::Probe => {
            let _tx = t
                .sender::<Candidate>("candidates", qos())
                .map_err(|e| e.to_string())?;
            let _rx = t
                .receiver::<Candidate>("candidates", qos())
                .map_err(|e| e.to_string())?;
            ready();
            Ok(())
        }
    }
}

fn qos() -> Qos {
    Qos::reliable(2).with_buffer(256)
}

/// Blocks in a WaitSet on `listener` until `done` says so or [`PEER_TIMEOUT`] passes.
/// Returns the number of wake-ups.
fn wait_until(
    t: &Transport,
    listener: &iceoryx2::port::listener::Listener<hnav_runtime::transport::Ipc>,
    mut on_wake: impl FnMut() -> Result<bool, String>,
) -> Result<u64, String> {
    let ws = t.waitset().map_err(|e| e.to_string())?;
    let guard = ws
        .attach_deadline(listener, PEER_TIMEOUT)
        .map_err(|e| format!("{e:?}"))?;
    let mut wakeups = 0;
    let mut outcome: Result<bool, String> = Ok(false);
    ws.wait_and_process(|id| {
        if id.has_missed_deadline(&guard) {
            outcome = Err(format!("no event within {PEER_TIMEOUT:?}"));
            return CallbackProgression::Stop;
        }
        wakeups += 1;
        outcome = on_wake();
        match outcome {
            Ok(false) => CallbackProgression::Continue,
            _ => CallbackProgression::Stop,
        }
    })
    .map_err(|e| format!("{e:?}"))?;
    match outcome {
        Ok(true) => Ok(wakeups),
        Ok(false) => Err("interrupted".into()),
        Err(e) => Err(e),
    }
}

fn pub_candidates(t: &Transport, count: u64) -> Result<(), String> {
    let tx = t
        .sender::<Candidate>("candidates", qos())
        .map_err(|e| e.to_string())?;
    let ack = t.receiver::<u64>("ack", qos()).map_err(|e| e.to_string())?;
    ready();
    for round in 0..count {
        tx.send(Candidate {
            round,
            agent: (round % 7) as u32,
            current: round as u32,
            ..Candidate::default()
        })
        .map_err(|e| e.to_string())?;
    }
    let mut acked = None;
    wait_until(t, ack.listener(), || {
        ack.take_wakeup().map_err(|e| e.to_string())?;
        ack.drain(|v| acked = Some(*v)).map_err(|e| e.to_string())?;
        Ok(acked.is_some())
    })?;
    if acked != Some(count) {
        return Err(format!("receiver acked {acked:?}, sent {count}"));
    }
    Ok(())
}

fn recv_candidates(t: &Transport, count: u64) -> Result<(), String> {
    let rx = t
        .receiver::<Candidate>("candidates", qos())
        .map_err(|e| e.to_string())?;
    let ack = t.sender::<u64>("ack", qos()).map_err(|e| e.to_string())?;
    ready();
    let mut expected = 0u64;
    let mut empty_receives = 0u64;
    let mut bad: Option<String> = None;
    let started = Instant::now();
    let wakeups = wait_until(t, rx.listener(), || {
        rx.take_wakeup().map_err(|e| e.to_string())?;
        let n = rx
            .drain(|c| {
                if bad.is_none() && (c.round != expected || c.current != expected as u32) {
                    bad = Some(format!("expected round {expected}, got {}", c.round));
                }
                expected += 1;
            })
            .map_err(|e| e.to_string())?;
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
    ack.send(expected).map_err(|e| e.to_string())?;
    println!(
        "RECEIVED {expected} wakeups={wakeups} empty={empty_receives} ms={}",
        started.elapsed().as_millis()
    );
    Ok(())
}

fn pub_slice(t: &Transport, len: usize) -> Result<(), String> {
    let tx = t
        .slice_sender::<f32, MapHeader>("map/0", len, Qos::latest())
        .map_err(|e| e.to_string())?;
    let ack = t.receiver::<u64>("ack", qos()).map_err(|e| e.to_string())?;
    ready();
    let header = MapHeader {
        width: len as u32,
        height: 1,
        ..MapHeader::default()
    };
    tx.send_from_fn(header, len, pattern::slice_value)
        .map_err(|e| e.to_string())?;
    let mut acked = None;
    wait_until(t, ack.listener(), || {
        ack.take_wakeup().map_err(|e| e.to_string())?;
        ack.drain(|v| acked = Some(*v)).map_err(|e| e.to_string())?;
        Ok(acked.is_some())
    })?;
    Ok(())
}

fn recv_slice(t: &Transport, len: usize) -> Result<(), String> {
    let rx = t
        .slice_receiver::<f32, MapHeader>("map/0", Qos::latest())
        .map_err(|e| e.to_string())?;
    let ack = t.sender::<u64>("ack", qos()).map_err(|e| e.to_string())?;
    ready();
    let mut sum = None;
    wait_until(t, rx.listener(), || {
        rx.take_wakeup().map_err(|e| e.to_string())?;
        if let Some(sample) = rx.receive().map_err(|e| e.to_string())? {
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
    ack.send(sum).map_err(|e| e.to_string())?;
    println!("CHECKSUM {sum:016x}");
    Ok(())
}

fn hold(t: &Transport) -> Result<(), String> {
    let _candidates = t
        .sender::<Candidate>("candidates", qos())
        .map_err(|e| e.to_string())?;
    let _map = t
        .slice_sender::<f32, MapHeader>("map/0", 4096, Qos::latest())
        .map_err(|e| e.to_string())?;
    let never = t
        .receiver::<u64>("never", qos())
        .map_err(|e| e.to_string())?;
    ready();
    // Blocks until the test kills this process (or PEER_TIMEOUT passes).
    wait_until(t, never.listener(), || Ok(false)).map(|_| ())
}
