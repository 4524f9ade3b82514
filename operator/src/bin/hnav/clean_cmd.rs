//! `hnav clean [RUN]`: remove what a dead run left behind (its leftover processes, its
//! shared memory in `/dev/shm` and under iceoryx2's root directory, its registry entry).
//! The work is in `hnav_operator::supervisor::clean`.
//!
//! Exit codes: 0 cleaned (or nothing to clean), 2 refused (a live run, an id held by another
//! process) or failed.

use std::process::ExitCode;

use hnav_operator::supervisor::clean::{clean_dead_runs, clean_named};
use hnav_operator::supervisor::registry::RunRegistry;
use hnav_runtime::transport::RunId;

/// `hnav clean` arguments.
#[derive(clap::Args, Debug)]
pub struct CleanArgs {
    /// The run to clean [default: every run whose supervisor is dead]. A live run is refused.
    pub run: Option<String>,
}

/// Cleans one run, or every dead run of `$HNAV_RUNS_DIR` (default `<temp dir>/hnav-runs`).
pub fn run(args: CleanArgs) -> ExitCode {
    hnav_runtime::logging::init();
    let registry = RunRegistry::default_location();
    let results = match args.run {
        Some(id) => match RunId::new(&id) {
            Ok(run) => clean_named(&registry, &run),
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(2);
            }
        },
        None => clean_dead_runs(&registry),
    };
    if results.is_empty() {
        println!("no dead runs");
    }
    let mut failed = false;
    for r in results {
        match r {
            Ok(c) => println!("{c}"),
            Err(e) => {
                eprintln!("error: {e}");
                failed = true;
            }
        }
    }
    if failed {
        ExitCode::from(2)
    } else {
        ExitCode::SUCCESS
    }
}
