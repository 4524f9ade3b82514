//! `hnav`: the HNAV command line. Argument parsing only; the work is done by
//! `hnav_runtime::scenario` and `hnav_runtime::grid`.
//!
//! Exit codes: 0 all good, 1 checks ran and found problems (or the report could not be
//! written), 2 the input could not be loaded or is invalid (and for usage errors, via clap).
//! For `hnav check`: 0 the scenario is valid and its report written, 1 it is valid but the
//! report could not be written, 2 it is invalid or cannot be read (README, *Command line*).

mod clean_cmd;
mod kill_cmd;
mod log_cmd;
mod log_export_cmd;
mod log_replay_cmd;
mod ps_cmd;
mod run_cmd;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use hnav_runtime::grid::check::check_map;
use hnav_runtime::scenario::{default_out_dir, Scenario, ScenarioReport};

/// HNAV swarm-robot runtime.
#[derive(Parser, Debug)]
#[command(name = "hnav", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Load and validate a scenario, print a summary and write scenario-report.json.
    ///
    /// Exit 0 when the scenario is valid and the report is written, 1 when it is valid but
    /// the report cannot be written, 2 when it is invalid or cannot be read (`file:line:
    /// problem` on stderr).
    Check {
        /// The scenario TOML file.
        scenario: PathBuf,
        /// Output directory [default: target/hnav-out/NAME, NAME = the scenario name].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Use exactly N agents (the first N, or extra seeded random ones).
        #[arg(long, value_name = "N")]
        agents: Option<usize>,
        /// Seed for generated agents [default: the scenario's sim.seed].
        #[arg(long, value_name = "S")]
        seed: Option<u64>,
    },
    /// MovingAI map tools.
    Map {
        #[command(subcommand)]
        command: MapCommand,
    },
    /// Run a scenario end to end: sim, coordinator and one agent process per robot.
    Run(run_cmd::RunArgs),
    /// List the live runs on this machine and their processes.
    Ps(ps_cmd::PsArgs),
    /// Send a signal to one process of a live run (agent:N, coordinator or sim).
    Kill(kill_cmd::KillArgs),
    /// Remove what dead runs left behind (processes, shared memory, registry entries).
    Clean(clean_cmd::CleanArgs),
    /// Inspect a run's consensus log, replay a lockstep run, export a run to MCAP.
    Log {
        #[command(subcommand)]
        command: log_cmd::LogCommand,
    },
}

#[derive(Subcommand, Debug)]
enum MapCommand {
    /// Load a .map (and a .scen), validate every entry and check every optimal length.
    Check {
        /// The .map file.
        map: PathBuf,
        /// A .scen file to check against the map.
        #[arg(long)]
        scen: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    // The matches too, not only the parsed arguments: `hnav run` reads the order in which
    // its --kill, --term and --freeze were given from them.
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    match cli.command {
        Command::Check {
            scenario,
            out,
            agents,
            seed,
        } => check(scenario, out, agents, seed),
        Command::Map {
            command: MapCommand::Check { map, scen },
        } => map_check(map, scen),
        Command::Run(args) => run_cmd::run_command(args, matches.subcommand_matches("run")),
        Command::Kill(args) => kill_cmd::run(args),
        Command::Ps(args) => ps_cmd::run(args),
        Command::Clean(args) => clean_cmd::run(args),
        Command::Log { command } => log_cmd::run(command),
    }
}

fn check(
    path: PathBuf,
    out: Option<PathBuf>,
    agents: Option<usize>,
    seed: Option<u64>,
) -> ExitCode {
    let loaded = Scenario::load(&path).and_then(|s| match agents {
        Some(n) => {
            let seed = seed.unwrap_or(s.sim.seed);
            s.with_agent_count(n, seed)
        }
        None => Ok(s),
    });
    let scenario = match loaded {
        Ok(s) => s,
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let report = ScenarioReport::new(&scenario);
    hnav_runtime::out!("{}", report.render());
    let dir = out.unwrap_or_else(|| default_out_dir(&scenario.name));
    match report.write_json(&dir) {
        Ok(p) => {
            hnav_runtime::outln!("report    {}", p.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            hnav_runtime::errln!("error: {}: cannot write report: {e}", dir.display());
            ExitCode::from(1)
        }
    }
}

fn map_check(map: PathBuf, scen: Option<PathBuf>) -> ExitCode {
    match check_map(&map, scen.as_deref()) {
        Ok(c) => {
            hnav_runtime::out!("{}", c.render(20));
            if c.is_ok() {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(1)
            }
        }
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
