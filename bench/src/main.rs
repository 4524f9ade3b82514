//! `hnav-bench`: HNAV's benchmarks, one subcommand each (see the library's table of contents).

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, Parser, Subcommand};

use hnav_agent::neural_map::Activation;
use hnav_agent::plan::PlanStop;
use hnav_bench::latency::{self, TransportKind};
use hnav_bench::plan::{self, PlannerKind};
use hnav_runtime::grid::Cell;

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
    /// One-way and round-trip latency, 8 B to 40 MiB: raw iceoryx2, the HNAV transport, Unix
    /// socket, TCP loopback, and the in-process floors (crossbeam channel, futex wake-up).
    Latency(LatencyArgs),
    /// Plan one query, or every entry of a MovingAI .scen file, with one of HNAV's planners.
    Plan(PlanCli),
    /// Seed 002's experiment (50x50 m, 1 m cells, 10/20/30 % random circular obstacles):
    /// A*, Basic Theta* and Lazy Theta*, ours beside the thesis's Table 3.1.
    Seed002(Seed002Cli),
    /// Physics stepper speed: robot-steps per second (differential drive, Hall ticks,
    /// collision checks) for N robots on one core.
    Sim(SimCli),
    /// Neural-map speed: updates per second and time per map, 20x20 to 1024x1024, tanh
    /// against linear, and plan queries corner to corner.
    NeuralMap {
        /// Spend 0.05 s a point instead of 0.3 s, and stop at 512x512.
        #[arg(long)]
        quick: bool,
    },
    /// Decision-round latency (all candidates in -> commit at every agent) against a real
    /// hnav-coordinator for 1..256 agents; with --faults, SIGKILL -> Down and rejoin latency.
    Round(hnav_bench::round::RoundArgs),
    /// Waking N waiting agents per commit: HNAV's publish + notify against one eventfd write
    /// and one futex wake (the notifier's cost and the last waiter's wake-up).
    Fanout(hnav_bench::fanout::FanoutArgs),
    /// The performance suite in one run (latency, round at 1..256 agents, neural map), each
    /// part's output in DIR and DIR/perf.md (for docs/explanation/performance.md).
    Perf {
        /// The smoke-check variant (under 2 minutes).
        #[arg(long)]
        quick: bool,
        /// Directory for every part's files and perf.md (created if missing).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Peer rows for the latency part (see `latency --peers`).
        #[arg(long, value_delimiter = ',', value_name = "FILE")]
        peers: Vec<PathBuf>,
    },
    /// Chaos campaign: seeded runs of a small swarm with agents, the coordinator or the sim
    /// killed or frozen; checks every run and prints a table and the recovery figures.
    Chaos(ChaosCli),
    /// MAPF benchmark: the first N entries of a MovingAI .scen run by a whole swarm
    /// (lockstep), per N and rules: robots at goal, collisions, makespan, sum of lengths
    /// against the .scen's lower bound, conflicts, replans, wall time, memory.
    Mapf(MapfCli),
    /// The coordinator's LaCAM search alone on MovingAI instances (up to thousands of agents,
    /// no robots): first solution, LaCAM*'s refinement within a wall-clock limit, sum of
    /// costs over the lower bound, configurations, peak memory of a child per instance.
    Lacam(hnav_bench::mapf::search_cli::LacamArgs),
    /// The seeds' experiments, ours beside the paper's tables (`hnav-bench experiment list`
    /// names them).
    Experiment(ExperimentCli),
    /// The deterministic simulation of the coordinator's replicated log: a sweep of seeds
    /// under nemeses (kill, pause, partitions, network, clock and disk faults), Raft's
    /// safety checked on every run; a table per nemesis, failures shrunk with their seed.
    RaftSim(hnav_bench::raft_sim::RaftSimArgs),
}

