//! `hnav-ros2 --run ID --scenario FILE [--agents N] [--seed S] [--mode M] [--domain-id D]
//! [--namespace NS] [--router ENDPOINT | --start-router | --listen ENDPOINT] [--rate-hz HZ]
//! [--robots]`: publishes
//! run ID as ROS 2 topics on rmw_zenoh's wire contract until the run stops (the supervisor's
//! `Stop`, SIGTERM/SIGINT, or its parent gone); then prints what it sent. Started by
//! `hnav run --ros2`; with `--robots` (a scenario of `[sim] kind = "ros2"`), it is the run's
//! sim instead, driving robots outside HNAV. See `hnav_ros2`.

use std::process::ExitCode;

use clap::Parser;
use hnav_ros2::outside::{drive, OutsideOptions};
use hnav_ros2::relay::{relay, RelayOptions, Topics};
use hnav_ros2::session::{self, Role, DEFAULT_ROUTER, OWN_ROUTER_LISTEN};
use hnav_runtime::launch::{process_main, ProcessArgs};
use hnav_runtime::scenario::SimKind;

#[derive(Parser)]
#[command(about = "HNAV's run as ROS 2 topics over rmw_zenoh's wire contract")]
struct Args {
    #[command(flatten)]
    common: ProcessArgs,
    /// `ROS_DOMAIN_ID` [default: the scenario's `[ros2] domain_id`, else 0].
    #[arg(long, value_name = "D")]
    domain_id: Option<u32>,
    /// Prefix of the robots' topics, e.g. `fleet` for `/fleet/robot_0/odom` [default: the
    /// scenario's `[ros2] namespace`, else none].
    #[arg(long, value_name = "NS")]
    namespace: Option<String>,
    /// The Zenoh router to join [default: the scenario's `[ros2] router`, else
    /// tcp/localhost:7447].
    #[arg(long, value_name = "ENDPOINT", conflicts_with = "start_router")]
    router: Option<String>,
    /// Be the router, listening on tcp/127.0.0.1:7447 (what `hnav run --ros2` asks for when
    /// no router answers there).
    #[arg(long, conflicts_with = "listen")]
    start_router: bool,
    /// Be the router, listening on ENDPOINT (`hnav-bench round --observers`: a free port).
    #[arg(long, value_name = "ENDPOINT", conflicts_with = "router")]
    listen: Option<String>,
    /// State messages (odometry, ground truth, plans, commands, /tf, markers) per second of
    /// wall clock.
    #[arg(long, value_name = "HZ", default_value_t = 20.0)]
    rate_hz: f64,
    /// Stand in for the sim: drive the scenario's robots outside HNAV through ROS 2
    /// (`[sim] kind = "ros2"`; the supervisor starts it so in the sim's slot).
    #[arg(long)]
    robots: bool,
}

fn main() -> ExitCode {
    process_main::<Args>("hnav-ros2", run)
}

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let scenario = args.common.scenario()?;
    let run = args.common.run_id()?;
    let ros2 = scenario.ros2.clone().unwrap_or_default();
    if !(args.rate_hz > 0.0 && args.rate_hz <= 1000.0) {
        return Err(format!("--rate-hz {}: must be in (0, 1000]", args.rate_hz).into());
    }
    let opts = RelayOptions {
        domain: args.domain_id.unwrap_or(ros2.domain_id),
        namespace: normalise_namespace(args.namespace.as_deref().unwrap_or(&ros2.namespace)),
        rate_hz: args.rate_hz,
    };
    let role = if let Some(listen) = &args.listen {
        Role::Router(listen.clone())
    } else if args.start_router {
        Role::Router(OWN_ROUTER_LISTEN.to_string())
    } else {
        let router = (args.router.clone())
            .or(ros2.router.clone())
            .unwrap_or_else(|| DEFAULT_ROUTER.to_string());
        Role::Peer(router)
    };
    if args.robots && scenario.sim.kind != SimKind::Ros2 {
        return Err(format!(
            "--robots: the scenario's [sim] kind is {:?}, not \"ros2\"",
            scenario.sim.kind.name()
        )
        .into());
    }
    let outside = args
        .robots
        .then(|| scenario.ros2.clone().unwrap_or_default());
    let session = session::open(&role)?;
    let source = outside.as_ref().map(|o| o.odometry);
    let mut topics = Topics::declare(session, scenario.agents.len(), &opts, source)?;
    tracing::info!(?role, node = topics.node.token(), "ros2 node up");
    for p in topics.publishers() {
        tracing::debug!(
            topic = p.topic(),
            key = p.key(),
            token = p.token(),
            "publisher"
        );
    }
    if let Some(ros2) = outside {
        let o = OutsideOptions {
            relay: opts,
            ros2,
            resume: args.common.resume,
            dir: args.common.dir.clone(),
        };
        let counts = drive(&run, &scenario, &mut topics, &o)?;
        hnav_runtime::outln!("{counts}");
        return Ok(());
    }
    let counts = relay(&run, &scenario, &mut topics, &opts)?;
    hnav_runtime::outln!("{counts}");
    Ok(())
}

/// `fleet`, `/fleet/` and `/fleet` are all `/fleet`; empty stays empty.
fn normalise_namespace(ns: &str) -> String {
    let ns = ns.trim_matches('/');
    if ns.is_empty() {
        String::new()
    } else {
        format!("/{ns}")
    }
}
