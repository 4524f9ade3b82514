//! Where a port's samples leave for Zenoh: straight from the bridge's loop, or, for the
//! samples a realtime run must not drop (lifecycle events and `ready`), through a thread of
//! their own.
//!
//! A put that must not be dropped waits for room on every link it goes out on, up to the
//! session's `wait_before_close` (one lease, see [`crate::session`]). Made on the loop, that
//! wait would hold every topic of the host while one link is dead: a lifecycle event
//! published while a robot host is cut off (a restart on the base station, say) would stand
//! the robots of every other host for up to a lease. Made on the ahead thread, it holds only
//! the events queued behind it, which keep their order. Lockstep runs (nothing droppable) keep every put on the loop: there a lost or late
//! sample holds the round anyway, and the order of all topics is the order of the loop.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crossbeam_channel::{Sender, TrySendError};
use zenoh::bytes::ZBytes;
use zenoh::pubsub::Publisher;
use zenoh::Wait;

/// Samples waiting for the ahead thread; past this a put is refused (counted as failed):
/// lifecycle events are a few per process start or host change, so a full queue means the
/// links have been dead for a long time.
const AHEAD_QUEUE: usize = 1024;

/// A put that held its thread this long is logged: on the loop, every topic of the host
/// waited behind it.
const HELD_WARN: Duration = Duration::from_millis(20);

/// Logs a put on `publisher`, begun at `since`, that held its thread (`on`: `loop` or
/// `ahead`) over [`HELD_WARN`]. The multi-host tests read these lines.
fn held_warning(publisher: &Publisher<'_>, since: Instant, on: &str) {
    let held = since.elapsed();
    if held > HELD_WARN {
        tracing::warn!(
            key = %publisher.key_expr(),
            held_ms = held.as_secs_f64() * 1e3,
            "a put to Zenoh held the bridge's {on} thread"
        );
    }
}

/// One put for the ahead thread.
struct Put {
    publisher: Arc<Publisher<'static>>,
    payload: ZBytes,
    type_name: &'static str,
}

/// A topic's way out to Zenoh.
pub(crate) struct Outlet {
    publisher: Arc<Publisher<'static>>,
    ahead: Option<Sender<Put>>,
}

impl Outlet {
    /// Puts from the bridge's loop.
    pub(crate) fn direct(publisher: Publisher<'static>) -> Self {
        Outlet {
            publisher: Arc::new(publisher),
            ahead: None,
        }
    }

    /// Puts through `line`'s thread.
    pub(crate) fn ahead(publisher: Publisher<'static>, line: &AheadLine) -> Self {
        Outlet {
            publisher: Arc::new(publisher),
            ahead: Some(line.tx.clone()),
        }
    }

    /// The Zenoh publisher (for its matching status).
    pub(crate) fn publisher(&self) -> &Publisher<'static> {
        &self.publisher
    }

    /// Puts `payload`, attached with its wire type name; `Err` is Zenoh's words (or a full
    /// ahead queue). Through the ahead thread, `Ok` means queued: that thread counts what
    /// Zenoh refuses ([`AheadLine::failed`]).
    pub(crate) fn put(
        &self,
        payload: impl Into<ZBytes>,
        type_name: &'static str,
    ) -> Result<(), String> {
        let payload = payload.into();
        match &self.ahead {
            None => {
                let since = Instant::now();
                let put = self.publisher.put(payload).attachment(type_name).wait();
                held_warning(&self.publisher, since, "loop");
                put.map_err(|e| e.to_string())
            }
            Some(tx) => {
                let put = Put {
                    publisher: Arc::clone(&self.publisher),
                    payload,
                    type_name,
                };
                tx.try_send(put).map_err(|e| match e {
                    TrySendError::Full(_) => "the ahead queue is full".to_string(),
                    TrySendError::Disconnected(_) => "the ahead thread ended".to_string(),
                })
            }
        }
    }
}

/// The thread that makes the puts that may wait, one after the other.
pub(crate) struct AheadLine {
    tx: Sender<Put>,
    failed: Arc<AtomicU64>,
    thread: Option<JoinHandle<()>>,
}

impl AheadLine {
    /// Starts the thread.
    pub(crate) fn start() -> std::io::Result<Self> {
        let (tx, rx) = crossbeam_channel::bounded::<Put>(AHEAD_QUEUE);
        let failed = Arc::new(AtomicU64::new(0));
        let count = Arc::clone(&failed);
        let thread = std::thread::Builder::new()
            .name("bridge-ahead".into())
            .spawn(move || {
                for p in rx {
                    let since = Instant::now();
                    let put = p.publisher.put(p.payload).attachment(p.type_name).wait();
                    held_warning(&p.publisher, since, "ahead");
                    if let Err(e) = put {
                        count.fetch_add(1, Ordering::Relaxed);
                        tracing::debug!(key = %p.publisher.key_expr(), "zenoh put failed: {e}");
                    }
                }
            })?;
        Ok(AheadLine {
            tx,
            failed,
            thread: Some(thread),
        })
    }

    /// Puts Zenoh refused on this thread so far.
    pub(crate) fn failed(&self) -> u64 {
        self.failed.load(Ordering::Relaxed)
    }
}

/// Ends the thread once every outlet's sender is gone (the bridge drops its outlets first)
/// and waits for it, so that its last puts are made before the session closes.
impl Drop for AheadLine {
    fn drop(&mut self) {
        let (closed, _) = crossbeam_channel::bounded(0);
        drop(std::mem::replace(&mut self.tx, closed));
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
