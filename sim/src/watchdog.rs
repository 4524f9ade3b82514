//! The motor watchdog: a wheel command older than the configured age is replaced by braking,
//! as a real motor driver does when its controller stops talking to it.

/// Sim-time watchdog shared by all robots of a world.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Watchdog {
    /// Largest command age that still drives the wheels, ns.
    pub max_age_ns: u64,
}

impl Watchdog {
    /// A watchdog of `ms` milliseconds.
    pub fn from_ms(ms: u32) -> Watchdog {
        Watchdog {
            max_age_ns: u64::from(ms) * 1_000_000,
        }
    }

    /// Whether a robot whose last command arrived at `last_ns` (`None`: never) must brake
    /// at `now_ns`.
    #[inline]
    pub fn expired(&self, last_ns: Option<u64>, now_ns: u64) -> bool {
        match last_ns {
            None => true,
            Some(t) => now_ns.saturating_sub(t) > self.max_age_ns,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expiry() {
        let w = Watchdog::from_ms(100);
        assert!(w.expired(None, 0));
        assert!(!w.expired(Some(0), 100_000_000));
        assert!(w.expired(Some(0), 100_000_001));
        assert!(!w.expired(Some(5), 0), "a command from the future is fresh");
    }
}
