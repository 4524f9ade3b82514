//! `hnav view RUN --foxglove [ADDR] [--speed X] [--exit-on-end]`: a run served to Foxglove
//! on the Foxglove WebSocket protocol. RUN is a live run (its id or directory, as `hnav top`
//! takes it) or a finished run's directory, played back at X times real time. Also
//! [`live`], the `--foxglove` of `hnav run`. The work is in `hnav_operator::viewer`.
//!
//! Exit codes: 0 the view was left (a signal, or the run's end with `--exit-on-end`); 1 the
//! run's topics or recording failed while it was served; 2 nothing was served: ADDR does not
//! parse or cannot be listened on, or RUN is neither a live run nor a run directory that can
//! be played back.

use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;

use hnav_operator::monitor::feed::{Feed, FeedError};
use hnav_operator::monitor::live::LiveFeed;
use hnav_operator::monitor::playback::PlaybackFeed;
use hnav_operator::supervisor::registry::RunRegistry;
use hnav_operator::viewer::live::LiveView;
use hnav_operator::viewer::{parse_addr, show, Server, DEFAULT_ADDR};
use hnav_runtime::launch::ProcessArgs;

/// `hnav view` arguments.
#[derive(clap::Args, Debug)]
pub struct ViewArgs {
    /// The run: a live run's id or directory (as `hnav ps` lists them), or a finished run's
    /// directory (holding log/ and recording/).
    pub run: String,
    /// Serve it on the Foxglove WebSocket protocol at ADDR [default ADDR: 127.0.0.1:8765].
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = DEFAULT_ADDR, required = true)]
    pub foxglove: Option<String>,
    /// A finished run plays back at this many times real time (0.01 to 10000).
    #[arg(long, value_name = "X", default_value_t = 1.0)]
    pub speed: f64,
    /// Leave as soon as the run (or its playback) ends, instead of serving its last state
    /// until SIGINT or SIGTERM.
    #[arg(long)]
    pub exit_on_end: bool,
}

/// Listens on `addr`, printing where; `Err` is the exit code after the message.
fn listen(addr: &str) -> Result<Server, ExitCode> {
    match parse_addr(addr).and_then(Server::bind) {
        Ok(server) => {
            hnav_runtime::errln!(
                "foxglove  ws://{} (Foxglove WebSocket protocol, foxglove.sdk.v1)",
                server.addr()
            );
            Ok(server)
        }
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            Err(ExitCode::from(2))
        }
    }
}

/// `hnav run --foxglove ADDR`: listens now, serves the run `args` starts from a thread.
pub fn live(addr: &str, args: &ProcessArgs) -> Result<LiveView, ExitCode> {
    let server = listen(addr)?;
    LiveView::start(server, args.run.clone()).map_err(|e| {
        hnav_runtime::errln!("error: cannot start the foxglove view's thread: {e}");
        ExitCode::from(2)
    })
}

/// Runs `hnav view`.
pub fn run(a: ViewArgs) -> ExitCode {
    hnav_runtime::logging::init();
    let addr = a.foxglove.as_deref().unwrap_or(DEFAULT_ADDR);
    let feed = open(&a.run, a.speed);
    let mut feed = match feed {
        Ok(feed) => feed,
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let mut server = match listen(addr) {
        Ok(s) => s,
        Err(code) => return code,
    };
    match show(
        feed.as_mut(),
        &mut server,
        a.exit_on_end,
        &AtomicBool::new(false),
    ) {
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            ExitCode::from(1)
        }
    }
}

/// The live run `run` names, else the finished run in directory `run`.
fn open(run: &str, speed: f64) -> Result<Box<dyn Feed>, FeedError> {
    match LiveFeed::open(&RunRegistry::default_location(), Some(run)) {
        Ok(feed) => return Ok(Box::new(feed)),
        Err(FeedError::NotFound { .. }) if Path::new(run).is_dir() => {}
        Err(e) => return Err(e),
    }
    let dir = hnav_operator::supervisor::replay::run_dir_of(Path::new(run));
    Ok(Box::new(PlaybackFeed::open(&dir, speed)?))
}
