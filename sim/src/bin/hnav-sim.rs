//! `hnav-sim --run ID --scenario FILE [--agents N] [--seed S] [--mode M] [--periods N]
//! [--standalone]`: the physics stepper of a run. Started by `hnav run`; see
//! `hnav_sim::process`.

use std::process::ExitCode;

use clap::Parser;
use hnav_runtime::criteria::files::SIM_FILE;
use hnav_runtime::launch::{process_main, LifecyclePorts, ProcessArgs};
use hnav_runtime::msg::Role;
use hnav_runtime::transport::Transport;
use hnav_sim::process::SimProcess;

#[derive(Parser)]
#[command(about = "HNAV physics stepper: wheel commands in, odometry and ground truth out")]
struct Args {
    #[command(flatten)]
    common: ProcessArgs,
    /// Stop after this many control periods (default: run until stopped).
    #[arg(long)]
    periods: Option<u64>,
    /// Run without a supervisor: no start handshake, no lifecycle events.
    #[arg(long)]
    standalone: bool,
}

fn main() -> ExitCode {
    process_main::<Args>("hnav-sim", run)
}

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let scenario = args.common.scenario()?;
    let run = args.common.run_id()?;
    let transport = Transport::builder(&run)
        .node_name(&Role::Sim.node_name(0))
        .create()?;
    let mut sim = SimProcess::new(&transport, &scenario)?.resuming(args.common.resume);
    if let Some(dir) = &args.common.dir {
        sim = sim.with_checkpoint(dir, &scenario);
    }
    if !args.standalone {
        let ports = LifecyclePorts::open(&transport, Role::Sim, 0, scenario.agents.len())?;
        sim = sim.with_lifecycle(ports);
    }
    let out = sim.run(args.periods)?;
    // The summary's energy and goal times; a run without them still counts.
    if let Some(dir) = &args.common.dir {
        if let Err(e) = sim.world().criteria().store(dir) {
            tracing::warn!("cannot write {}: {e}", dir.join(SIM_FILE).display());
        }
    }
    for c in sim.world().collisions() {
        tracing::warn!(
            t_s = c.time_ns as f64 * 1e-9,
            robot = c.robot,
            hit = ?c.hit,
            x = c.position.x,
            y = c.position.y,
            other_x = c.other_position.x,
            other_y = c.other_position.y,
            "collision"
        );
    }
    hnav_runtime::outln!(
        "periods={} collisions={} signalled={}",
        out.periods,
        out.collisions,
        out.signalled
    );
    Ok(())
}
