//! Intervals for the experiments' tables: Wilson's score interval for a success rate and a
//! percentile bootstrap for a mean. Both are the usual choices for the sample sizes the seeds
//! report (100 runs a setting): Wilson stays inside [0, 1] and keeps its coverage near 0 % and
//! 100 %, where the normal approximation does not; the bootstrap assumes nothing about the
//! shape of a step-count distribution, which is skewed.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// z of a two-sided 95 % interval.
pub const Z95: f64 = 1.959_963_984_540_054;

/// A closed interval `[lo, hi]`.
#[derive(Clone, Copy, PartialEq, Debug, serde::Serialize)]
pub struct Interval {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
}

/// Wilson's score interval for `successes` of `n` trials at normal quantile `z`; `None` for
/// `n == 0` or `successes > n`.
pub fn wilson(successes: u64, n: u64, z: f64) -> Option<Interval> {
    if n == 0 || successes > n {
        return None;
    }
    let n = n as f64;
    let p = successes as f64 / n;
    let z2 = z * z;
    let centre = (p + z2 / (2.0 * n)) / (1.0 + z2 / n);
    let half = z / (1.0 + z2 / n) * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    // At 0 or n successes the bound is exactly 0 or 1; the subtraction leaves a rounding
    // residue (3.5e-18 at 0 of 100) that would print as a nonzero lower bound.
    Some(Interval {
        lo: if successes == 0 {
            0.0
        } else {
            (centre - half).max(0.0)
        },
        hi: if successes as f64 == n {
            1.0
        } else {
            (centre + half).min(1.0)
        },
    })
}

/// The mean of `samples`, `None` if there are none.
pub fn mean(samples: &[f64]) -> Option<f64> {
    (!samples.is_empty()).then(|| samples.iter().sum::<f64>() / samples.len() as f64)
}

/// Percentile bootstrap interval of the mean at level `1 - alpha` from `resamples`
/// resamples drawn with `seed`; `None` if there are no samples or no resamples.
pub fn bootstrap_mean(
    samples: &[f64],
    resamples: usize,
    alpha: f64,
    seed: u64,
) -> Option<Interval> {
    if samples.is_empty() || resamples == 0 {
        return None;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = samples.len();
    let mut means: Vec<f64> = (0..resamples)
        .map(|_| (0..n).map(|_| samples[rng.gen_range(0..n)]).sum::<f64>() / n as f64)
        .collect();
    means.sort_by(f64::total_cmp);
    let at = |q: f64| means[((q * resamples as f64) as usize).min(resamples - 1)];
    Some(Interval {
        lo: at(alpha / 2.0),
        hi: at(1.0 - alpha / 2.0),
    })
}

/// Two algorithms on the same tasks, compared on the tasks both solve.
#[derive(Clone, Copy, PartialEq, Debug, serde::Serialize)]
pub struct Paired {
    /// Tasks both solved.
    pub n: u64,
    /// Mean of the first algorithm's values on those tasks.
    pub mean_a: Option<f64>,
    /// Mean of the second's.
    pub mean_b: Option<f64>,
    /// Mean of the per-task differences `b - a` (equal to `mean_b - mean_a`).
    pub mean_diff: Option<f64>,
    /// Bootstrap 95 % interval of `mean_diff` (tasks resampled, the pairs kept together).
    pub diff_ci: Option<Interval>,
    /// Median of the per-task differences (the mean of the middle two for an even count):
    /// step counts have long tails, and a few tasks can carry the mean.
    pub median_diff: Option<f64>,
    /// Tasks where `b` is lower, and where it is higher (ties in neither).
    pub b_lower: u64,
    /// See `b_lower`.
    pub b_higher: u64,
}

/// The median of `samples`, `None` if there are none.
pub fn median(samples: &[f64]) -> Option<f64> {
    let mut s = samples.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(s[n / 2]),
        _ => Some((s[n / 2 - 1] + s[n / 2]) / 2.0),
    }
}

