//! Summary statistics of one series of latency samples.

use anyhow::{ensure, Context, Result};
use hdrhistogram::Histogram;

/// Significant decimal digits the percentile histogram keeps: 3 digits means a percentile is
/// off by at most 0.1 %, far below the run-to-run noise of a latency measurement.
const SIGNIFICANT_DIGITS: u8 = 3;

/// Mean and percentiles of a series of latencies, all in nanoseconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    /// Number of samples.
    pub n: u64,
    /// Exact arithmetic mean (from the exact sum, not from the histogram).
    pub mean_ns: f64,
    /// Median.
    pub p50_ns: u64,
    /// 90th percentile.
    pub p90_ns: u64,
    /// 99th percentile.
    pub p99_ns: u64,
    /// 99.9th percentile.
    pub p999_ns: u64,
    /// Exact maximum.
    pub max_ns: u64,
}

impl Summary {
    /// Summarises `samples` (nanoseconds). Every sample counts: nothing is trimmed.
    pub fn from_ns(samples: &[u64]) -> Result<Self> {
        ensure!(!samples.is_empty(), "no samples to summarise");
        // An auto-resizing histogram: no upper bound to guess, so a multi-second outlier is
        // recorded like any other sample instead of being clipped or rejected.
        let mut hist = Histogram::<u64>::new(SIGNIFICANT_DIGITS).context("create histogram")?;
        let mut sum: u128 = 0;
        for &v in samples {
            hist.record(v).context("record sample")?;
            sum += u128::from(v);
        }
        let max_ns = samples.iter().copied().max().unwrap_or(0);
        // The histogram reports the top of a value's bucket (0.1 % wide), which can lie above
        // the exact maximum: no percentile may exceed it.
        let at = |q: f64| hist.value_at_quantile(q).min(max_ns);
        Ok(Self {
            n: samples.len() as u64,
            mean_ns: sum as f64 / samples.len() as f64,
            p50_ns: at(0.50),
            p90_ns: at(0.90),
            p99_ns: at(0.99),
            p999_ns: at(0.999),
            max_ns,
        })
    }

    /// The mean in microseconds.
    pub fn mean_us(&self) -> f64 {
        self.mean_ns / 1e3
    }

    /// The median in microseconds.
    pub fn p50_us(&self) -> f64 {
        self.p50_ns as f64 / 1e3
    }

    /// The 90th percentile in microseconds.
    pub fn p90_us(&self) -> f64 {
        self.p90_ns as f64 / 1e3
    }

    /// The 99th percentile in microseconds.
    pub fn p99_us(&self) -> f64 {
        self.p99_ns as f64 / 1e3
    }

    /// The 99.9th percentile in microseconds.
    pub fn p999_us(&self) -> f64 {
        self.p999_ns as f64 / 1e3
    }

    /// The maximum in microseconds.
    pub fn max_us(&self) -> f64 {
        self.max_ns as f64 / 1e3
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Within the histogram's resolution (3 significant digits: 0.1 %).
    fn close(actual: u64, expected: u64) -> bool {
        actual.abs_diff(expected) * 1000 <= expected
    }

    #[test]
    fn mean_is_exact_and_percentiles_match_known_data() {
        // 1..=1000 ns: mean 500.5, p50 = 500, p90 = 900, p99 = 990, p99.9 = 999.
        let samples: Vec<u64> = (1..=1000).collect();
        let s = Summary::from_ns(&samples).unwrap();
        assert_eq!(s.n, 1000);
        assert_eq!(s.mean_ns, 500.5);
        assert_eq!(s.p50_ns, 500);
        assert_eq!(s.p90_ns, 900);
        assert_eq!(s.p99_ns, 990);
        assert_eq!(s.p999_ns, 999);
        assert_eq!(s.max_ns, 1000);
        assert!((s.mean_us() - 0.5005).abs() < 1e-12);
    }

    #[test]
    fn large_values_keep_three_significant_digits() {
        // 99 samples of 10 µs and one of 5 s: the outlier moves the mean but not p99.
        let mut samples = vec![10_000u64; 99];
        samples.push(5_000_000_000);
        let s = Summary::from_ns(&samples).unwrap();
        assert_eq!(s.mean_ns, (99.0 * 10_000.0 + 5e9) / 100.0);
        assert!(close(s.p50_ns, 10_000), "p50 {}", s.p50_ns);
        assert!(close(s.p99_ns, 10_000), "p99 {}", s.p99_ns);
    }

    #[test]
    fn unsorted_input_and_zero_are_fine() {
        let s = Summary::from_ns(&[30, 0, 20, 10]).unwrap();
        assert_eq!(s.mean_ns, 15.0);
        assert_eq!(s.p50_ns, 10);
        assert_eq!(s.p99_ns, 30);
    }

    /// The `hnav-bench latency` quick run that found it: a 13 551 ns p99.9 over a 13 550 ns
    /// maximum, the top of the maximum's histogram bucket.
    #[test]
    fn no_percentile_exceeds_the_maximum() {
        let mut samples = vec![270u64; 499];
        samples.push(13_550);
        let s = Summary::from_ns(&samples).unwrap();
        assert_eq!(s.max_ns, 13_550);
        assert!(s.p999_ns <= s.max_ns, "{} > {}", s.p999_ns, s.max_ns);
        assert!(s.p99_ns <= s.p999_ns);
    }

    #[test]
    fn empty_input_is_an_error() {
        assert!(Summary::from_ns(&[]).is_err());
    }
}
