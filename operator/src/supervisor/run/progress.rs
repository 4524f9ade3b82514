//! What `hnav run` shows while a run goes on, from the coordinator's latest [`Progress`]: on a
//! terminal a progress bar (agents at their goal, the round, conflicts and replans); elsewhere
//! (a CI log, a pipe) one plain line on stderr every [`LINE_EVERY`], which a bar redrawing in
//! place would turn into noise.

use std::time::{Duration, Instant};

use hnav_runtime::msg::Progress;

/// How often a run that is not on a terminal prints its progress line.
pub(super) const LINE_EVERY: Duration = Duration::from_secs(5);

/// The bar, or the plain progress lines.
pub(super) enum ProgressView {
    Bar(indicatif::ProgressBar),
    Lines {
        agents: usize,
        t0: Instant,
        /// When the next line is due; the first progress gets one at once.
        next: Instant,
    },
}

impl ProgressView {
    /// A bar over `agents` agents if `terminal`, else progress lines.
    pub(super) fn new(terminal: bool, agents: usize) -> Self {
        let now = Instant::now();
        if !terminal {
            return Self::Lines {
                agents,
                t0: now,
                next: now,
            };
        }
        let bar = indicatif::ProgressBar::new(agents as u64);
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{elapsed_precise} [{bar:30}] {pos}/{len} at goal  {msg}",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        Self::Bar(bar)
    }

    /// Draws `p`, or prints it if a line is due.
    pub(super) fn show(&mut self, p: &Progress) {
        match self {
            Self::Bar(b) => {
                b.set_position(u64::from(p.at_goal));
                b.set_message(format!(
                    "round {}  conflicts {}  replans {}",
                    p.round, p.conflicts, p.replans
                ));
            }
            Self::Lines { agents, t0, next } => {
                let now = Instant::now();
                if now >= *next {
                    *next = now + LINE_EVERY;
                    eprintln!("{}", line(p, *agents, now - *t0));
                }
            }
        }
    }

    /// Removes the bar from the terminal.
    pub(super) fn finish(self) {
        if let Self::Bar(b) = self {
            b.finish_and_clear();
        }
    }
}

/// One progress line: `progress: round 120, 3/8 agents at goal, 2 conflicts, 0 replans, 5.0 s`.
fn line(p: &Progress, agents: usize, elapsed: Duration) -> String {
    format!(
        "progress: round {}, {}/{agents} agents at goal, {} conflicts, {} replans, {:.1} s",
        p.round,
        p.at_goal,
        p.conflicts,
        p.replans,
        elapsed.as_secs_f64()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_progress_line_says_round_agents_at_goal_and_elapsed_time() {
        let p = Progress {
            round: 120,
            at_goal: 3,
            conflicts: 2,
            ..Progress::default()
        };
        assert_eq!(
            line(&p, 8, Duration::from_millis(5049)),
            "progress: round 120, 3/8 agents at goal, 2 conflicts, 0 replans, 5.0 s"
        );
    }
}