#[derive(Debug, Args)]
struct ExperimentCli {
    /// The experiment's name, or `list`.
    name: String,
    /// The reduced variant (under 30 s), as the tests run it.
    #[arg(long)]
    quick: bool,
    /// Print the figures as JSON instead of markdown.
    #[arg(long)]
    json: bool,
    /// Seed of the experiment's random stream.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Keep the run directories of experiments that run swarms, and print where they are.
    #[arg(long)]
    keep: bool,
    /// Only the swarm size of N robots, in experiments with several sizes.
    #[arg(long, value_name = "N")]
    robots: Option<usize>,
    /// The coordinator's rules (dissertation, pibt, lacam) in experiments that run swarms,
    /// instead of the experiment's own choice.
    #[arg(long, value_name = "RULES", value_parser = parse_rules)]
    rules: Option<hnav_runtime::scenario::Rules>,
    /// Only the variant of this name, in experiments that compare variants (dynamic:
    /// partial, rebuild, all-knowing).
    #[arg(long, value_name = "NAME", value_parser = parse_variant)]
    variant: Option<hnav_bench::experiment::dynamic::Variant>,
}

/// A variant of `hnav-bench experiment dynamic`.
fn parse_variant(name: &str) -> Result<hnav_bench::experiment::dynamic::Variant, String> {
    use hnav_bench::experiment::dynamic::Variant;
    named(&Variant::ALL, Variant::name, "variant", "variants", name)
}

/// A `[coordinator] rules` name.
fn parse_rules(name: &str) -> Result<hnav_runtime::scenario::Rules, String> {
    use hnav_runtime::scenario::Rules;
    named(&Rules::ALL, Rules::name, "rules", "rules", name)
}

/// The one of `all` called `name`, or an error that lists their names.
fn named<T: Copy>(
    all: &[T],
    name_of: fn(T) -> &'static str,
    what: &str,
    plural: &str,
    name: &str,
) -> Result<T, String> {
    all.iter()
        .copied()
        .find(|&t| name_of(t) == name)
        .ok_or_else(|| {
            let names: Vec<&str> = all.iter().map(|&t| name_of(t)).collect();
            format!(
                "no {what} called {name:?}; the {plural} are {}",
                names.join(", ")
            )
        })
}

fn experiment(args: ExperimentCli) -> Result<()> {
    use hnav_bench::experiment::{self, Options, EXPERIMENTS};
    if args.name == "list" {
        for e in EXPERIMENTS {
            println!("{:<16} {}", e.name, e.about);
        }
        return Ok(());
    }
    let options = Options {
        quick: args.quick,
        seed: args.seed,
        keep: args.keep,
        robots: args.robots,
        rules: args.rules,
        variant: args
            .variant
            .map(hnav_bench::experiment::dynamic::Variant::name),
    };
    let report = experiment::run(&args.name, options)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", report.markdown);
    }
    Ok(())
}

#[derive(Debug, Args)]
struct MapfCli {
    /// The MovingAI .map file.
    #[arg(long, value_name = "FILE", required_unless_present = "quick")]
    map: Option<PathBuf>,
    /// Its .scen file; instance N is its first N entries.
    #[arg(long, value_name = "FILE", required_unless_present = "quick")]
    scen: Option<PathBuf>,
    /// Instance sizes [default: 50,100,150,200,250; with --quick 8,16].
    #[arg(long, value_delimiter = ',', value_name = "N")]
    agents: Vec<usize>,
    /// Coordinator rules, each run at every size (the scenario's [coordinator] rules).
    #[arg(long, value_delimiter = ',', default_value = "lacam")]
    rules: Vec<String>,
    /// lockstep (the same log every time) or realtime.
    #[arg(long, default_value = "lockstep", value_parser = ["lockstep", "realtime"])]
    mode: String,
    /// The scenarios' time limit, simulated seconds in lockstep [default: 10 s per cell of
    /// the longest optimal path, at least 600 s].
    #[arg(long, value_name = "S")]
    time_limit_s: Option<f64>,
    /// Wall-clock cap of each run, start-up included; a run past it is stopped.
    #[arg(long, value_name = "S", default_value_t = 1800.0)]
    wall_limit_s: f64,
    /// Robots hosted by one agent process (the scenarios' [run] agents_per_process).
    #[arg(long, value_name = "K", default_value_t = 1)]
    agents_per_process: u32,
    /// The control rate, the scenarios' [sim] odometry_hz: one lockstep round a period, so
    /// 20 takes a fifth of the rounds of the default 100 for the same simulated time.
    #[arg(long, value_name = "HZ", value_parser = clap::value_parser!(u32).range(1..=1000))]
    odometry_hz: Option<u32>,
    /// One JSON object per run instead of the table.
    #[arg(long)]
    json: bool,
    /// Where each run gets its directory (<map>-<rules>-<N>/, replaced by the next run).
    #[arg(long, value_name = "DIR", default_value = "target/hnav-out/mapf")]
    out: PathBuf,
    /// A tiny instance: N = 8, 16 on maps/random-32-32-10 unless --map/--scen/--agents say
    /// otherwise.
    #[arg(long)]
    quick: bool,
}

