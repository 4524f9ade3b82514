//! The removal of dead nodes' shared memory, off the watch's thread ([`Sweeper`]).
//!
//! Removing a dead node's stale resources opens every service it used and wakes its peers.
//! For a coordinator, in a debug build on a loaded machine, that took about 300 ms (strace of
//! `hnav run` on plan 53 of the chaos campaign), and a watch busy with it reaps no one: two
//! agents SIGKILLed together with the coordinator had exited 42 and 190 ms after the signal,
//! but were told `Down` 313 ms after it. On a thread of its own the clean-up no longer stands
//! between a child's exit and its `Down`.

use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use hnav_runtime::transport::Transport;
use iceoryx2::config::Config;

/// Clean-ups asked for and done; `quit` ends the thread.
#[derive(Default)]
struct Counts {
    asked: u64,
    done: u64,
    quit: bool,
}

type Shared = Arc<(Mutex<Counts>, Condvar)>;

fn lock(shared: &Shared) -> MutexGuard<'_, Counts> {
    // The counters stay consistent even if a clean-up panicked mid-way.
    shared.0.lock().unwrap_or_else(PoisonError::into_inner)
}

/// A thread that removes the run's dead nodes' resources when asked; asks that come while
/// it works are served by one more pass.
pub(super) struct Sweeper {
    shared: Shared,
    thread: Option<JoinHandle<()>>,
}

impl Sweeper {
    /// The sweeper of the run whose iceoryx2 config is `config`.
    pub(super) fn start(config: Config) -> std::io::Result<Self> {
        let shared: Shared = Arc::default();
        let theirs = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("dead-node-sweeper".into())
            .spawn(move || sweep_when_asked(&theirs, &config))?;
        Ok(Sweeper {
            shared,
            thread: Some(thread),
        })
    }

    /// Asks for a clean-up; returns at once.
    pub(super) fn sweep(&self) {
        lock(&self.shared).asked += 1;
        self.shared.1.notify_all();
    }

    /// Waits until every clean-up asked for so far is done, at most `timeout`: a respawned
    /// process should find its predecessor's ports gone. `false` on timeout.
    pub(super) fn settle(&self, timeout: Duration) -> bool {
        let until = Instant::now() + timeout;
        let mut c = lock(&self.shared);
        while c.done < c.asked {
            let left = until.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return false;
            }
            c = match self.shared.1.wait_timeout(c, left) {
                Ok((c, _)) => c,
                Err(poisoned) => poisoned.into_inner().0,
            };
        }
        true
    }
}

fn sweep_when_asked(shared: &Shared, config: &Config) {
    loop {
        let target = {
            let mut c = lock(shared);
            while !c.quit && c.done == c.asked {
                c = match shared.1.wait(c) {
                    Ok(c) => c,
                    Err(poisoned) => poisoned.into_inner(),
                };
            }
            if c.quit {
                return;
            }
            c.asked
        };
        if let Err(e) = Transport::cleanup_dead_nodes_with(config) {
            tracing::warn!("dead-node clean-up failed: {e}");
        }
        lock(shared).done = target;
        shared.1.notify_all();
    }
}

impl Drop for Sweeper {
    fn drop(&mut self) {
        lock(&self.shared).quit = true;
        self.shared.1.notify_all();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::transport::{PurgeOnDrop, RunId};

    #[test]
    fn every_sweep_asked_for_is_done_before_settle_returns() {
        let run = PurgeOnDrop(RunId::unique("sweep"));
        let transport = Transport::builder(&run.0)
            .handle_signals(false)
            .create()
            .unwrap();
        let sweeper = Sweeper::start(transport.config().clone()).unwrap();
        assert!(sweeper.settle(Duration::ZERO), "nothing asked: settled");
        for _ in 0..3 {
            sweeper.sweep();
        }
        assert!(sweeper.settle(Duration::from_secs(30)));
        let c = lock(&sweeper.shared);
        assert_eq!((c.asked, c.done), (3, 3));
    }
}
