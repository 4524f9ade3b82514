//! `hnav log export DIR --mcap OUT`: a run as an MCAP file for Foxglove Studio. The work is
//! in `hnav_operator::export`.
//!
//! Exit codes: 0 written (what was missing is said on stderr), 1 the output cannot be
//! written, 2 the run cannot be read (no log, a damaged log or recording file: the message
//! names the file and the offset).

use std::path::PathBuf;
use std::process::ExitCode;

use hnav_operator::export::{export_mcap, ExportError};
use hnav_operator::supervisor::replay::run_dir_of;

/// `hnav log export` arguments.
#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// The run directory (holding log/, recording/ and invocation.json), or its log/.
    pub dir: PathBuf,
    /// The MCAP file to write.
    #[arg(long, value_name = "OUT")]
    pub mcap: PathBuf,
}

/// Runs `hnav log export`.
pub fn run(a: ExportArgs) -> ExitCode {
    match export_mcap(&run_dir_of(&a.dir), &a.mcap) {
        Ok(report) => {
            for note in &report.notes {
                hnav_runtime::errln!("note: {note}");
            }
            hnav_runtime::outln!(
                "{}: {} channels, {} messages",
                a.mcap.display(),
                report.channels.len(),
                report.messages()
            );
            for (topic, (schema, n)) in &report.channels {
                hnav_runtime::outln!("  {topic:<28} {schema:<22} {n}");
            }
            ExitCode::SUCCESS
        }
        Err(e @ ExportError::Write { .. }) => {
            hnav_runtime::errln!("error: {e}");
            ExitCode::from(1)
        }
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
