//! `hnav run SCENARIO [--agents N] [--mode lockstep|realtime] [--seed S] [--out DIR]
//! [--run ID] [--replicas N] [--force] [--no-record] [--bin-dir DIR]
//! [--kill|--term|--freeze TARGET@WHEN[+SECONDSs]]... [--host NAME [--hosts FILE]]
//! [--foxglove [ADDR]] [--ros2 [--ros2-router ENDPOINT]]`: the
//! supervisor. The work
//! is in `hnav_operator::supervisor::run`; the faults' syntax in
//! `hnav_runtime::scenario::fault_arg`.
//!
//! Exit codes: 0 every robot reached its goal without a collision, 1 the run ended otherwise
//! (time limit, collisions, stopped), 2 the run could not happen (bad scenario or fault, a process
//! that would not start, a run id or directory held by a live run, a finished run's
//! directory without `--force`), 3 the run was ended early because it could not go on (the
//! sim or the coordinator down and not restarted, no agent left, or an agent not restarted
//! under `[restart] on_give_up = "stop"`: the summary is still written; or a process stopped
//! on a full disk: no summary, the message names it and the directory), 4 the run finished
//! with robots lost (agents not restarted; the summary's `lost` names them and why).

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::ArgMatches;
use hnav_operator::supervisor::run::{
    default_run_dir, new_run_id, run, HostPart, Ros2Options, RunError, RunOptions,
};
use hnav_operator::supervisor::run_dir::RUN_OUTPUTS;
use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::scenario::fault_arg::{self, FaultArgError, FaultFlag};
use hnav_runtime::scenario::{ClockMode, FaultSpec, Scenario, SimKind};

/// The exit code of a run that started but could not go on (a process stopped on a full
/// disk): neither a finished run (0, 1) nor one that never started (2).
const EXIT_RUN_BROKEN: u8 = 3;
/// The exit code of a run that went on without the robots whose agents were not restarted,
/// and finished.
const EXIT_ROBOTS_LOST: u8 = 4;

/// `hnav run` arguments.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// The scenario TOML file.
    pub scenario: PathBuf,
    /// Use exactly N agents (the scenario's first N, or extra seeded random ones).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = crate::arg_values::agent_count)]
    pub agents: Option<usize>,
    /// Clock mode [default: the scenario's sim.clock].
    #[arg(long, value_name = "lockstep|realtime")]
    pub mode: Option<ClockMode>,
    /// Coordinator replicas agreeing on every round by Raft: 1, 3 or 5 [default: the
    /// scenario's coordinator.replicas].
    #[arg(long, value_name = "N")]
    pub replicas: Option<u32>,
    /// Seed of the sim's noise and of generated agents [default: the scenario's sim.seed].
    #[arg(long, value_name = "S", allow_negative_numbers = true, value_parser = crate::arg_values::seed)]
    pub seed: Option<u64>,
    /// Run directory (log, summary, process logs) [default: target/hnav-out/NAME, with --host
    /// HOST target/hnav-out/NAME-HOST].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Run id (letters, digits, '-', '_') [default: a fresh unique one]. Tests pass their own
    /// so they can clean the run's shared memory up even if the supervisor dies.
    #[arg(long, value_name = "ID")]
    pub run: Option<String>,
    /// Replace the outputs of a finished run in the run directory (every one a run writes
    /// there, listed in the help from `run_dir::RUN_OUTPUTS`); other files there are kept.
    #[arg(long, help = force_help())]
    pub force: bool,
    /// Write no recording (DIR/recording/: trajectories and neural maps); the report is then
    /// drawn without trajectories.
    #[arg(long)]
    pub no_record: bool,
    /// Where the process binaries are [default: next to this executable].
    #[arg(long, value_name = "DIR")]
    pub bin_dir: Option<PathBuf>,
    /// SIGKILL a process at a round or a time after Start, e.g. agent:3@round:40,
    /// coordinator@2.5s, sim@round:200 (repeatable; after the scenario's `[[faults]]`).
    #[arg(long, value_name = "TARGET@WHEN")]
    pub kill: Vec<String>,
    /// Like --kill, with SIGTERM.
    #[arg(long, value_name = "TARGET@WHEN")]
    pub term: Vec<String>,
    /// SIGSTOP a process, and SIGCONT it SECONDS later if +SECONDSs is given, e.g.
    /// agent:5@round:60+3s (repeatable).
    #[arg(long, value_name = "TARGET@WHEN[+SECONDSs]")]
    pub freeze: Vec<String>,
    /// Run this host's part of a run across hosts: its processes and its bridge, as the
    /// placement file says (every host runs the same command with its own NAME and the same
    /// --run ID). Its processes meet in the iceoryx2 domain NAME (HNAV_DOMAIN, if set, wins),
    /// so hosts of one run may share a machine.
    #[arg(long, value_name = "NAME")]
    pub host: Option<String>,
    /// The placement file for --host [default: hosts.toml beside the scenario].
    #[arg(long, value_name = "FILE", requires = "host")]
    pub hosts: Option<PathBuf>,
    /// Serve the run live to Foxglove (the Foxglove WebSocket protocol) on ADDR [default
    /// ADDR: 127.0.0.1:8765]; see docs/tutorials/watch-a-run-in-foxglove.md.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = hnav_operator::viewer::DEFAULT_ADDR)]
    pub foxglove: Option<String>,
    /// Publish the run as ROS 2 topics over rmw_zenoh (`hnav-ros2`; docs/reference/ros2.md),
    /// as a scenario's `[ros2]` does. Without a router at tcp/localhost:7447 (and no
    /// --ros2-router), one is started there for the run.
    #[arg(long)]
    pub ros2: bool,
    /// The Zenoh router of the ROS 2 graph (implies --ros2) [default: the scenario's `[ros2]
    /// router`, else tcp/localhost:7447].
    #[arg(long, value_name = "ENDPOINT")]
    pub ros2_router: Option<String>,
}

