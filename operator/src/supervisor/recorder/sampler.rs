//! What the recorder keeps of the live topics, decided by simulated time alone (no
//! iceoryx2 here, so the rules are tested on their own).
//!
//! - Ground truth: one sample per robot each time simulated time crosses the next `1 / rate`
//!   boundary ([`SimClock`]); a truth message whose period follows the last one seen by more
//!   than one was preceded by messages the recorder never saw (its buffer overflowed), which
//!   are counted as missed. A period seen again (a restarted sim republishes its last one)
//!   is not sampled twice.
//! - Estimates: the same boundaries, per agent; a boundary passed without a message (the
//!   depth-1 buffer was overwritten before the recorder read it) is counted as skipped.
//! - Neural maps: per agent at most one snapshot per simulated second ([`MAP_INTERVAL_NS`]),
//!   and always the last one each agent published ([`MapThrottle`]).

/// Least simulated time between two recorded snapshots of one agent's neural map.
pub const MAP_INTERVAL_NS: u64 = 1_000_000_000;

/// The sampling boundaries of one stream: every `interval_ns` of simulated time, or every
/// message when the interval is 0.
#[derive(Clone, Copy, Debug, Default)]
pub struct SimClock {
    interval_ns: u64,
    next_ns: Option<u64>,
    /// Boundaries passed with no message taken at them: a later message was the first seen
    /// past more than one (the messages between were overwritten before the recorder read).
    pub skipped: u64,
}

impl SimClock {
    /// Boundaries every `1 / rate_hz` seconds (0: every message).
    pub fn new(rate_hz: u16) -> Self {
        Self {
            interval_ns: if rate_hz == 0 {
                0
            } else {
                1_000_000_000 / u64::from(rate_hz)
            },
            next_ns: None,
            skipped: 0,
        }
    }

    /// Whether a message at `t_ns` is the first at or past the next boundary (then the
    /// boundary after `t_ns` becomes the next).
    pub fn take(&mut self, t_ns: u64) -> bool {
        match self.next_ns {
            Some(n) if t_ns < n => return false,
            Some(n) if self.interval_ns > 0 => self.skipped += (t_ns - n) / self.interval_ns,
            _ => {}
        }
        self.next_ns = Some(match self.interval_ns {
            0 => t_ns.saturating_add(1),
            i => (t_ns / i + 1).saturating_mul(i),
        });
        true
    }
}

/// The truth stream's sampling, gap and collision accounting.
#[derive(Clone, Debug, Default)]
pub struct TruthSampler {
    clock: SimClock,
    last_period: Option<u64>,
    collisions: u32,
    /// Truth messages the recorder never saw.
    pub missed: u64,
    /// Simulated times at which the sim's collision count rose.
    pub collisions_at_ns: Vec<u64>,
}

impl TruthSampler {
    /// Samples at `rate_hz` (0: every message).
    pub fn new(rate_hz: u16) -> Self {
        Self {
            clock: SimClock::new(rate_hz),
            ..Self::default()
        }
    }

    /// Whether the truth of `period` at `t_ns` with `collisions` so far is recorded. A rise
    /// of the collision count is always recorded, so that the report finds the robots where
    /// it happened.
    pub fn take(&mut self, t_ns: u64, period: u64, collisions: u32) -> bool {
        if let Some(last) = self.last_period {
            if period <= last {
                return false;
            }
            self.missed += period - last - 1;
        }
        self.last_period = Some(period);
        let rose = collisions > self.collisions;
        if rose {
            self.collisions = collisions;
            self.collisions_at_ns.push(t_ns);
        }
        self.clock.take(t_ns) || rose
    }
}

/// Per agent: when its last snapshot was recorded, and whether a newer one is held back.
#[derive(Clone, Debug)]
pub struct MapThrottle {
    last_written_ns: Vec<Option<u64>>,
    pending: Vec<bool>,
}

/// What to do with a snapshot just received.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum MapAction {
    /// Write it now.
    Write,
    /// Keep it (replacing an older kept one) to write at the end, unless a later one is
    /// written first.
    Hold,
}

impl MapThrottle {
    /// For `agents` agents.
    pub fn new(agents: usize) -> Self {
        Self {
            last_written_ns: vec![None; agents],
            pending: vec![false; agents],
        }
    }