fn mapf(args: MapfCli) -> Result<()> {
    use hnav_bench::mapf::{self, report, MapfConfig};
    let (quick_map, quick_scen) = mapf::quick_files();
    let agents = match (args.agents.is_empty(), args.quick) {
        (false, _) => args.agents,
        (true, true) => mapf::QUICK_AGENTS.to_vec(),
        (true, false) => vec![50, 100, 150, 200, 250],
    };
    if !(args.wall_limit_s > 0.0 && args.wall_limit_s.is_finite()) {
        anyhow::bail!("--wall-limit-s must be a positive number of seconds");
    }
    if args
        .time_limit_s
        .is_some_and(|t| !(t > 0.0 && t.is_finite()))
    {
        anyhow::bail!("--time-limit-s must be a positive number of seconds");
    }
    let config = MapfConfig {
        map: args.map.unwrap_or(quick_map),
        scen: args.scen.unwrap_or(quick_scen),
        agents,
        rules: args.rules,
        mode: args.mode,
        time_limit_s: args.time_limit_s,
        agents_per_process: args.agents_per_process,
        odometry_hz: args.odometry_hz,
        wall_limit: std::time::Duration::from_secs_f64(args.wall_limit_s),
        out: args.out,
        bin_dir: hnav_bench::swarm_run::bin_dir().map_err(anyhow::Error::msg)?,
    };
    let json = args.json;
    let rows = mapf::run_benchmark(
        &config,
        |line| hnav_runtime::errln!("{line}"),
        |row| {
            if json {
                hnav_runtime::out!("{}", report::render_json(std::slice::from_ref(row)));
            }
        },
    )
    .map_err(anyhow::Error::msg)?;
    if !json {
        hnav_runtime::out!("{}", report::render_table(&rows));
    }
    Ok(())
}

#[derive(Debug, Args)]
struct ChaosCli {
    /// Runs in all, split 30:10:5:5:5:4 over the classes [default: 118, or 59 with --quick].
    #[arg(long, value_name = "N")]
    runs: Option<usize>,
    /// The campaign's seed (every plan is drawn from it).
    #[arg(long, default_value_t = 12)]
    seed: u64,
    /// The campaign the test runs: 59 runs.
    #[arg(long)]
    quick: bool,
    /// Run only plan N of the campaign (numbered from 0, as the failures name them); its run
    /// directory is kept, passed or not.
    #[arg(long, value_name = "N")]
    only: Option<usize>,
    /// Only runs of one class: kill-agents, kill-coordinator, freeze-agent, kill-sim,
    /// kill-mix or kill-leader (the Raft leader of 3 replicas).
    #[arg(long, value_name = "CLASS")]
    class: Option<String>,
    /// Robots per agent process in every run (`[run] agents_per_process`); with 8, the
    /// chaos swarm's six robots share one process and every agent fault takes all six down.
    #[arg(long, value_name = "K", default_value_t = 1,
          value_parser = clap::value_parser!(u32).range(1..=256))]
    agents_per_process: u32,
}

