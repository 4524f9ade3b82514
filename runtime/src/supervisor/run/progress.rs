//! The progress bar of `hnav run` on a terminal: agents at their goal, the round, conflicts
//! and replans, from the coordinator's latest [`Progress`].

use crate::msg::Progress;

/// The bar, or nothing when progress is not shown.
pub(super) struct ProgressView {
    bar: Option<indicatif::ProgressBar>,
}

impl ProgressView {
    /// A bar over `agents` agents if `show`, else a view that draws nothing.
    pub(super) fn new(show: bool, agents: usize) -> Self {
        if !show {
            return Self { bar: None };
        }
        let bar = indicatif::ProgressBar::new(agents as u64);
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{elapsed_precise} [{bar:30}] {pos}/{len} at goal  {msg}",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        Self { bar: Some(bar) }
    }

    /// Draws `p`.
    pub(super) fn show(&self, p: &Progress) {
        if let Some(b) = &self.bar {
            b.set_position(u64::from(p.at_goal));
            b.set_message(format!(
                "round {}  conflicts {}  replans {}",
                p.round, p.conflicts, p.replans
            ));
        }
    }

    /// Removes the bar from the terminal.
    pub(super) fn finish(self) {
        if let Some(b) = self.bar {
            b.finish_and_clear();
        }
    }
}
