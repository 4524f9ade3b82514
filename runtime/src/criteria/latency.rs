//! [`Histogram`]: latencies in microseconds, counted into log-linear buckets (exact below
//! 64 µs, then 64 buckets per power of two: a percentile is within 1.6 % of the true
//! value), so that counting allocates nothing and a run of any length fits in a few KiB.

use serde::{Deserialize, Serialize};

/// Sub-buckets per power of two.
const SUB: u64 = 64;
/// log2 of [`SUB`].
const SUB_BITS: u32 = 6;
/// Powers of two above the exact range: values up to 2^46 µs (two years).
const OCTAVES: u64 = 40;
/// Buckets in all.
const BUCKETS: usize = (SUB + OCTAVES * SUB) as usize;

/// A latency histogram (see the [module docs](self)).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Histogram {
    counts: Vec<u64>,
    total: u64,
}

impl Default for Histogram {
    fn default() -> Self {
        Histogram {
            counts: vec![0; BUCKETS],
            total: 0,
        }
    }
}

/// The bucket of `us`.
fn bucket(us: u64) -> usize {
    if us < SUB {
        return us as usize;
    }
    let exp = 63 - us.leading_zeros(); // >= SUB_BITS
    let shift = exp - SUB_BITS;
    let sub = (us >> shift) & (SUB - 1);
    let i = SUB + u64::from(shift) * SUB + sub;
    (i as usize).min(BUCKETS - 1)
}

/// The smallest value of bucket `i`.
fn lower(i: usize) -> u64 {
    let i = i as u64;
    if i < SUB {
        return i;
    }
    let shift = (i - SUB) / SUB;
    let sub = (i - SUB) % SUB;
    (SUB + sub) << shift
}

/// The value a bucket stands for: the middle of its range.
fn middle(i: usize) -> u64 {
    let lo = lower(i);
    let hi = if i + 1 < BUCKETS {
        lower(i + 1)
    } else {
        lo + 1
    };
    lo + (hi - lo) / 2
}

/// A histogram as it is stored: `[bucket's smallest value in µs, count]` for each bucket
/// that has any.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Stored(pub Vec<[u64; 2]>);

impl Histogram {
    /// Counts one latency of `us` microseconds.
    #[inline]
    pub fn record(&mut self, us: u64) {
        let c = &mut self.counts[bucket(us)];
        *c = c.saturating_add(1);
        self.total = self.total.saturating_add(1);
    }

    /// Latencies counted.
    pub fn len(&self) -> u64 {
        self.total
    }

    /// Whether none was counted.
    pub fn is_empty(&self) -> bool {
        self.total == 0
    }

    /// The `p`-quantile (`0 < p <= 1`) by nearest rank, in µs; 0 when empty.
    pub fn percentile(&self, p: f64) -> u64 {
        if self.total == 0 {
            return 0;
        }
        let rank = ((p * self.total as f64).ceil() as u64).clamp(1, self.total);
        let mut seen = 0u64;
        for (i, &c) in self.counts.iter().enumerate() {
            seen += c;
            if seen >= rank {
                return middle(i);
            }
        }
        middle(BUCKETS - 1)
    }

    /// The buckets that have any, for storing.
    pub fn to_stored(&self) -> Stored {
        Stored(
            self.counts
                .iter()
                .enumerate()
                .filter(|(_, &c)| c > 0)
                .map(|(i, &c)| [lower(i), c])
                .collect(),
        )
    }

    /// The histogram `stored` describes (a value is counted in the bucket it falls in).
    pub fn from_stored(stored: &Stored) -> Self {
        let mut h = Histogram::default();
        for &[us, count] in &stored.0 {
            let c = &mut h.counts[bucket(us)];
            *c = c.saturating_add(count);
            h.total = h.total.saturating_add(count);
        }
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_are_exact_below_64_and_within_1_6_percent_above() {
        for us in [
            0u64,
            1,
            63,
            64,
            65,
            127,
            128,
            1000,
            12_345,
            10_000_000,
            u64::MAX / 4,
        ] {
            let b = bucket(us);
            assert!(lower(b) <= us, "{us}: bucket from {}", lower(b));
            if b + 1 < BUCKETS {
                assert!(us < lower(b + 1), "{us}: next bucket from {}", lower(b + 1));
            }
            if us < 64 {
                assert_eq!(middle(b), us);
            }
            let err = (middle(b) as f64 - us as f64).abs() / (us.max(1) as f64);
            assert!(us >= 1 << 46 || err <= 1.0 / 64.0, "{us}: {}", middle(b));
        }
    }

    #[test]
    fn percentiles_by_nearest_rank_and_a_stored_round_trip() {
        let mut h = Histogram::default();
        assert_eq!(h.percentile(0.5), 0);
        // 1..=100 µs: p50 is 50, p99 is 99 (within the bucket above 64).
        for us in 1..=100 {
            h.record(us);
        }
        assert_eq!(h.len(), 100);
        assert_eq!(h.percentile(0.5), 50);
        let p99 = h.percentile(0.99);
        assert!((98..=100).contains(&p99), "{p99}");
        let back = Histogram::from_stored(&h.to_stored());
        assert_eq!(back, h);
        let json = serde_json::to_string(&h.to_stored()).unwrap();
        assert!(json.starts_with("[[1,1],[2,1]"), "{json}");
    }
}