fn chaos(args: ChaosCli) -> Result<()> {
    use hnav_bench::chaos::{run_campaign, CampaignConfig, FULL_RUNS, QUICK_RUNS};
    let bin_dir = hnav_bench::swarm_run::bin_dir().map_err(anyhow::Error::msg)?;
    let default_runs = if args.quick { QUICK_RUNS } else { FULL_RUNS };
    let class = match args.class.as_deref() {
        None => None,
        Some(name) => Some(
            hnav_bench::chaos::plan::Class::from_slug(name).ok_or_else(|| {
                anyhow::anyhow!(
                    "--class {name}: no such class (kill-agents, kill-coordinator, freeze-agent, \
                 kill-sim, kill-mix, kill-leader)"
                )
            })?,
        ),
    };
    let config = CampaignConfig {
        runs: args.runs.unwrap_or(default_runs),
        seed: args.seed,
        only: args.only,
        class,
        bin_dir,
        agents_per_process: args.agents_per_process,
    };
    let report =
        run_campaign(&config, |line| hnav_runtime::outln!("{line}")).map_err(anyhow::Error::msg)?;
    hnav_runtime::out!("{}", report.render());
    match report.failures().len() {
        _ if report.passed() => Ok(()),
        0 => anyhow::bail!("no run of the campaign ran (every plan was skipped)"),
        n => anyhow::bail!("{n} of the campaign's runs failed"),
    }
}

#[derive(Debug, Args)]
struct SimCli {
    /// Robots in the world (each size given is measured in turn).
    #[arg(long, value_delimiter = ',', default_values_t = [1usize, 64, 1024])]
    robots: Vec<usize>,
    /// Wall-clock seconds of stepping per size.
    #[arg(long, default_value_t = 2.0)]
    seconds: f64,
    /// One JSON object per size instead of a table.
    #[arg(long)]
    json: bool,
}

fn sim(args: SimCli) -> Result<()> {
    if !args.json {
        hnav_runtime::outln!(
            "{:>8} {:>14} {:>10} {:>18}",
            "robots",
            "steps",
            "seconds",
            "robot-steps/s"
        );
    }
    for robots in args.robots {
        let r = hnav_bench::sim::robot_steps_per_second(robots, args.seconds)?;
        if args.json {
            hnav_runtime::outln!("{}", serde_json::to_string(&r)?);
        } else {
            hnav_runtime::outln!(
                "{:>8} {:>14} {:>10.2} {:>18.3e}",
                r.robots,
                r.steps,
                r.elapsed_s,
                r.robot_steps_per_s
            );
        }
    }
    Ok(())
}

#[derive(Debug, Args)]
struct Seed002Cli {
    /// Solvable maps per obstacle density.
    #[arg(long, default_value_t = 100)]
    trials: usize,
    /// Seed of the obstacle fields.
    #[arg(long, default_value_t = 2)]
    seed: u64,
    /// Timing repetitions per query (the best is kept).
    #[arg(long, default_value_t = 3)]
    repeats: usize,
}

fn seed002(args: Seed002Cli) -> Result<()> {
    use hnav_bench::seed002::{run, Seed002Config};
    let config = Seed002Config {
        trials: args.trials,
        seed: args.seed,
        timing_repeats: args.repeats,
        ..Seed002Config::default()
    };
    hnav_runtime::out!("{}", run(&config)?.render());
    Ok(())
}

