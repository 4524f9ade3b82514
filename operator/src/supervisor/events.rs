//! The run's event journal, `DIR/events.jsonl`: what the supervisor did to its processes and
//! saw of them, one JSON object per line, each stamped with [`monotonic_ns`].
//!
//! It is the supervisor's side of the chaos campaign's figures: a fault's signal, a process's
//! exit, a hang declared, a respawn and the respawned process's `Up` carry the same clock as
//! what an observer of the run's topics sees, so "killed → coordinator told" and "respawned →
//! first round" are differences of two stamps. The consensus log cannot hold these: it must
//! stay byte-identical between runs.
//!
//! Events are rare (per fault and per restart, never per round), so each line is written at
//! once, in one `write` to the file open in append mode (`hnav kill` appends to a live run's
//! journal too); a failed write (a full disk) costs the journal, never the run: it is
//! reported once and the journal stops.
//!
//! Lines are in the order things happened. Every line is written under an exclusive `flock`
//! of the file, and a writer that makes something happen that another writer will see and
//! record holds the lock across both ([`RunEvents::hold`]): `hnav kill` takes it, signals,
//! writes its `signalled` line and only then lets go, so the supervisor, woken by the death
//! at once, writes its `exited` after it (issue 34: it used to come first).
//!
//! ```json
//! {"t_ns":81234567890,"event":"signalled","node":"agent-3","pid":4242,"signal":"SIGKILL","fault":0,"round":40}
//! ```

use std::cell::RefCell;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::Serialize;

use hnav_runtime::clock::monotonic_ns;

/// File name of the journal in the run directory.
pub const EVENTS_FILE: &str = "events.jsonl";

/// What happened to one process of the run.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "event")]
pub enum RunEvent {
    /// A signal was sent to a process: a planned fault (`fault` = its index in the plan, in
    /// the order of the scenario's `[[faults]]` then the command line's), `hnav kill`, or the
    /// supervisor's own (a hang).
    Signalled {
        /// Node name, e.g. `agent-3`.
        node: String,
        /// The process signalled.
        pid: u32,
        /// `SIGKILL`, `SIGTERM`, `SIGSTOP`, `SIGCONT`.
        signal: String,
        /// The fault plan entry that sent it, if any.
        fault: Option<usize>,
        /// The last committed round the supervisor knew of when it sent it.
        round: u64,
    },
    /// A process exited and was reaped.
    Exited {
        /// Node name.
        node: String,
        /// The process that exited.
        pid: u32,
        /// How it ended, e.g. `killed by SIGKILL`, `exit code 0`.
        how: String,
    },
    /// A process missed its heartbeat deadline and is declared hung.
    Hung {
        /// Node name.
        node: String,
        /// The hung process.
        pid: u32,
        /// How long it had been silent, in milliseconds.
        silent_ms: u64,
    },
    /// A process was (re)spawned after an exit.
    Spawned {
        /// Node name.
        node: String,
        /// The new process.
        pid: u32,
        /// Its role's restarts so far, this one included.
        restarts: u32,
    },
    /// A respawned process announced itself up (the peers are told `Restarted` now).
    Up {
        /// Node name.
        node: String,
        /// The process that came up.
        pid: u32,
    },
    /// A process is left down for good (its restart budget or policy), and what that means
    /// for the run.
    GaveUp {
        /// Node name.
        node: String,
        /// Why it is not restarted, and what happens instead.
        why: String,
    },
}

/// Stamped with [`monotonic_ns`] when it is written.
#[derive(Serialize)]
struct Stamped<'e> {
    t_ns: u64,
    #[serde(flatten)]
    event: &'e RunEvent,
}

/// The open journal of one run. Recording takes `&self` (the supervisor's slots stay
/// borrowed by its waiter while events happen).
///
/// The file is open in append mode and each line goes out in one `write`, so that lines
/// `hnav kill` appends to a live run's journal ([`RunEvents::append`]) and the supervisor's
/// own never overwrite or split each other.
pub struct RunEvents {
    path: PathBuf,
    out: RefCell<Option<File>>,
}

impl RunEvents {
    /// Creates (truncates) `dir/events.jsonl`. A journal that cannot be created is reported
    /// and the run goes on without it.
    pub fn create(dir: &Path) -> Self {
        let path = dir.join(EVENTS_FILE);
        let out = File::create(&path).and_then(|_| open_append(&path));
        Self::from_open(path, out)
    }

    /// Opens `dir/events.jsonl` to add lines after the ones already there (created if
    /// missing): another process's view of a live run's journal.
    pub fn append(dir: &Path) -> Self {
        let path = dir.join(EVENTS_FILE);
        let out = open_append(&path);
        Self::from_open(path, out)
    }

    fn from_open(path: PathBuf, out: std::io::Result<File>) -> Self {
        let out = match out {
            Ok(f) => Some(f),
            Err(e) => {
                tracing::warn!("no event journal {}: {e}", path.display());
                None
            }
        };
        Self {
            path,
            out: RefCell::new(out),
        }
    }

    /// A journal that records nothing (tools that borrow the supervisor's pieces).
    pub fn disabled() -> Self {
        Self {
            path: PathBuf::new(),
            out: RefCell::new(None),
        }
    }

    /// Whether lines are being written.
    pub fn is_open(&self) -> bool {
        self.out.borrow().is_some()
    }

