//! `hnav-bench`: HNAV's benchmarks, one subcommand each (see the library's table of contents).

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, Parser, Subcommand};

use hnav_bench::latency::{self, TransportKind};

#[derive(Debug, Parser)]
#[command(name = "hnav-bench", version, about = "HNAV benchmarks")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// One variant per benchmark; each carries its own argument struct so new subcommands
/// (`plan`, `sim`, ...) are added without touching the others.
#[derive(Debug, Subcommand)]
enum Command {
    /// One-way and round-trip latency: raw iceoryx2, HNAV transport, Unix socket, TCP.
    Latency(LatencyArgs),
}

#[derive(Debug, Args)]
struct LatencyArgs {
    /// 10,000 measured iterations per point instead of 100,000.
    #[arg(long)]
    quick: bool,
    /// Directory for latency.csv and latency-sockets.csv (created if missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Measure only these transports (iceoryx2, hnav, uds, tcp; comma-separated).
    #[arg(long, value_delimiter = ',', value_name = "TRANSPORT")]
    only: Vec<TransportKind>,
    /// Payload sizes in bytes (comma-separated).
    #[arg(long, value_delimiter = ',', value_name = "BYTES",
          default_values_t = latency::DEFAULT_SIZES)]
    sizes: Vec<usize>,
}

fn latency(args: LatencyArgs) -> Result<()> {
    let mut opts = latency::Options::new(args.quick, args.out);
    opts.only = args.only;
    opts.sizes = args.sizes;
    let report = latency::run(&opts)?;
    print!("{}", report.render());
    Ok(())
}

fn main() -> Result<()> {
    hnav_runtime::logging::init();
    match Cli::parse().command {
        Command::Latency(args) => latency(args),
    }
}
