//! `hnav-sim --run ID --scenario FILE [--periods N]`: the physics stepper of a run.

use clap::Parser;
use hnav_runtime::scenario::Scenario;
use hnav_runtime::transport::{RunId, Transport};
use hnav_sim::process::SimProcess;
use std::process::ExitCode;

#[derive(Parser)]
#[command(about = "HNAV physics stepper: wheel commands in, odometry and ground truth out")]
struct Args {
    /// Run id shared by the processes of the run.
    #[arg(long)]
    run: String,
    /// Scenario file (TOML).
    #[arg(long)]
    scenario: std::path::PathBuf,
    /// Stop after this many control periods (default: run until signalled).
    #[arg(long)]
    periods: Option<u64>,
}

fn main() -> ExitCode {
    hnav_runtime::logging::init();
    let args = Args::parse();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("hnav-sim: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let scenario = Scenario::load(&args.scenario)?;
    let run = RunId::new(&args.run)?;
    let transport = Transport::builder(&run).node_name("sim").create()?;
    let mut sim = SimProcess::new(&transport, &scenario)?;
    let out = sim.run(args.periods)?;
    println!(
        "periods={} collisions={} signalled={}",
        out.periods, out.collisions, out.signalled
    );
    Ok(())
}
