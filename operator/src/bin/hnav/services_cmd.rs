//! `hnav services RUN [--json]`: a live run's topics with their publishers and subscribers.
//! The work is in `hnav_operator::supervisor::services`.
//!
//! Exit codes: 0 listed, 2 a run the registry does not know, a dead run, or services that
//! could not be read.

use std::process::ExitCode;

use hnav_operator::supervisor::registry::RunRegistry;
use hnav_operator::supervisor::services::services;

/// `hnav services` arguments.
#[derive(clap::Args, Debug)]
pub struct ServicesArgs {
    /// The run id, as `hnav ps` lists it.
    pub run: String,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Lists the topics of a run of `$HNAV_RUNS_DIR` (default `<temp dir>/hnav-runs`).
pub fn run(a: ServicesArgs) -> ExitCode {
    hnav_runtime::logging::init();
    match services(&RunRegistry::default_location(), &a.run) {
        Ok(report) if a.json => {
            hnav_runtime::outln!("{}", report.to_json());
            ExitCode::SUCCESS
        }
        Ok(report) => {
            hnav_runtime::out!("{}", report.render());
            ExitCode::SUCCESS
        }
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
