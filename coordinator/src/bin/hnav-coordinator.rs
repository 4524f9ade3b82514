//! `hnav-coordinator --run ID --scenario FILE --dir DIR [--agents N] [--seed S] [--mode M]
//! [--replicas N --replica ID] [--resume]`: the central compute block of a run, or one replica
//! of it. Started by `hnav run`; see `hnav_coordinator::process`.

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
    /// This process is replica ID (1-based) of a replicated coordinator (the scenario's
    /// coordinator.replicas, or --replicas, is 3 or 5).
    #[arg(long, value_name = "ID")]
    replica: Option<u64>,
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
    let replicas = u64::from(scenario.coordinator.replicas);
    match args.replica {
        Some(id) if replicas == 1 || id == 0 || id > replicas => {
            return Err(format!(
                "--replica {id}: the run has {replicas} replica(s); ids run from 1 to {replicas} \
                 when coordinator.replicas is 3 or 5"
            )
            .into())
        }
        None if replicas > 1 => {
            return Err(format!("the run has {replicas} replicas: say which with --replica").into())
        }
        _ => {}
    }
    let index = args.replica.map_or(0, |id| id as u32);
    let transport = Transport::builder(&run)
        .node_name(&Role::Coordinator.node_name(index))
        .create()?;
    let mut coordinator = CoordinatorProcess::new(&transport, &scenario, &dir, args.replica)?;
    let out = coordinator.run(args.common.resume)?;
    tracing::info!(
        round = out.round,
        all_at_goal = out.all_at_goal,
        dropped = out.dropped,
        "coordinator done"
    );
    Ok(())
}
