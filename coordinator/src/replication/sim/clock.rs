//! Simulated time ([`Time`]), owned by the scheduler, and each replica's tick clock
//! ([`TickClock`]): the replica's logical clock runs on it, at its normal rate, fast, or not
//! at all, as the clock nemesis sets it.

use std::fmt;

/// Simulated time: microseconds since the run started.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Debug, Default)]
pub struct Time(pub u64);

impl Time {
    /// `ms` milliseconds after the start.
    pub const fn ms(ms: u64) -> Time {
        Time(ms * 1000)
    }

    /// `us` microseconds later.
    pub fn after(self, us: u64) -> Time {
        Time(self.0 + us)
    }

    /// Whole milliseconds since the start.
    pub fn as_ms(self) -> u64 {
        self.0 / 1000
    }
}

impl fmt::Display for Time {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{:03}s", self.0 / 1_000_000, self.0 / 1000 % 1000)
    }
}

/// How fast a replica's clock runs.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Rate {
    /// One tick per period.
    Normal,
    /// This many ticks per period.
    Fast(u32),
    /// No ticks: the clock stands still.
    Stalled,
}

/// A replica's tick clock: when its next tick is due.
#[derive(Clone, Debug)]
pub struct TickClock {
    /// Microseconds between ticks at the normal rate (the coordinator's
    /// `raft_heartbeat_ms`).
    period: u64,
    rate: Rate,
    /// When the next tick is due; `None` while the clock stands still or the replica is not
    /// running.
    next: Option<Time>,
}

impl TickClock {
    /// A clock ticking every `period` microseconds, not started.
    pub fn new(period: u64) -> Self {
        TickClock {
            period,
            rate: Rate::Normal,
            next: None,
        }
    }

    /// Its rate now.
    pub fn rate(&self) -> Rate {
        self.rate
    }

    /// Sets the rate; the next tick is due one interval of the new rate from `now`.
    pub fn set_rate(&mut self, rate: Rate, now: Time) -> Option<Time> {
        self.rate = rate;
        self.start(now)
    }

    /// Starts (or restarts) the clock at `now`, the first tick `phase` microseconds later
    /// (within one interval); returns when it is due.
    pub fn start_with_phase(&mut self, now: Time, phase: u64) -> Option<Time> {
        self.next = self.interval().map(|i| now.after(phase % i.max(1)));
        self.next
    }

    /// Starts (or restarts) the clock: the next tick one interval from `now`.
    pub fn start(&mut self, now: Time) -> Option<Time> {
        self.next = self.interval().map(|i| now.after(i));
        self.next
    }

    /// Stops it (the replica is down or paused).
    pub fn stop(&mut self) {
        self.next = None;
    }

    /// Whether a tick scheduled for `at` is the one due (not one made stale by a change of
    /// rate, a pause or a crash).
    pub fn is_due(&self, at: Time) -> bool {
        self.next == Some(at)
    }

    /// After the tick at `now`: when the next is due.
    pub fn ticked(&mut self, now: Time) -> Option<Time> {
        self.start(now)
    }

    fn interval(&self) -> Option<u64> {
        match self.rate {
            Rate::Normal => Some(self.period),
            Rate::Fast(k) => Some((self.period / u64::from(k.max(1))).max(1)),
            Rate::Stalled => None,
        }
    }
}
