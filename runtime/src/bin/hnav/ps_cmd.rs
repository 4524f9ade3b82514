//! `hnav ps`: the live runs on this machine and the state of their processes. A thin
//! front end; the registry and the state lookup live in `hnav_runtime::supervisor::registry`.

use std::process::ExitCode;

use hnav_runtime::supervisor::registry::RunRegistry;

/// `hnav ps` arguments.
#[derive(clap::Args, Debug)]
pub struct PsArgs {
    /// Print JSON: `{"runs": [{"run_id", "dir", "processes": [{"role", "index", "pid", "state"}]}]}`.
    #[arg(long)]
    pub json: bool,
}

/// Lists the runs of `$HNAV_RUNS_DIR` (default `<temp dir>/hnav-runs`); exits 0, also when
/// there are none.
pub fn run(args: PsArgs) -> ExitCode {
    hnav_runtime::logging::init();
    let report = RunRegistry::default_location().status();
    if args.json {
        println!("{}", report.to_json());
    } else {
        print!("{}", report.render_table());
    }
    ExitCode::SUCCESS
}
