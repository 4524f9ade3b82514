//! One `tracing` set-up for every HNAV binary.
//!
//! iceoryx2 is built with its `tracing` logger backend (the workspace turns its `console`
//! feature off), so its own messages arrive here as `tracing` events with the target
//! `iceoryx2_bb_loggers::tracing` and obey the same filter as ours. By default that target is
//! limited to errors: iceoryx2 warns about things HNAV does on purpose (running without a
//! config file, cleaning up after killed processes).

use tracing_subscriber::EnvFilter;

/// The filter used when neither `HNAV_LOG` nor `RUST_LOG` is set.
pub const DEFAULT_FILTER: &str = "info,iceoryx2_bb_loggers=error";

/// Installs a stderr subscriber filtered by `HNAV_LOG`, else `RUST_LOG`, else
/// [`DEFAULT_FILTER`]. Calling it twice is harmless (the second call does nothing).
pub fn init() {
    let filter = std::env::var("HNAV_LOG")
        .or_else(|_| std::env::var("RUST_LOG"))
        .ok()
        .and_then(|f| EnvFilter::try_new(f).ok())
        .unwrap_or_else(|| EnvFilter::new(DEFAULT_FILTER));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .try_init();
}