/// Compares `a` and `b`, one value per task or `None` where the algorithm failed, on the
/// tasks both solved. The bootstrap resamples tasks, so the interval is the paired one.
pub fn paired(a: &[Option<f64>], b: &[Option<f64>], resamples: usize, seed: u64) -> Paired {
    let both: Vec<(f64, f64)> = a
        .iter()
        .zip(b)
        .filter_map(|(x, y)| Some(((*x)?, (*y)?)))
        .collect();
    let xs: Vec<f64> = both.iter().map(|p| p.0).collect();
    let ys: Vec<f64> = both.iter().map(|p| p.1).collect();
    let diffs: Vec<f64> = both.iter().map(|p| p.1 - p.0).collect();
    Paired {
        n: both.len() as u64,
        mean_a: mean(&xs),
        mean_b: mean(&ys),
        mean_diff: mean(&diffs),
        diff_ci: bootstrap_mean(&diffs, resamples, 0.05, seed),
        median_diff: median(&diffs),
        b_lower: diffs.iter().filter(|&&d| d < 0.0).count() as u64,
        b_higher: diffs.iter().filter(|&&d| d > 0.0).count() as u64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_matches_the_textbook_example() {
        // 81 of 263 (Wilson 1927 style example used by many texts): 0.2553..0.3662 at 95 %.
        let i = wilson(81, 263, Z95).unwrap();
        assert!((i.lo - 0.2553).abs() < 1e-3, "{i:?}");
        assert!((i.hi - 0.3662).abs() < 1e-3, "{i:?}");
    }

    #[test]
    fn wilson_stays_inside_the_unit_interval_at_the_edges() {
        let all = wilson(100, 100, Z95).unwrap();
        assert_eq!(all.hi, 1.0);
        assert!(all.lo > 0.95 && all.lo < 0.97, "{all:?}");
        let none = wilson(0, 100, Z95).unwrap();
        assert_eq!(none.lo, 0.0);
        assert!(wilson(1, 0, Z95).is_none() && wilson(3, 2, Z95).is_none());
    }

    #[test]
    fn bootstrap_brackets_the_mean_and_is_seeded() {
        let xs: Vec<f64> = (0..100).map(|i| (i % 17) as f64).collect();
        let m = mean(&xs).unwrap();
        let a = bootstrap_mean(&xs, 2000, 0.05, 7).unwrap();
        assert!(a.lo < m && m < a.hi, "{a:?} around {m}");
        assert_eq!(a, bootstrap_mean(&xs, 2000, 0.05, 7).unwrap());
        assert!(bootstrap_mean(&[], 10, 0.05, 7).is_none());
    }

    #[test]
    fn paired_keeps_only_the_tasks_both_solve() {
        let a = [Some(10.0), None, Some(4.0), Some(6.0)];
        let b = [Some(12.0), Some(1.0), None, Some(7.0)];
        let p = paired(&a, &b, 500, 3);
        assert_eq!(
            (p.n, p.mean_a, p.mean_b, p.mean_diff),
            (2, Some(8.0), Some(9.5), Some(1.5))
        );
        let ci = p.diff_ci.unwrap();
        assert!(
            ci.lo >= 1.0 && ci.hi <= 2.0 && ci.lo <= 1.5 && 1.5 <= ci.hi,
            "{ci:?}"
        );
        assert_eq!(paired(&[None], &[Some(1.0)], 10, 1).n, 0);
        // Differences 2, 1, -1 and 0: median 0.5, one lower, two higher, one tie.
        let c = [Some(1.0), Some(1.0), Some(3.0), Some(5.0)];
        let d = [Some(3.0), Some(2.0), Some(2.0), Some(5.0)];
        let q = paired(&c, &d, 100, 1);
        assert_eq!((q.median_diff, q.b_lower, q.b_higher), (Some(0.5), 1, 2));
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[]), None);
    }
}
