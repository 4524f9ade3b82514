//! `hnav ps`: the live runs on this machine and the state of their processes. A thin
//! front end; the registry lives in `hnav_operator::supervisor::registry`, the state lookup
//! in `hnav_operator::supervisor::ps`.

use std::process::ExitCode;

use hnav_operator::supervisor::ps::PsReport;
use hnav_operator::supervisor::registry::RunRegistry;

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
    let report = PsReport::of(&RunRegistry::default_location());
    if args.json {
        hnav_runtime::outln!("{}", report.to_json());
    } else {
        hnav_runtime::out!("{}", report.render_table());
    }
    ExitCode::SUCCESS
}