/// How `hnav-ros2` joins the ROS 2 graph, if the run is published (`--ros2`,
/// `--ros2-router` or `[ros2]`). With rmw_zenoh's default router and none answering there,
/// `hnav-ros2` is the router, and stderr says so.
fn ros2_options(ros2: bool, router: Option<&str>, s: &Scenario) -> Option<Ros2Options> {
    if !ros2 && router.is_none() && s.ros2.is_none() {
        return None;
    }
    let router = (router.map(String::from)).or_else(|| s.ros2.as_ref()?.router.clone());
    let tcp = |addr: &str| {
        use std::net::ToSocketAddrs;
        let timeout = std::time::Duration::from_millis(500);
        (addr.to_socket_addrs().into_iter().flatten())
            .any(|sa| std::net::TcpStream::connect_timeout(&sa, timeout).is_ok())
    };
    match &router {
        None if !tcp("localhost:7447") => {
            hnav_runtime::errln!(
                "ros2: no Zenoh router answers at tcp/localhost:7447: hnav-ros2 starts one there for this run (it ends with the run)"
            );
            return Some(Ros2Options {
                router: None,
                start_router: true,
            });
        }
        Some(r) if r.strip_prefix("tcp/").is_some_and(|addr| !tcp(addr)) => {
            hnav_runtime::errln!(
                "ros2: no Zenoh router answers at {r} yet: hnav-ros2 keeps trying to join it"
            );
        }
        _ => {}
    }
    Some(Ros2Options {
        router,
        start_router: false,
    })
}

/// `--force`'s help: the outputs it removes, from the one list the refusal also names.
fn force_help() -> String {
    format!(
        "Replace the outputs of a finished run in the run directory: {}; other files there are kept",
        RUN_OUTPUTS.join(", ")
    )
}

/// The command line's faults in the order they were written (`matches` says where each
/// came; without them, every --kill, then every --term, then every --freeze).
fn cli_faults(a: &RunArgs, matches: Option<&ArgMatches>) -> Vec<(FaultFlag, String)> {
    let mut faults: Vec<(usize, FaultFlag, String)> = Vec::new();
    for flag in FaultFlag::ALL {
        let values = match flag {
            FaultFlag::Kill => &a.kill,
            FaultFlag::Term => &a.term,
            FaultFlag::Freeze => &a.freeze,
        };
        let at: Vec<usize> = matches
            .and_then(|m| m.indices_of(flag.name()))
            .map(Iterator::collect)
            .unwrap_or_default();
        for (i, v) in values.iter().enumerate() {
            let pos = at.get(i).copied().unwrap_or(usize::MAX);
            faults.push((pos, flag, v.clone()));
        }
    }
    // Stable: without positions the flags' own order stays.
    faults.sort_by_key(|f| f.0);
    faults.into_iter().map(|(_, f, v)| (f, v)).collect()
}

/// Parses the command line's faults and checks them against `scenario`; the error names the
/// argument.
fn parse_faults(
    written: &[(FaultFlag, String)],
    scenario: &Scenario,
) -> Result<Vec<FaultSpec>, FaultArgError> {
    written
        .iter()
        .map(|(flag, value)| {
            let f = fault_arg::parse(*flag, value)?;
            fault_arg::check_target(*flag, value, &f, scenario.agents.len())?;
            Ok(f)
        })
        .collect()
}

