//! `hnav-agent --run ID --scenario FILE --index I [--agents N] [--seed S] [--mode M] [--dir D]
//! [--resume]`: one robot's agent. Started by `hnav run`; see `hnav_agent::process`.

use std::process::ExitCode;

use clap::Parser;
use hnav_agent::process::AgentProcess;
use hnav_runtime::launch::{process_main, ProcessArgs};
use hnav_runtime::msg::Role;
use hnav_runtime::transport::Transport;

#[derive(Parser)]
#[command(about = "HNAV agent: neural map, path constructor and wheel controller of one robot")]
struct Args {
    #[command(flatten)]
    common: ProcessArgs,
    /// Agent index (0-based).
    #[arg(long)]
    index: u32,
}

fn main() -> ExitCode {
    process_main::<Args>("hnav-agent", run)
}

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let scenario = args.common.scenario()?;
    let run = args.common.run_id()?;
    let transport = Transport::builder(&run)
        .node_name(&Role::Agent.node_name(args.index))
        .create()?;
    let mut agent = AgentProcess::new(&transport, &args.common, &scenario, args.index)?;
    let out = agent.run(args.common.resume)?;
    tracing::info!(
        agent = args.index,
        periods = out.periods,
        last_commit = out.last_commit,
        at_goal = out.at_goal,
        "agent done"
    );
    Ok(())
}
