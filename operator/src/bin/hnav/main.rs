//! `hnav`: the HNAV command line, the binary of `hnav-operator`. Argument parsing and
//! printing only, one module per verb (`run_cmd`, `ps_cmd`, `top`, ...): a run and what
//! reads it back are this crate's library (`hnav_operator::supervisor`, `monitor`, `report`,
//! `export`); `hnav check`, `hnav map` and `hnav layout`, here, are thin calls into
//! `hnav_runtime::scenario`, `hnav_runtime::grid` and `hnav_runtime::msg`.
//!
//! Exit codes: 0 all good, 1 checks ran and found problems (or the report could not be
//! written), 2 the input could not be loaded or is invalid (and for usage errors, via clap).
//! For `hnav check`: 0 the scenario is valid (and the report asked for with `--report` is
//! written), 1 it is valid but that report could not be written, 2 it is invalid or cannot
//! be read (`docs/reference/cli.md`).

mod arg_values;
mod clean_cmd;
mod kill_cmd;
mod log_cmd;
mod log_export_cmd;
mod log_replay_cmd;
mod pager;
mod ps_cmd;
mod report_cmd;
mod run_cmd;
mod services_cmd;
mod top;
mod view_cmd;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use hnav_runtime::grid::check::check_map;
use hnav_runtime::scenario::report::REPORT_FILE;
use hnav_runtime::scenario::{Scenario, ScenarioReport};

/// HNAV swarm-robot runtime.
#[derive(Parser, Debug)]
#[command(name = "hnav", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Load and validate a scenario and print a summary (each agent's shortest path); with
    /// --report FILE also write it as JSON. Writes nothing else.
    ///
    /// Exit 0 when the scenario is valid (and the report asked for is written), 1 when it is
    /// valid but the report cannot be written, 2 when it is invalid or cannot be read
    /// (`file:line: problem` on stderr).
    Check {
        /// The scenario TOML file.
        scenario: PathBuf,
        /// Write the summary as JSON to FILE.
        #[arg(long, value_name = "FILE")]
        report: Option<PathBuf>,
        /// Write the summary as JSON to DIR/scenario-report.json (as --report does).
        #[arg(long, value_name = "DIR", conflicts_with = "report")]
        out: Option<PathBuf>,
        /// Use exactly N agents (the first N, or extra seeded random ones).
        #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = arg_values::agent_count)]
        agents: Option<usize>,
        /// Seed for generated agents [default: the scenario's sim.seed].
        #[arg(long, value_name = "S", allow_negative_numbers = true, value_parser = arg_values::seed)]
        seed: Option<u64>,
    },
    /// MovingAI map tools.
    Map {
        #[command(subcommand)]
        command: MapCommand,
    },
    /// Run a scenario end to end: sim, coordinator and the agents (one process per robot, or
    /// per `[run] agents_per_process` robots).
    Run(Box<run_cmd::RunArgs>),
    /// List the live runs on this machine and their processes.
    Ps(ps_cmd::PsArgs),
    /// Send a signal to one process of a live run (agent:N, coordinator, coordinator:ID or sim).
    Kill(kill_cmd::KillArgs),
    /// List a live run's topics with their publishers and subscribers.
    Services(services_cmd::ServicesArgs),
    /// Remove what dead runs left behind (processes, shared memory, registry entries).
    Clean(clean_cmd::CleanArgs),
    /// Draw a finished run's report (DIR/report.svg) again, with the neural maps of --agents.
    Report(report_cmd::ReportArgs),
    /// Watch a live run in the terminal: its map, robots, agents' states and processes.
    Top(top::TopArgs),
    /// Serve a live or finished run to Foxglove (WebSocket): map, robots, goals, routes,
    /// conflicts, speeds, decisions.
    View(view_cmd::ViewArgs),
    /// Inspect a run's consensus log, replay a lockstep run, export a run to MCAP.
    Log {
        #[command(subcommand)]
        command: log_cmd::LogCommand,
    },
    /// Print every payload's size, alignment and field offsets (for clients in other
    /// languages; the Python client's layout test reads it).
    #[command(hide = true)]
    Layout {
        /// As JSON.
        #[arg(long)]
        json: bool,
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
    /// Write a seeded random MovingAI .scen for a map to stdout: distinct starts and goals
    /// in its largest connected component, optimal lengths without corner cutting.
    Scen {
        /// The .map file.
        map: PathBuf,
        /// Entries to write (the largest N-agent instance it holds).
        #[arg(long, value_name = "N")]
        agents: usize,
        /// Seed of the random starts and goals.
        #[arg(long, value_name = "S", default_value_t = 1)]
        seed: u64,
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
            report,
            out,
            agents,
            seed,
        } => check(
            scenario,
            report.or_else(|| out.map(|d| d.join(REPORT_FILE))),
            agents,
            seed,
        ),
        Command::Map {
            command: MapCommand::Check { map, scen },
        } => map_check(map, scen),
        Command::Map {
            command: MapCommand::Scen { map, agents, seed },
        } => map_scen(map, agents, seed),
        Command::Run(args) => run_cmd::run_command(*args, matches.subcommand_matches("run")),
        Command::Kill(args) => kill_cmd::run(args),
        Command::Ps(args) => ps_cmd::run(args),
        Command::Clean(args) => clean_cmd::run(args),
        Command::Services(args) => services_cmd::run(args),
        Command::Report(args) => report_cmd::run(args),
        Command::Log { command } => log_cmd::run(command),
        Command::Layout { json } => {
            let table = hnav_runtime::layout::layouts();
            if json {
                hnav_runtime::outln!("{}", table.to_json());
            } else {
                hnav_runtime::out!("{}", table.render());
            }
            ExitCode::SUCCESS
        }
        Command::Top(args) => top::run(args),
        Command::View(args) => view_cmd::run(args),
    }
}

/// `hnav check`: `report` is the JSON file to write, if one was asked for.
fn check(
    path: PathBuf,
    report_file: Option<PathBuf>,
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
    let Some(file) = report_file else {
        return ExitCode::SUCCESS;
    };
    match report.write_json_to(&file) {
        Ok(()) => {
            hnav_runtime::outln!("report    {}", file.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            hnav_runtime::errln!("error: {}: cannot write report: {e}", file.display());
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

fn map_scen(map: PathBuf, agents: usize, seed: u64) -> ExitCode {
    use hnav_runtime::grid::{read_map_file, scen_gen::generate_scen, write_scen};
    let name = map
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let generated = read_map_file(&map)
        .map_err(|e| e.to_string())
        .and_then(|grid| generate_scen(&grid, &name, agents, seed).map_err(|e| e.to_string()));
    match generated {
        Ok(scen) => {
            hnav_runtime::out!("{}", write_scen(&scen));
            ExitCode::SUCCESS
        }
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
