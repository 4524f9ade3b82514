//! The simulation's random numbers ([`Rng`]): SplitMix64 streams drawn from the run's seed,
//! one per purpose, so that a change to one purpose's draws (a nemesis event left out while
//! shrinking) leaves the others' sequence alone as far as it can.

use hnav_runtime::hash::SplitMix64;

/// One seeded stream.
#[derive(Clone, Debug)]
pub struct Rng(SplitMix64);

impl Rng {
    /// The stream `purpose` of `seed`.
    pub fn new(seed: u64, purpose: u64) -> Self {
        let mut mix = SplitMix64::new(seed ^ purpose.wrapping_mul(0xa076_1d64_78bd_642f));
        Rng(SplitMix64::new(mix.next_u64()))
    }

    /// A uniform number in `lo..hi` (`lo` when the range is empty).
    pub fn range(&mut self, lo: u64, hi: u64) -> u64 {
        lo + self.0.below(hi.saturating_sub(lo))
    }

    /// True with probability `percent` / 100.
    pub fn chance(&mut self, percent: u64) -> bool {
        self.0.below(100) < percent
    }

    /// One of `items` (which must not be empty).
    pub fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[self.0.below(items.len() as u64) as usize]
    }
}
