//! `hnav-bench lacam`'s command line: the cases of [`search_only`](super::search_only), each
//! run in a child of this binary, printed as a markdown table or JSON lines.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{bail, Context, Result};
use clap::Args;

use super::search_only::{
    default_cases, quick_cases, search_case, search_in_child, table, Case, SearchRow,
};

/// `hnav-bench lacam`'s arguments.
#[derive(Debug, Args)]
pub struct LacamArgs {
    /// The MovingAI .map file [default: the measured cases, see docs/perf/lacam-search.txt].
    #[arg(long, value_name = "FILE", requires = "scen")]
    map: Option<PathBuf>,
    /// Its .scen file; instance N is its first N entries.
    #[arg(long, value_name = "FILE", requires = "map")]
    scen: Option<PathBuf>,
    /// Instance sizes (with --map).
    #[arg(long, value_delimiter = ',', value_name = "N")]
    agents: Vec<usize>,
    /// The search's wall-clock limit per instance, s.
    #[arg(long, default_value_t = 10.0, value_name = "S")]
    limit_s: f64,
    /// Memory the search's tables may take, MiB (the node budgets follow from it).
    #[arg(long, default_value_t = 2048, value_name = "MIB")]
    memory_mib: usize,
    /// Extend a .scen shorter than N with HNAV's generator at this seed.
    #[arg(long, value_name = "SEED")]
    extend_seed: Option<u64>,
    /// Agents as points: a diagonal does not hold its side cells.
    #[arg(long)]
    points: bool,
    /// Without LaCAM3's swap in the configuration generator.
    #[arg(long)]
    no_swap: bool,
    /// random-32-32-10, 50 agents, 1 s (the smoke check of bench/tests/lacam_quick.rs).
    #[arg(long)]
    quick: bool,
    /// Print JSON lines instead of a markdown table.
    #[arg(long)]
    json: bool,
    /// Run one case in this process and print its row (what the parent spawns).
    #[arg(long, hide = true)]
    child: bool,
}

/// Runs `hnav-bench lacam`.
pub fn main(args: LacamArgs) -> Result<()> {
    if !(args.limit_s > 0.0 && args.limit_s.is_finite()) {
        bail!("--limit-s must be a positive number of seconds");
    }
    let limit = Duration::from_secs_f64(args.limit_s);
    let mut cases: Vec<Case> = match (&args.map, &args.scen, args.quick) {
        (Some(map), Some(scen), _) => {
            if args.agents.is_empty() {
                bail!("--map needs --agents");
            }
            args.agents
                .iter()
                .map(|&agents| Case {
                    map: map.clone(),
                    scen: scen.clone(),
                    agents,
                    limit,
                    memory_mib: args.memory_mib,
                    extend_seed: args.extend_seed,
                    points: args.points,
                    swap: !args.no_swap,
                })
                .collect()
        }
        (_, _, true) => quick_cases(),
        _ => default_cases(limit, args.memory_mib),
    };
    for case in &mut cases {
        case.swap &= !args.no_swap;
        case.points |= args.points;
    }
    if args.child {
        let [case] = &cases[..] else {
            bail!("--child runs exactly one case");
        };
        let row = search_case(case).map_err(anyhow::Error::msg)?;
        println!("{}", serde_json::to_string(&row)?);
        return Ok(());
    }
    let exe = std::env::current_exe().context("the benchmark's own binary")?;
    let mut rows: Vec<SearchRow> = Vec::new();
    for case in &cases {
        hnav_runtime::errln!(
            "lacam: {} agents on {} ({} s) ...",
            case.agents,
            case.map.display(),
            case.limit.as_secs_f64()
        );
        let row = search_in_child(&exe, case).map_err(anyhow::Error::msg)?;
        if args.json {
            println!("{}", serde_json::to_string(&row)?);
        }
        rows.push(row);
    }
    if !args.json {
        print!("{}", table(&rows));
    }
    Ok(())
}
