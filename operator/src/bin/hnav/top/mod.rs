//! `hnav top [RUN] [--exit-on-end]`: the live view of a run in the terminal; [`view()`] also
//! shows a recorded run played back (`hnav log replay DIR --speed X`).
//!
//! The library's `monitor` module does the work: a feed (`LiveFeed`, a subscriber of the
//! run like any other client, or `PlaybackFeed`, a run directory's recording) folded into a
//! `ViewState` and drawn by `monitor::view`. This
//! module owns what only a terminal has: the [`terminal::TerminalGuard`] and the keys
//! ([`input`]), and the loop between them.
//!
//! The loop sleeps in the feed's `Waiter` for at most [`DRAIN`], looks at the keys without
//! blocking, drains whatever the feed has, and redraws every [`FRAME`]. Draining more often
//! than it draws keeps the commits a fast lockstep run publishes (about 2 000 a second) from
//! overflowing the viewer's buffer, which the coordinator never waits for.
//!
//! Exit codes: 0 when the viewer was left (a key, the end of the run with `--exit-on-end`,
//! SIGINT or SIGTERM); 1 when the run's topics failed while it ran; 2 when there was no run
//! to show (none live, several and none named, an unknown one), its scenario could not be
//! loaded, or standard output is not a terminal.

mod input;
mod terminal;

use std::process::ExitCode;
use std::time::{Duration, Instant};

use hnav_operator::monitor::feed::{Feed, FeedError, Waited};
use hnav_operator::monitor::live::LiveFeed;
use hnav_operator::monitor::state::ViewState;
use hnav_operator::monitor::view::{self, Hints};
use hnav_operator::supervisor::registry::RunRegistry;
use iceoryx2_bb_posix::signal::SignalHandler;

use terminal::TerminalGuard;

/// The longest the loop sleeps in the feed between two drains of its topics.
pub const DRAIN: Duration = Duration::from_millis(20);
/// The redraw period.
pub const FRAME: Duration = Duration::from_millis(100);

/// `hnav top` arguments.
#[derive(clap::Args, Debug)]
pub struct TopArgs {
    /// The run: its id or its directory, as `hnav ps` lists them [default: the only live run].
    pub run: Option<String>,
    /// Leave as soon as the run ends, instead of showing "run ended" until a key is pressed.
    #[arg(long)]
    pub exit_on_end: bool,
}

/// How the viewer was left.
enum Left {
    Key,
    Signal,
    RunEnded,
}

/// Shows the run until it is left; see the module docs for the exit codes.
pub fn run(args: TopArgs) -> ExitCode {
    match LiveFeed::open(&RunRegistry::default_location(), args.run.as_deref()) {
        Ok(feed) => view(feed, args.exit_on_end),
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

/// Shows what `feed` yields until the viewer is left: the live view of `hnav top` and the
/// playback of `hnav log replay --speed`. Exit codes as in the module docs.
pub fn view(feed: impl Feed, exit_on_end: bool) -> ExitCode {
    let mut state = ViewState::new(feed.info().clone());
    let mut guard = match TerminalGuard::enter() {
        Ok(g) => g,
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let result = show(&mut guard, Some(feed), &mut state, exit_on_end);
    drop(guard);
    let run = &state.info.run_id;
    let at_goal = format!("{}/{} at goal", state.at_goal(), state.agents.len());
    match result {
        Ok(left) => {
            let how = match (left, state.ended) {
                (Left::RunEnded | Left::Key, Some(end)) => format!("ended: {}", end.describe()),
                (Left::Signal, _) => "left on a signal".to_string(),
                (_, None) => "left".to_string(),
            };
            hnav_runtime::outln!("run {run} {how} (round {}, {at_goal})", state.round);
            ExitCode::SUCCESS
        }
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            ExitCode::from(1)
        }
    }
}

/// Why the loop stopped early.
#[derive(Debug, thiserror::Error)]
enum ShowError {
    #[error(transparent)]
    Feed(#[from] FeedError),
    #[error("the terminal: {0}")]
    Terminal(#[from] std::io::Error),
}

/// The loop: sleep in the feed, keys, drain, draw (module docs). The feed is dropped as soon
/// as the run has ended, so a viewer left open holds nothing of the run.
fn show<F: Feed>(
    guard: &mut TerminalGuard,
    mut feed: Option<F>,
    state: &mut ViewState,
    exit_on_end: bool,
) -> Result<Left, ShowError> {
    let hints = Hints::default();
    let mut next_frame = Instant::now();
    loop {
        let now = Instant::now();
        let waited = match &mut feed {
            Some(f) => f.wait((now + DRAIN).min(next_frame))?,
            // iceoryx2's handler still turns SIGINT/SIGTERM into this flag.
            None if SignalHandler::termination_requested() => Waited::Stop,
            None => Waited::Ready,
        };
        if waited == Waited::Stop {
            return Ok(Left::Signal);
        }
        // Blocking on the keys only once the feed is gone: until then the feed's wait sleeps.
        let live = feed.is_some();
        let keys = input::poll(if live { Duration::ZERO } else { FRAME })?;
        if keys.quit || (!live && keys.key) {
            return Ok(Left::Key);
        }
        if let Some(f) = &mut feed {
            f.pump(&mut |u| state.apply(u, Instant::now()))?;
            if state.ended.is_some() {
                feed = None;
                next_frame = Instant::now();
            }
        }
        let live = feed.is_some();
        let now = Instant::now();
        if now >= next_frame || keys.resized {
            guard
                .terminal()
                .draw(|f| view::draw(f, state, now, hints))?;
            next_frame = now + FRAME;
            if !live && exit_on_end {
                return Ok(Left::RunEnded);
            }
        }
    }
}