#[derive(Debug, Args)]
struct PlanCli {
    /// The planner: astar, theta, lazy-theta (the coordinator's) or hnav (the neural map).
    #[arg(long)]
    planner: PlannerKind,
    /// The MovingAI .map file.
    #[arg(long, value_name = "FILE")]
    map: PathBuf,
    /// Start cell, MovingAI x (column), y (row).
    #[arg(long, value_name = "X,Y", value_parser = plan::parse_cell, requires = "goal", conflicts_with = "scen")]
    start: Option<Cell>,
    /// Goal cell.
    #[arg(long, value_name = "X,Y", value_parser = plan::parse_cell, requires = "start")]
    goal: Option<Cell>,
    /// Answer every entry of this .scen file instead (one line each, then a summary line).
    #[arg(long, value_name = "FILE")]
    scen: Option<PathBuf>,
    /// Only the first N entries of the .scen file.
    #[arg(long, value_name = "N", requires = "scen")]
    first: Option<usize>,
    /// Neural-map activation.
    #[arg(long, value_enum, default_value = "tanh")]
    activation: ActivationArg,
    /// Neural-map stop rule: partial (the start is reached) or full (every reachable cell).
    #[arg(long, value_enum, default_value = "partial")]
    stop: StopArg,
    /// Let diagonals pass between two blocked cells (the dissertation's reproductions);
    /// without it MovingAI's rule applies, in propagation and in the path.
    #[arg(long)]
    corner_cutting: bool,
    /// Print JSON lines instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum ActivationArg {
    Linear,
    Tanh,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum StopArg {
    Partial,
    Full,
}

fn plan_cmd(args: PlanCli) -> Result<()> {
    let json = args.json;
    let plan_args = plan::PlanArgs {
        planner: args.planner,
        map: args.map,
        endpoints: args.start.zip(args.goal),
        scen: args.scen.map(|s| (s, args.first)),
        activation: match args.activation {
            ActivationArg::Linear => Activation::Linear,
            ActivationArg::Tanh => Activation::Tanh,
        },
        stop: match args.stop {
            StopArg::Partial => PlanStop::Partial,
            StopArg::Full => PlanStop::Full,
        },
        corner_cutting: args.corner_cutting,
    };
    let summary = plan::run(&plan_args, |line| {
        if json {
            hnav_runtime::outln!("{}", serde_json::to_string(line).unwrap_or_default());
        } else {
            hnav_runtime::outln!("{}", plan::render(line));
        }
    })?;
    if let Some(s) = summary {
        if json {
            hnav_runtime::outln!("{}", serde_json::to_string(&s)?);
        } else {
            hnav_runtime::outln!("{}", s.render());
        }
    }
    Ok(())
}

#[derive(Debug, Args)]
struct LatencyArgs {
    /// 5,000 measured iterations per small point instead of 100,000 (larger sizes get a
    /// tenth or a hundredth of that either way): a smoke check of the whole suite.
    #[arg(long)]
    quick: bool,
    /// Directory for latency.csv, latency.md and latency.svg (created if missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Measure only these transports (iceoryx2, hnav, uds, tcp, crossbeam, futex, and
    /// hnav-bridge, hnav-waitset and uds-dgram, which are measured only when named here;
    /// comma-separated).
    #[arg(long, value_delimiter = ',', value_name = "TRANSPORT")]
    only: Vec<TransportKind>,
    /// Measure only these modes (poll, event; comma-separated).
    #[arg(long, value_delimiter = ',', value_name = "MODE")]
    modes: Vec<latency::Mode>,
    /// CSV files of peer rows written by `bench/peers/*/run.sh` (Zenoh, dora-rs), reported
    /// beside ours (comma-separated).
    #[arg(long, value_delimiter = ',', value_name = "FILE")]
    peers: Vec<PathBuf>,
    /// Payload sizes in bytes (comma-separated).
    #[arg(long, value_delimiter = ',', value_name = "BYTES",
          default_values_t = latency::DEFAULT_SIZES)]
    sizes: Vec<usize>,
}

fn latency(args: LatencyArgs) -> Result<()> {
    let mut opts = latency::Options::new(args.quick, args.out);
    opts.only = args.only;
    opts.peers = args.peers;
    opts.modes = args.modes;
    opts.sizes = args.sizes;
    let report = latency::run(&opts)?;
    hnav_runtime::out!("{}", report.render());
    Ok(())
}

fn main() -> std::process::ExitCode {
    hnav_runtime::logging::init();
    let outcome = match Cli::parse().command {
        Command::Latency(args) => latency(args),
        Command::Plan(args) => plan_cmd(args),
        Command::Seed002(args) => seed002(args),
        Command::Sim(args) => sim(args),
        Command::NeuralMap { quick } => {
            hnav_bench::neural_map::run(quick);
            Ok(())
        }
        Command::Round(args) => hnav_bench::round::main(args),
        Command::Fanout(args) => hnav_bench::fanout::run(&args).map(drop),
        Command::Perf { quick, out, peers } => {
            hnav_bench::perf::run(quick, &out, &peers).map(|md| {
                hnav_runtime::errln!("wrote {}", md.display());
            })
        }
        Command::Chaos(args) => chaos(args),
        Command::Mapf(args) => mapf(args),
        Command::Lacam(args) => hnav_bench::mapf::search_cli::main(args),
        Command::Experiment(args) => experiment(args),
        Command::RaftSim(args) => hnav_bench::raft_sim::main(args),
    };
    match outcome {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            // `{:#}` prints the whole context chain on one line, without a backtrace.
            hnav_runtime::errln!("error: {e:#}");
            std::process::ExitCode::from(2)
        }
    }
}