pub fn run_command(a: RunArgs, matches: Option<&ArgMatches>) -> ExitCode {
    hnav_runtime::logging::init();
    let written = cli_faults(&a, matches);
    let run_id = a.run.unwrap_or_else(|| new_run_id().as_str().to_string());
    let mut args = ProcessArgs {
        agents: a.agents,
        seed: a.seed,
        mode: a.mode,
        replicas: a.replicas,
        ..ProcessArgs::new(run_id, a.scenario)
    };
    // The scenario as the processes will see it (--agents applied), so that a fault's agent
    // is checked against the run's agents before anything is spawned.
    let checked = args.scenario().map_err(|e| e.to_string()).and_then(|s| {
        let faults = parse_faults(&written, &s).map_err(|e| e.to_string())?;
        Ok((s, faults))
    });
    let placed = checked.and_then(|(s, faults)| {
        let host = match &a.host {
            None => None,
            Some(name) => {
                let file = a.hosts.clone().unwrap_or_else(|| {
                    let dir = args.scenario.parent().unwrap_or(std::path::Path::new(""));
                    dir.join(hnav_runtime::placement::DEFAULT_FILE)
                });
                let part = HostPart::load(&file, name, &s).map_err(|e| e.to_string())?;
                let all: Vec<_> = s.faults.iter().chain(&faults).cloned().collect();
                part.check_faults(&all, &s)?;
                Some(part)
            }
        };
        Ok((s, faults, host))
    });
    let (name, faults, host, ros2) = match placed {
        Ok((s, faults, host)) => {
            // Robots outside HNAV are reached through the ROS 2 graph whatever the flags.
            let outside = s.sim.kind == SimKind::Ros2;
            let ros2 = ros2_options(a.ros2 || outside, a.ros2_router.as_deref(), &s);
            (default_run_dir(&s, a.host.as_deref()), faults, host, ros2)
        }
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    args.faults = faults;
    let Some(bin_dir) = bin_dir(a.bin_dir) else {
        return ExitCode::from(2);
    };
    // Listening before anything is spawned: an address in use stops the run here.
    let view = match a
        .foxglove
        .as_deref()
        .map(|addr| crate::view_cmd::live(addr, &args))
    {
        Some(Err(code)) => return code,
        Some(Ok(view)) => Some(view),
        None => None,
    };
    let dir = a.out.unwrap_or(name);
    args.dir = Some(dir.clone());
    let opts = RunOptions {
        args,
        bin_dir,
        progress: std::io::stderr().is_terminal(),
        force: a.force,
        record: !a.no_record,
        host,
        ros2,
    };
    let result = run(&opts);
    drop(view);
    match result {
        Ok(summary) => {
            hnav_runtime::out!("{}", summary.render());
            hnav_runtime::outln!("summary   {}", dir.join("summary.json").display());
            if let Some(host) = &summary.counts_on_host {
                hnav_runtime::outln!("log       on host {host} (the coordinator's)");
            } else if summary.log.as_os_str().is_empty() {
                hnav_runtime::outln!("log       on the coordinator's host");
            } else {
                hnav_runtime::outln!("log       {}", summary.log.display());
            }
            if summary.report_error.is_none() && !summary.log.as_os_str().is_empty() {
                let report = dir.join(hnav_operator::report::FILE);
                hnav_runtime::outln!("report    {}", report.display());
            }
            if let Some(why) = &summary.cannot_go_on {
                hnav_runtime::errln!("error: {why}");
                ExitCode::from(EXIT_RUN_BROKEN)
            } else if !summary.lost.is_empty() {
                for l in &summary.lost {
                    hnav_runtime::errln!("robot {} lost: {}", l.id, l.why);
                }
                ExitCode::from(EXIT_ROBOTS_LOST)
            } else if summary.success() {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(1)
            }
        }
        Err(e @ RunError::NoSpace { .. }) => {
            hnav_runtime::errln!("error: {e}");
            ExitCode::from(EXIT_RUN_BROKEN)
        }
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

/// The directory of the process binaries: `--bin-dir`, else this executable's. `None` (said
/// on stderr) when neither is known.
pub fn bin_dir(given: Option<PathBuf>) -> Option<PathBuf> {
    let dir = given.or_else(|| {
        std::env::current_exe()
            .ok()
            .and_then(|p| p.parent().map(PathBuf::from))
    });
    if dir.is_none() {
        hnav_runtime::errln!("error: cannot locate the process binaries; pass --bin-dir");
    }
    dir
}