    /// Appends `event`, stamped now, in one write under the file's lock.
    pub fn record(&self, event: RunEvent) {
        self.hold().record(event);
    }

    /// Takes the file's exclusive lock (waiting for another writer's line, or its [`Held`]
    /// span, to end) until the [`Held`] is dropped: lines the other writers record meanwhile
    /// come after the ones recorded through it.
    pub fn hold(&self) -> Held<'_> {
        let locked = match self.out.borrow().as_ref().map(File::lock) {
            Some(Ok(())) => true,
            // Unlocked, the line is still written; only its order is not guaranteed.
            Some(Err(e)) => {
                tracing::debug!("event journal {} not locked: {e}", self.path.display());
                false
            }
            None => false,
        };
        Held {
            journal: self,
            locked,
        }
    }

    fn write_line(&self, event: &RunEvent) {
        let mut slot = self.out.borrow_mut();
        let Some(out) = slot.as_mut() else {
            return;
        };
        let stamped = Stamped {
            t_ns: monotonic_ns(),
            event,
        };
        let written = serde_json::to_vec(&stamped)
            .map_err(std::io::Error::from)
            .and_then(|mut line| {
                line.push(b'\n');
                out.write_all(&line)
            });
        if let Err(e) = written {
            tracing::warn!("event journal {} stopped: {e}", self.path.display());
            *slot = None;
        }
    }
}

/// A journal locked against every other writer of the file ([`RunEvents::hold`]); unlocked
/// when dropped.
pub struct Held<'j> {
    journal: &'j RunEvents,
    locked: bool,
}

impl Held<'_> {
    /// Appends `event`, stamped now, in one write.
    pub fn record(&self, event: RunEvent) {
        self.journal.write_line(&event);
    }
}

impl Drop for Held<'_> {
    fn drop(&mut self) {
        if self.locked {
            if let Some(out) = self.journal.out.borrow().as_ref() {
                let _ = out.unlock();
            }
        }
    }
}

fn open_append(path: &Path) -> std::io::Result<File> {
    OpenOptions::new().create(true).append(true).open(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_event_is_one_stamped_json_line() {
        let dir = tempfile::tempdir().unwrap();
        let j = RunEvents::create(dir.path());
        j.record(RunEvent::Signalled {
            node: "agent-3".into(),
            pid: 42,
            signal: "SIGKILL".into(),
            fault: Some(0),
            round: 40,
        });
        j.record(RunEvent::Up {
            node: "agent-3".into(),
            pid: 43,
        });
        let text = std::fs::read_to_string(dir.path().join(EVENTS_FILE)).unwrap();
        let lines: Vec<serde_json::Value> = text
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        assert_eq!(lines.len(), 2);
        assert_eq!(lines[0]["event"], "signalled");
        assert_eq!(lines[0]["signal"], "SIGKILL");
        assert_eq!(lines[1]["event"], "up");
        let (t0, t1) = (
            lines[0]["t_ns"].as_u64().unwrap(),
            lines[1]["t_ns"].as_u64().unwrap(),
        );
        assert!(t0 > 0 && t1 >= t0);
    }

    #[test]
    fn lines_appended_by_another_writer_are_kept() {
        let dir = tempfile::tempdir().unwrap();
        let supervisor = RunEvents::create(dir.path());
        supervisor.record(RunEvent::Up {
            node: "sim".into(),
            pid: 1,
        });
        let kill = RunEvents::append(dir.path());
        kill.record(RunEvent::Signalled {
            node: "agent-0".into(),
            pid: 2,
            signal: "SIGKILL".into(),
            fault: None,
            round: 7,
        });
        supervisor.record(RunEvent::Exited {
            node: "agent-0".into(),
            pid: 2,
            how: "killed by SIGKILL".into(),
        });
        let text = std::fs::read_to_string(dir.path().join(EVENTS_FILE)).unwrap();
        let events: Vec<String> = text
            .lines()
            .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap()["event"].to_string())
            .collect();
        assert_eq!(events, ["\"up\"", "\"signalled\"", "\"exited\""]);
    }

    #[test]
    fn a_held_journal_keeps_every_other_writer_out_until_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let supervisor = RunEvents::create(dir.path());
        let kill = RunEvents::append(dir.path());
        let other = File::open(dir.path().join(EVENTS_FILE)).unwrap();
        let held = kill.hold();
        assert!(
            matches!(other.try_lock(), Err(std::fs::TryLockError::WouldBlock)),
            "another writer could write while the journal is held"
        );
        held.record(RunEvent::Up {
            node: "sim".into(),
            pid: 1,
        });
        drop(held);
        other.try_lock().expect("free once the hold is dropped");
        other.unlock().unwrap();
        supervisor.record(RunEvent::Up {
            node: "sim".into(),
            pid: 2,
        });
        let text = std::fs::read_to_string(dir.path().join(EVENTS_FILE)).unwrap();
        assert_eq!(text.lines().count(), 2, "{text}");
    }

    #[test]
    fn a_journal_that_cannot_be_written_is_dropped_quietly() {
        let j = RunEvents::create(Path::new("/nonexistent-hnav-dir"));
        j.record(RunEvent::Up {
            node: "sim".into(),
            pid: 1,
        });
        assert!(j.out.borrow().is_none());
    }
}
