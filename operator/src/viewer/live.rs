//! `hnav run --foxglove`: the view of the run this process supervises, on a thread of its
//! own. The server listens before anything is spawned (an address in use is an error then,
//! not after the run started); the thread waits for the run to appear in the run registry,
//! opens a [`LiveFeed`] on it like `hnav top` would, and serves it until the run ends.
//!
//! The feed's node is dropped as soon as the run ends (all at goal, time limit, `Stop`), so it
//! is gone before the supervisor removes the run's shared memory, which it only does once no
//! node of the run is alive.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use super::{show, Server};
use crate::monitor::feed::FeedError;
use crate::monitor::live::LiveFeed;
use crate::supervisor::registry::RunRegistry;

/// How often the thread looks for the run in the registry before it is there.
const LOOK_AGAIN: Duration = Duration::from_millis(20);

/// The view's thread; [`LiveView::finish`] (or a drop) ends it.
#[derive(Debug)]
pub struct LiveView {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl LiveView {
    /// Serves run `run_id` on `server` from a thread of its own.
    pub fn start(server: Server, run_id: String) -> std::io::Result<LiveView> {
        Self::start_in(RunRegistry::default_location(), server, run_id)
    }

    /// [`LiveView::start`], with the run looked up in `registry`.
    pub fn start_in(
        registry: RunRegistry,
        mut server: Server,
        run_id: String,
    ) -> std::io::Result<LiveView> {
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::Builder::new()
            .name("hnav-foxglove".into())
            .spawn(move || {
                let mut feed = loop {
                    if flag.load(Ordering::Relaxed) {
                        return;
                    }
                    match LiveFeed::open(&registry, Some(&run_id)) {
                        Ok(feed) => break feed,
                        Err(FeedError::NotFound { .. } | FeedError::Lookup(_)) => {
                            std::thread::sleep(LOOK_AGAIN);
                        }
                        Err(e) => {
                            tracing::warn!("foxglove view: {e}");
                            return;
                        }
                    }
                };
                let shown = show(&mut feed, &mut server, true, &flag);
                drop(feed);
                if let Err(e) = shown {
                    tracing::warn!("foxglove view: {e}");
                }
            })?;
        Ok(LiveView {
            stop,
            thread: Some(thread),
        })
    }

    /// Ends the view (at once if the run has not ended yet) and waits for its thread.
    pub fn finish(mut self) {
        self.end();
    }

    fn end(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for LiveView {
    fn drop(&mut self) {
        self.end();
    }
}
