//! One `tracing` set-up for every HNAV binary.
//!
//! iceoryx2 is built with its `tracing` logger backend (the workspace turns its `console`
//! feature off), so its own messages arrive here as `tracing` events with the target
//! `iceoryx2_bb_loggers::tracing` and obey the same filter as ours. By default that target is
//! limited to errors: iceoryx2 warns about things HNAV does on purpose (running without a
//! config file, cleaning up after killed processes).

use std::io::IsTerminal;

use iceoryx2::prelude::{set_log_level, LogLevel};
use tracing::level_filters::LevelFilter;
use tracing_subscriber::EnvFilter;

/// The filter used when neither `HNAV_LOG` nor `RUST_LOG` is set.
pub const DEFAULT_FILTER: &str = "info,iceoryx2_bb_loggers=error";

/// Installs a stderr subscriber filtered by `HNAV_LOG`, else `RUST_LOG`, else
/// [`DEFAULT_FILTER`]. Colours only when stderr is a terminal: the run's processes write to
/// `DIR/logs/<node>.log`, which must read as plain text. Calling it twice is harmless (the
/// second call does nothing).
pub fn init() {
    let filter = std::env::var("HNAV_LOG")
        .or_else(|_| std::env::var("RUST_LOG"))
        .ok()
        .and_then(|f| EnvFilter::try_new(f).ok())
        .unwrap_or_else(|| EnvFilter::new(DEFAULT_FILTER));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        // A failed write (a full disk under a redirected stderr) must not panic the process,
        // nor be reported on the very stream that just failed.
        .with_writer(|| crate::diag::StderrWriter)
        .log_internal_errors(false)
        .with_ansi(std::io::stderr().is_terminal())
        .try_init();
    // iceoryx2 filters by its own level before its message reaches `tracing`; open it exactly
    // as far as the most verbose directive, so the tracing filter decides and nothing more
    // is formatted than could be shown.
    set_log_level(iceoryx2_level(LevelFilter::current()));
}

fn iceoryx2_level(max: LevelFilter) -> LogLevel {
    match max.into_level() {
        None => LogLevel::Fatal,
        Some(tracing::Level::ERROR) => LogLevel::Error,
        Some(tracing::Level::WARN) => LogLevel::Warn,
        Some(tracing::Level::INFO) => LogLevel::Info,
        Some(tracing::Level::DEBUG) => LogLevel::Debug,
        Some(tracing::Level::TRACE) => LogLevel::Trace,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iceoryx2_level_follows_the_most_verbose_directive() {
        assert_eq!(iceoryx2_level(LevelFilter::TRACE), LogLevel::Trace);
        assert_eq!(iceoryx2_level(LevelFilter::INFO), LogLevel::Info);
        assert_eq!(iceoryx2_level(LevelFilter::OFF), LogLevel::Fatal);
    }
}
