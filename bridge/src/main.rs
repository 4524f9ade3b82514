//! `hnav-bridge --run ID --agents N [--replicas N] [--hosts FILE --host NAME] [--listen EP]...
//! [--connect EP]... [--maps]`: forwards run ID's topics between this host's iceoryx2 domain and the other
//! hosts' bridges over Zenoh, until SIGTERM or SIGINT; then prints what it moved (`out=..
//! in=.. dropped=.. overflow=.. failed=..`). See `hnav_bridge`.
//!
//! With `--hosts FILE --host NAME` (what `hnav run --host` starts) the endpoints come from the
//! placement, and the bridge follows the other hosts: it announces itself `Up` on its host's
//! `ready` once it hears all of them, and tells its host when one is cut off and back. Where
//! the placement puts the coordinator's replicas on more than one host, their Raft messages
//! cross too.

use std::process::ExitCode;

use clap::Parser;
use hnav_bridge::hosts::{PeerHost, Peers};
use hnav_bridge::session::{Endpoints, Mode};
use hnav_bridge::{topics, Bridge};
use hnav_runtime::placement::Placement;
use hnav_runtime::transport::RunId;

#[derive(Parser)]
#[command(about = "HNAV bridge: a run's topics between hosts over Zenoh")]
struct Args {
    /// The run id (the same on every host).
    #[arg(long)]
    run: String,
    /// The run's agent count (with `--agents-per-process`, which `odom/<first>` and
    /// `wheels/<first>` topics exist).
    #[arg(long)]
    agents: usize,
    /// Robots per agent process (`[run] agents_per_process`): one `odom/<first>` and one
    /// `wheels/<first>` topic per process.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    agents_per_process: u32,
    /// Zenoh endpoint to listen on (`tcp/10.0.0.1:7447`); repeatable.
    #[arg(long)]
    listen: Vec<String>,
    /// Zenoh endpoint of another host's bridge (`tcp/10.0.0.2:7447`); repeatable.
    #[arg(long)]
    connect: Vec<String>,
    /// Also forward each agent's neural-map snapshots (`map/<i>`, up to megabytes each).
    #[arg(long)]
    maps: bool,
    /// The run's placement (`hosts.toml`): endpoints and the other hosts from there.
    #[arg(long, value_name = "FILE", requires = "host")]
    hosts: Option<std::path::PathBuf>,
    /// This host's name in the placement.
    #[arg(long, value_name = "NAME", requires = "hosts")]
    host: Option<String>,
    /// The run's coordinator replicas (1: a single coordinator): with the replicas on more
    /// than one host, their Raft inboxes `raft/<i>` cross too.
    #[arg(long, default_value_t = 1)]
    replicas: u32,
    /// Drop samples other than lifecycle events that a link cannot take instead of waiting:
    /// for realtime runs (`hnav run` passes it), never for lockstep.
    #[arg(long)]
    best_effort: bool,
}

fn main() -> ExitCode {
    hnav_runtime::logging::init();
    let args = Args::parse();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            hnav_runtime::errln!("hnav-bridge: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    if args.agents == 0 || args.agents > hnav_runtime::msg::MAX_AGENTS {
        return Err(format!(
            "--agents {}: a run has 1 to {} agents",
            args.agents,
            hnav_runtime::msg::MAX_AGENTS
        )
        .into());
    }
    let run = RunId::new(&args.run)?;
    let mut endpoints = Endpoints {
        listen: args.listen.clone(),
        connect: args.connect.clone(),
        ..Endpoints::default()
    };
    let mut peers = None;
    let mut specs = topics::run_topics(args.agents, args.agents_per_process, args.maps);
    if let (Some(file), Some(name)) = (&args.hosts, &args.host) {
        let placement = Placement::load(file, args.agents, args.replicas)?;
        if placement.replicas_apart() {
            specs.extend(topics::raft_topics(args.replicas));
        }
        let me = placement.index_of(name)?;
        endpoints
            .listen
            .extend(placement.hosts()[me].listen.iter().cloned());
        endpoints.connect.extend(placement.connect_of(me));
        endpoints.mode = if placement.is_hub(me) {
            Mode::Router
        } else {
            Mode::Client
        };
        peers = Some(Peers {
            me: name.clone(),
            index: me as u32,
            others: (placement.hosts().iter())
                .filter(|h| &h.name != name)
                .map(|h| PeerHost {
                    name: h.name.clone(),
                    agents: h.agents.clone(),
                })
                .collect(),
        });
    }
    if args.best_effort {
        topics::best_effort(&mut specs);
    }
    let mut bridge = Bridge::open(&run, &specs, &endpoints, peers)?;
    tracing::info!(run = run.as_str(), domain = ?run.domain(), "bridge up");
    hnav_runtime::outln!("ready");
    let counts = bridge.run(None)?;
    hnav_runtime::outln!("{counts}");
    Ok(())
}
