//! A process's heartbeat: the sending half of hang detection.
//!
//! Every process of a run (agent, coordinator, sim) beats on the `heartbeat` topic
//! ([`topics::HEARTBEAT`]) from its main loop while it is up, idle waits included: every
//! pass of the loop calls [`Heartbeat::beat`] (a loop that works through a backlog without
//! waiting still beats), and the loop asks [`Heartbeat::until`] for its wait's deadline,
//! which sends the beat that is due and returns the earlier of the loop's own deadline and
//! the next beat. A beat therefore proves
//! that the loop itself turns; a helper thread would go on beating while the loop is stuck.
//! The supervisor's half is `supervisor::run::hang`.
//!
//! A beat is one 32-byte sample written into a loaned chunk (no allocation) and sent without
//! a notification: the supervisor reads every process's last beat at its own deadline, so a
//! beat wakes nobody.
//!
//! ```no_run
//! use std::time::{Duration, Instant};
//! use hnav_runtime::health::Heartbeat;
//! use hnav_runtime::msg::Role;
//! use hnav_runtime::transport::{RunId, Transport, Wake};
//!
//! # fn main() -> Result<(), hnav_runtime::transport::TransportError> {
//! let run = RunId::new("demo-1")?;
//! let transport = Transport::builder(&run).node_name("sim").create()?;
//! let heart = Heartbeat::open(&transport, Role::Sim, 0, 4, Duration::from_millis(50))?;
//! let waiter = transport.waiter()?;
//! let _tick = waiter.attach_interval(Duration::from_secs(1))?;
//! let deadline = Instant::now() + Duration::from_secs(5);
//! while waiter.wait(heart.until(Some(deadline))?)? != Wake::Stop {
//!     if Instant::now() >= deadline {
//!         break;
//!     }
//! }
//! # Ok(()) }
//! ```

use std::cell::Cell;
use std::time::{Duration, Instant};

use crate::clock::monotonic_ns;
use crate::msg::{Heartbeat as Beat, Role};
use crate::topics;
use crate::transport::{Sender, Transport, TransportError};

/// One process's heartbeat sender and its schedule. Beating takes `&self` (a loop's ports
/// stay borrowed by its waiter's attachments).
pub struct Heartbeat {
    sender: Sender<Beat>,
    role: Role,
    index: u32,
    every: Duration,
    /// When the next beat is due; `None` before the first.
    next: Cell<Option<Instant>>,
    seq: Cell<u64>,
}

impl Heartbeat {
    /// Opens the `heartbeat` topic for process `role`/`index` of a swarm of `agents`, to beat
    /// `every` so long (at least 1 ms).
    pub fn open(
        transport: &Transport,
        role: Role,
        index: u32,
        agents: usize,
        every: Duration,
    ) -> Result<Self, TransportError> {
        Ok(Self {
            sender: transport.sender(topics::HEARTBEAT, topics::heartbeat_qos(agents))?,
            role,
            index,
            every: every.max(Duration::from_millis(1)),
            next: Cell::new(None),
            seq: Cell::new(0),
        })
    }

    /// Sends a beat if one is due (the first call always does) and returns when the next
    /// one is due.
    pub fn beat(&self) -> Result<Instant, TransportError> {
        let now = Instant::now();
        if let Some(next) = self.next.get().filter(|&n| now < n) {
            return Ok(next);
        }
        let seq = self.seq.get();
        self.sender
            .send_silently(Beat::new(self.role, self.index, seq, monotonic_ns()))?;
        self.seq.set(seq + 1);
        // From now, not from the missed due time: a loop that was late beats once, not in
        // a burst.
        let next = now + self.every;
        self.next.set(Some(next));
        Ok(next)
    }

    /// Beats if due and returns the deadline a loop should wait to: the earlier of its own
    /// `deadline` (none = wait only for input) and the next beat.
    pub fn until(&self, deadline: Option<Instant>) -> Result<Option<Instant>, TransportError> {
        let next = self.beat()?;
        Ok(Some(deadline.map_or(next, |d| d.min(next))))
    }

    /// Beats sent so far.
    pub fn beats(&self) -> u64 {
        self.seq.get()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::{purge_run, RunId};

    #[test]
    fn a_beat_is_sent_when_due_and_read_as_the_senders_latest() {
        let run = RunId::unique("heart");
        {
            let t = Transport::builder(&run)
                .handle_signals(false)
                .create()
                .unwrap();
            let rx = t
                .receiver::<Beat>(topics::HEARTBEAT, topics::heartbeat_qos(2))
                .unwrap();
            let every = Duration::from_millis(20);
            let heart = Heartbeat::open(&t, Role::Agent, 1, 2, every).unwrap();
            let first = heart.beat().unwrap();
            // Not due again before `every`: the same deadline, no second beat.
            assert_eq!(heart.beat().unwrap(), first);
            assert_eq!(heart.beats(), 1);
            let mine = Instant::now() + Duration::from_secs(60);
            assert_eq!(heart.until(Some(mine)).unwrap(), Some(first));
            let soon = Instant::now();
            assert_eq!(heart.until(Some(soon)).unwrap(), Some(soon));
            std::thread::sleep(first.saturating_duration_since(Instant::now()));
            heart.beat().unwrap();
            assert_eq!(heart.beats(), 2);
            // Depth 1: only the latest beat is left to read.
            let mut got = Vec::new();
            rx.drain(|b| got.push(*b)).unwrap();
            assert_eq!(got.len(), 1, "{got:?}");
            assert_eq!(
                (got[0].role, got[0].index, got[0].seq),
                (Role::Agent as u8, 1, 1)
            );
        }
        purge_run(&run).unwrap();
    }
}
