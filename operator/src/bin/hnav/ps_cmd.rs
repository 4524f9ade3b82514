//! `hnav ps [RUN]`: the live runs on this machine, one line each, or the processes of one
//! run. A thin front end; the registry lives in `hnav_operator::supervisor::registry`, the
//! state lookup in `hnav_operator::supervisor::ps`.

use std::process::ExitCode;

use hnav_operator::supervisor::ps::PsReport;
use hnav_operator::supervisor::registry::RunRegistry;

/// `hnav ps` arguments.
#[derive(clap::Args, Debug)]
pub struct PsArgs {
    /// A run id or run directory: list that run's processes (role, index, pid, state)
    /// instead of one line per run.
    #[arg(value_name = "RUN")]
    pub run: Option<String>,
    /// Print JSON, every process of every run (or of RUN): `{"runs": [{"run_id", "dir",
    /// "processes": [{"role", "index", "pid", "state"}]}]}`.
    #[arg(long)]
    pub json: bool,
}

/// Lists the runs of `$HNAV_RUNS_DIR` (default `<temp dir>/hnav-runs`); exits 0, also when
/// there are none, and 2 for a RUN the registry does not list.
pub fn run(args: PsArgs) -> ExitCode {
    hnav_runtime::logging::init();
    let registry = RunRegistry::default_location();
    let mut report = PsReport::of(&registry);
    if let Some(run) = &args.run {
        match report.select(run) {
            Some(one) => report = one,
            None => {
                hnav_runtime::errln!(
                    "error: no run {run} in {} (`hnav ps` lists the runs)",
                    registry.dir().display()
                );
                return ExitCode::from(2);
            }
        }
    }
    if args.json {
        hnav_runtime::outln!("{}", report.to_json());
    } else if args.run.is_some() {
        hnav_runtime::out!("{}", report.render_table());
    } else {
        hnav_runtime::out!("{}", report.render_summary());
    }
    ExitCode::SUCCESS
}
