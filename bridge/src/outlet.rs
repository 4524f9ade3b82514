//! Where a port's samples leave for Zenoh, and the record of a put that held the bridge's
//! loop.
//!
//! A put that must not be dropped (lifecycle events, `ready`, and in lockstep every sample)
//! waits for room on every link it goes out on, up to the session's `wait_before_close` (one
//! lease, see [`crate::session`]), and every topic of the host waits behind it. Such a put
//! is logged (`a put to Zenoh held the bridge's loop thread`), so that a stall of the robots
//! of one host while another is cut off can be told apart from the machine's load. A thread
//! of its own for these puts was tried and taken out again: with it, the partition test's
//! rare stall (see `docs/explanation/between-hosts.md`) came in 3 of 3 runs instead of about
//! 1 in 11.

use std::time::{Duration, Instant};

use zenoh::bytes::ZBytes;
use zenoh::pubsub::Publisher;
use zenoh::Wait;

/// A put that held the loop this long is logged: every topic of the host waited behind it.
const HELD_WARN: Duration = Duration::from_millis(20);

/// A topic's way out to Zenoh.
pub(crate) struct Outlet {
    publisher: Publisher<'static>,
}

impl Outlet {
    /// Puts through `publisher`, from the bridge's loop.
    pub(crate) fn new(publisher: Publisher<'static>) -> Self {
        Outlet { publisher }
    }

    /// The Zenoh publisher (for its matching status).
    pub(crate) fn publisher(&self) -> &Publisher<'static> {
        &self.publisher
    }

    /// Puts `payload`, attached with its wire type name; `Err` is Zenoh's words.
    pub(crate) fn put(
        &self,
        payload: impl Into<ZBytes>,
        type_name: &'static str,
    ) -> Result<(), String> {
        let since = Instant::now();
        let put = self.publisher.put(payload).attachment(type_name).wait();
        let held = since.elapsed();
        if held > HELD_WARN {
            tracing::warn!(
                key = %self.publisher.key_expr(),
                held_ms = held.as_secs_f64() * 1e3,
                "a put to Zenoh held the bridge's loop thread"
            );
        }
        put.map_err(|e| e.to_string())
    }
}
