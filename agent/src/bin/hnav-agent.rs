//! `hnav-agent --run ID --scenario FILE --index I [--count K] [--agents N] [--seed S]
//! [--mode M] [--dir D] [--resume]`: the agents of robots `I .. I+K` (one by default).
//! Started by `hnav run`; see `hnav_agent::process`.

use std::process::ExitCode;

use clap::Parser;
use hnav_agent::process::AgentProcess;
use hnav_runtime::launch::{process_main, ProcessArgs};
use hnav_runtime::msg::Role;
use hnav_runtime::transport::Transport;

#[derive(Parser)]
#[command(
    about = "HNAV agent: neural map, path constructor and wheel controller of a robot \
                   (or of several, one process hosting them)"
)]
struct Args {
    #[command(flatten)]
    common: ProcessArgs,
    /// Agent index (0-based): the process's first robot.
    #[arg(long)]
    index: u32,
    /// Robots this process hosts, from `--index` on (`[run] agents_per_process`).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    count: u32,
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
    let robots = (args.index, args.count);
    let mut process = AgentProcess::hosting(&transport, &args.common, &scenario, robots)?;
    let outcomes = process.run(args.common.resume)?;
    for (agent, out) in (args.index..).zip(outcomes) {
        tracing::info!(
            agent,
            periods = out.periods,
            last_commit = out.last_commit,
            at_goal = out.at_goal,
            "agent done"
        );
    }
    Ok(())
}
