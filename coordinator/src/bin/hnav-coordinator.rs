//! `hnav-coordinator --run ID --scenario FILE --dir DIR [--agents N] [--seed S] [--mode M]
//! [--resume]`: the central compute block of a run. Started by `hnav run`; see
//! `hnav_coordinator::process`.

use std::process::ExitCode;

use clap::Parser;
use hnav_coordinator::process::CoordinatorProcess;
use hnav_runtime::launch::{process_main, ProcessArgs};
use hnav_runtime::msg::Role;
use hnav_runtime::transport::Transport;

#[derive(Parser)]
#[command(about = "HNAV coordinator: conflict resolution, global replanning, consensus log")]
struct Args {
    #[command(flatten)]
    common: ProcessArgs,
}

fn main() -> ExitCode {
    process_main::<Args>("hnav-coordinator", run)
}

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let scenario = args.common.scenario()?;
    let run = args.common.run_id()?;
    let dir = args
        .common
        .dir
        .clone()
        .ok_or("--dir is required: the consensus log lives in DIR/log")?;
    let transport = Transport::builder(&run)
        .node_name(&Role::Coordinator.node_name(0))
        .create()?;
    let mut coordinator = CoordinatorProcess::new(&transport, &scenario, &dir)?;
    let out = coordinator.run(args.common.resume)?;
    tracing::info!(
        round = out.round,
        all_at_goal = out.all_at_goal,
        dropped = out.dropped,
        "coordinator done"
    );
    Ok(())
}