    /// What to do with agent `agent`'s snapshot received at `t_ns`; `None` for an agent
    /// the run does not have.
    pub fn on_snapshot(&mut self, agent: usize, t_ns: u64) -> Option<MapAction> {
        let last = self.last_written_ns.get_mut(agent)?;
        if last.is_none_or(|l| t_ns >= l.saturating_add(MAP_INTERVAL_NS)) {
            *last = Some(t_ns);
            self.pending[agent] = false;
            Some(MapAction::Write)
        } else {
            self.pending[agent] = true;
            Some(MapAction::Hold)
        }
    }

    /// Holds agent `agent`'s snapshot after all (the file had no room for it before the end).
    pub fn defer(&mut self, agent: usize) {
        if let Some(p) = self.pending.get_mut(agent) {
            *p = true;
        }
    }

    /// Marks agent `agent`'s held snapshot as written anyway (at the end).
    pub fn flushed(&mut self, agent: usize) {
        if let Some(p) = self.pending.get_mut(agent) {
            *p = false;
        }
    }

    /// The agents whose last snapshot is held back and must be written at the end.
    pub fn pending(&self) -> impl Iterator<Item = usize> + '_ {
        self.pending
            .iter()
            .enumerate()
            .filter_map(|(i, p)| p.then_some(i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PERIOD: u64 = 10_000_000;

    #[test]
    fn truth_is_sampled_at_each_boundary_of_simulated_time() {
        let mut s = TruthSampler::new(20);
        let taken: Vec<u64> = (0..21).filter(|p| s.take(p * PERIOD, *p, 0)).collect();
        // 20 Hz over 10 ms periods: every fifth.
        assert_eq!(taken, vec![0, 5, 10, 15, 20]);
        assert_eq!(s.missed, 0);
    }

    #[test]
    fn boundaries_passed_without_a_message_are_counted_as_skipped() {
        let mut c = SimClock::new(20);
        assert!(c.take(0));
        // The next boundary is 50 ms; a message at 160 ms is the first past 50, 100 and 150:
        // it is taken for 150, and 50 and 100 went without one.
        assert!(c.take(16 * PERIOD));
        assert_eq!(c.skipped, 2);
        // 200 ms exactly is the next boundary: nothing skipped.
        assert!(!c.take(19 * PERIOD));
        assert!(c.take(20 * PERIOD));
        assert_eq!(c.skipped, 2);
        // Every message sampled (rate 0): nothing is ever skipped.
        let mut every = SimClock::new(0);
        assert!(every.take(0) && every.take(10 * PERIOD));
        assert_eq!(every.skipped, 0);
    }

    #[test]
    fn gaps_count_as_missed_and_repeats_are_not_sampled_twice() {
        let mut s = TruthSampler::new(20);
        assert!(s.take(0, 0, 0));
        assert!(!s.take(PERIOD, 1, 0));
        // Periods 2..=6 lost; period 7 lies past the 50 ms boundary.
        assert!(s.take(7 * PERIOD, 7, 0));
        assert_eq!(s.missed, 5);
        // A restarted sim republishes period 7.
        assert!(!s.take(7 * PERIOD, 7, 0));
        assert_eq!(s.missed, 5);
    }

    #[test]
    fn a_rise_of_the_collision_count_is_always_sampled() {
        let mut s = TruthSampler::new(20);
        assert!(s.take(0, 0, 0));
        assert!(s.take(PERIOD, 1, 1));
        assert!(!s.take(2 * PERIOD, 2, 1));
        assert!(s.take(3 * PERIOD, 3, 3));
        assert_eq!(s.collisions_at_ns, vec![PERIOD, 3 * PERIOD]);
    }

    #[test]
    fn rate_zero_takes_every_message() {
        let mut c = SimClock::new(0);
        assert!((0..5).all(|p| c.take(p * PERIOD)));
    }

    #[test]
    fn maps_are_throttled_per_agent_and_the_last_is_kept() {
        let mut m = MapThrottle::new(2);
        let s = 1_000_000_000;
        assert_eq!(m.on_snapshot(0, 0), Some(MapAction::Write));
        assert_eq!(m.on_snapshot(1, s / 2), Some(MapAction::Write));
        assert_eq!(m.on_snapshot(0, s / 2), Some(MapAction::Hold));
        assert_eq!(m.pending().collect::<Vec<_>>(), vec![0]);
        assert_eq!(m.on_snapshot(0, s), Some(MapAction::Write));
        assert_eq!(m.pending().count(), 0);
        assert_eq!(m.on_snapshot(1, s), Some(MapAction::Hold));
        m.flushed(1);
        assert_eq!(m.pending().count(), 0);
        assert_eq!(m.on_snapshot(7, 0), None);
    }
}
