//! `hnav log replay DIR [--bin-dir DIR] [--run ID]`: a lockstep run started again, its log compared with
//! the run's. The work is in `hnav_operator::supervisor::replay`.
//! `hnav log replay DIR --speed X [--exit-on-end]`: the run's recording played back into the
//! `hnav top` view at X times real time (any clock mode; nothing is re-run). The work is in
//! `hnav_operator::monitor::playback`.
//!
//! Exit codes: 0 every record identical, 1 the replay diverged (the first divergence is
//! printed: round, agent, both decisions), 2 the run cannot be replayed (realtime, no
//! `invocation.json`, a scenario whose hash is not the log's, an unreadable log) or the
//! replay could not run. With `--speed`, those of `hnav top`: 0 left, 1 the recording failed
//! while it played, 2 it cannot be played (no recording, an unreadable log or map, standard
//! output not a terminal).

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use hnav_operator::monitor::playback::PlaybackFeed;
use hnav_operator::supervisor::replay::{replay, ReplayOptions};
use hnav_runtime::consensus_log::Comparison;
use hnav_runtime::transport::RunId;

/// `hnav log replay` arguments.
#[derive(clap::Args, Debug)]
pub struct ReplayArgs {
    /// The run directory (holding log/ and invocation.json), or its log/.
    pub dir: PathBuf,
    /// Where the process binaries are [default: next to this executable].
    #[arg(long, value_name = "DIR")]
    pub bin_dir: Option<PathBuf>,
    /// The replay's run id (letters, digits, '-', '_') [default: a fresh unique one]. Tests
    /// pass their own so they can clean its shared memory up whatever happens.
    #[arg(long, value_name = "ID")]
    pub run: Option<String>,
    /// Instead of re-running: play the run's recording back into the `hnav top` view at this
    /// many times real time (0.01 to 10000; simulated time, so a lockstep run plays at the
    /// speed its robots drove).
    #[arg(long, value_name = "X", conflicts_with_all = ["bin_dir", "run"])]
    pub speed: Option<f64>,
    /// With --speed: leave the view as soon as the playback ends.
    #[arg(long, requires = "speed")]
    pub exit_on_end: bool,
}

/// Runs `hnav log replay`.
pub fn run(a: ReplayArgs) -> ExitCode {
    hnav_runtime::logging::init();
    if let Some(speed) = a.speed {
        let dir = hnav_operator::supervisor::replay::run_dir_of(&a.dir);
        return match PlaybackFeed::open(&dir, speed) {
            Ok(feed) => crate::top::view(feed, a.exit_on_end),
            Err(e) => {
                hnav_runtime::errln!("error: {e}");
                ExitCode::from(2)
            }
        };
    }
    let Some(bin_dir) = crate::run_cmd::bin_dir(a.bin_dir) else {
        return ExitCode::from(2);
    };
    let run = match a.run.as_deref().map(RunId::new).transpose() {
        Ok(run) => run,
        Err(e) => {
            hnav_runtime::errln!("error: --run: {e}");
            return ExitCode::from(2);
        }
    };
    let opts = ReplayOptions {
        dir: a.dir,
        bin_dir,
        progress: std::io::stderr().is_terminal(),
        run,
    };
    match replay(&opts) {
        Ok(r) => match r.comparison {
            Comparison::Identical {
                rounds,
                cut_short_at,
            } => {
                hnav_runtime::outln!("{rounds} rounds replayed, identical");
                if let Some(round) = cut_short_at {
                    hnav_runtime::outln!(
                        "(the logged run was cut short after round {round}; compared that far)"
                    );
                }
                ExitCode::SUCCESS
            }
            Comparison::Diverged(d) => {
                hnav_runtime::outln!("first divergence: {d}");
                ExitCode::from(1)
            }
        },
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
