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
    /// Leave after drawing N frames and print the frame rate and the slowest frame's draw
    /// time to standard error: how the view is measured on a large swarm.
    #[arg(long, value_name = "N")]
    pub frames: Option<u32>,
}

/// How the viewer was left.
enum Left {
    Key,
    Signal,
    RunEnded,
    Frames,
}

/// `--frames N`: when each frame started, for the rate of a large swarm's view.
struct FrameClock {
    wanted: u32,
    started: Option<Instant>,
    /// Each frame's draw time (state already folded in), s.
    draws: Vec<f64>,
    /// The longest gap between two frames' starts, s.
    worst_gap: f64,
    last: Option<Instant>,
}

impl FrameClock {
    fn new(wanted: u32) -> Self {
        Self {
            wanted: wanted.max(1),
            started: None,
            draws: Vec::with_capacity(wanted as usize),
            worst_gap: 0.0,
            last: None,
        }
    }

    /// Records a frame that started at `at` and took `draw`; whether enough were drawn.
    fn tick(&mut self, at: Instant, draw: Duration) -> bool {
        self.started.get_or_insert(at);
        if let Some(l) = self.last.replace(at) {
            self.worst_gap = self.worst_gap.max(at.duration_since(l).as_secs_f64());
        }
        self.draws.push(draw.as_secs_f64());
        self.draws.len() as u32 >= self.wanted
    }

    fn describe(&self, robots: usize) -> String {
        let n = self.draws.len();
        let span = match (self.started, self.last) {
            (Some(a), Some(b)) => b.duration_since(a).as_secs_f64(),
            _ => 0.0,
        };
        let mut d = self.draws.clone();
        d.sort_by(f64::total_cmp);
        let at = |q: f64| {
            d.get(((n as f64 - 1.0) * q).round() as usize)
                .copied()
                .unwrap_or(0.0)
        };
        format!(
            "frames {n} robots {robots} in {span:.2} s: {:.2} frames/s (aim {:.0}); draw p50 {:.1} ms, max {:.1} ms; longest gap {:.1} ms",
            if span > 0.0 { (n - 1) as f64 / span } else { 0.0 },
            1.0 / FRAME.as_secs_f64(),
            at(0.5) * 1e3,
            at(1.0) * 1e3,
            self.worst_gap * 1e3
        )
    }
}

/// Shows the run until it is left; see the module docs for the exit codes.
pub fn run(args: TopArgs) -> ExitCode {
    match LiveFeed::open(&RunRegistry::default_location(), args.run.as_deref()) {
        Ok(feed) => view_counting(feed, args.exit_on_end, args.frames),
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

/// Shows what `feed` yields until the viewer is left: the live view of `hnav top` and the
/// playback of `hnav log replay --speed`. Exit codes as in the module docs.
pub fn view(feed: impl Feed, exit_on_end: bool) -> ExitCode {
    view_counting(feed, exit_on_end, None)
}

/// [`view()`], leaving after `frames` frames if given and then telling how fast they came.
fn view_counting(feed: impl Feed, exit_on_end: bool, frames: Option<u32>) -> ExitCode {
    let mut state = ViewState::new(feed.info().clone());
    let mut guard = match TerminalGuard::enter() {
        Ok(g) => g,
        Err(e) => {
            hnav_runtime::errln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let mut clock = frames.map(FrameClock::new);
    let result = show(
        &mut guard,
        Some(feed),
        &mut state,
        exit_on_end,
        clock.as_mut(),
    );
    drop(guard);
    if let Some(c) = &clock {
        hnav_runtime::errln!("{}", c.describe(state.agents.len()));
    }
    let run = &state.info.run_id;
    let at_goal = format!("{}/{} at goal", state.at_goal(), state.agents.len());
    match result {
        Ok(left) => {
            let how = match (left, state.ended) {
                (Left::RunEnded | Left::Key, Some(end)) => format!("ended: {}", end.describe()),
                (Left::Signal, _) => "left on a signal".to_string(),
                (Left::Frames, _) => "left after the frames asked for".to_string(),
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
    mut clock: Option<&mut FrameClock>,
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
            if let Some(c) = clock.as_deref_mut() {
                if c.tick(now, now.elapsed()) {
                    return Ok(Left::Frames);
                }
            }
            if !live && exit_on_end {
                return Ok(Left::RunEnded);
            }
        }
    }
}
