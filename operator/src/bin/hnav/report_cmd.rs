//! `hnav report DIR [--agents 0,3] [--out FILE]`: draws a finished run's report again
//! (`hnav_operator::report`). Exit 0 when it is written, 2 when the run directory cannot be
//! read or the file cannot be written.

use std::path::PathBuf;
use std::process::ExitCode;

use hnav_operator::report::{write_report, ReportOptions};

/// `hnav report` arguments.
#[derive(clap::Args, Debug)]
pub struct ReportArgs {
    /// The run directory (holding log/, recording/, map.map and summary.json).
    pub dir: PathBuf,
    /// The agents whose final neural map is drawn, comma-separated.
    #[arg(long, value_name = "0,3", value_delimiter = ',', default_value = "0")]
    pub agents: Vec<u32>,
    /// Output file [default: DIR/report.svg].
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

pub fn run(a: ReportArgs) -> ExitCode {
    let opts = ReportOptions {
        agents: a.agents,
        out: a.out,
    };
    match write_report(&a.dir, &opts) {
        Ok(w) => {
            for n in &w.notes {
                hnav_runtime::errln!("note: {n}");
            }
            hnav_runtime::outln!("report    {}", w.path.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
