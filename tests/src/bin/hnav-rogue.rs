//! `hnav-rogue --run ID --scenario S --class CLASS [--for-s X] [--seed N]`: a hostile process
//! for the tests. It joins a live run like any of its processes (same run id, same services),
//! follows the commits to learn the open round, and publishes forged candidates
//! ([`hnav_tests::rogue`]): one class at about one per 2 ms, or every class in turn as fast
//! as the transport takes them (`--class flood`). It takes one spare publisher slot on the
//! candidate topic and one spare subscriber slot on the commit topic (each admits
//! `Qos::EXTRA_NODES` more than the swarm needs), so no real process loses its place.
//!
//! It prints `READY` once its ports exist, and `SENT <count> class=<count> ...` when it
//! stops: after `--for-s` seconds or on SIGINT/SIGTERM (exit 0), or on a transport error such
//! as the run's services going away (exit 2, with the error).

use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::Parser;
use hnav_runtime::msg::Candidate;
use hnav_runtime::rejected::Rejections;
use hnav_runtime::scenario::Scenario;
use hnav_runtime::topics;
use hnav_runtime::transport::{RunId, Transport, Wake};
use hnav_tests::rogue::{Attack, Forger};

/// Between two forged candidates of a single class.
const PACE: Duration = Duration::from_millis(2);
/// A flood looks for commits and for a stop request once per this many candidates.
const FLOOD_BATCH: u64 = 256;

#[derive(Parser)]
#[command(about = "HNAV test rogue: publishes hostile candidates into a live run")]
struct Args {
    /// The run to attack.
    #[arg(long)]
    run: String,
    /// The run's scenario (for its map and agents).
    #[arg(long)]
    scenario: std::path::PathBuf,
    /// What to send: agent, flags, priority-speed, cell, future-round, past-round or flood.
    #[arg(long)]
    class: String,
    /// How long to attack, in seconds [default: until stopped].
    #[arg(long)]
    for_s: Option<f64>,
    /// Seed of the forged values.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

fn main() -> ExitCode {
    hnav_runtime::logging::init();
    match run(&Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("hnav-rogue: {e}");
            ExitCode::from(2)
        }
    }
}

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let attack = Attack::from_name(&args.class).ok_or_else(|| {
        format!(
            "unknown --class {:?}; one of {}",
            args.class,
            Attack::names()
        )
    })?;
    let until = match args.for_s {
        Some(s) if (0.0..=1e6).contains(&s) => Some(Instant::now() + Duration::from_secs_f64(s)),
        Some(s) => return Err(format!("--for-s {s}: must be within [0, 1000000] s").into()),
        None => None,
    };
    let scenario = Scenario::load(&args.scenario)?;
    let n = scenario.agents.len();
    let run = RunId::new(&args.run)?;
    let transport = Transport::builder(&run).node_name("rogue").create()?;
    let candidates =
        transport.sender::<Candidate>(topics::CANDIDATES, topics::candidates_qos(n))?;
    let commits: topics::CommitReceiver =
        transport.slice_receiver(topics::COMMIT, topics::commit_qos(n))?;
    let waiter = transport.waiter()?;
    let _commits = waiter.attach(&commits)?;
    println!("READY");
    let mut forger = Forger::new(&scenario, args.seed);
    let mut sent = Rejections::default();
    let mut last_commit = 0;
    let mut i: u64 = 0;
    let end = loop {
        if until.is_some_and(|u| Instant::now() >= u) {
            break Ok(());
        }
        if attack != Attack::Flood || i.is_multiple_of(FLOOD_BATCH) {
            // A flood does not wait: the deadline of now only picks up commits and signals.
            let pause = if attack == Attack::Flood {
                Duration::ZERO
            } else {
                PACE
            };
            match waiter.wait(Some(Instant::now() + pause)) {
                Ok(Wake::Stop) => break Ok(()),
                Ok(_) => {}
                Err(e) => break Err(e),
            }
            if let Err(e) = commits.drain_pending(|h, _| last_commit = last_commit.max(h.round)) {
                break Err(e);
            }
        }
        let (class, c) = forger.next(attack, last_commit);
        match candidates.send(c) {
            Ok(_) => {
                sent.note(class);
            }
            Err(e) => break Err(e),
        }
        i += 1;
    };
    println!("SENT {} {sent}", sent.total());
    end.map_err(Into::into)
}
