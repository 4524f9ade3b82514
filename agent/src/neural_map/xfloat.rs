//! The fast path's number format: an `f32` mantissa in `[1, 2)` (or 0) and an `i32` binary
//! exponent, value `m * 2^e`. See [`super::fast`] for why. All helpers are branch-free
//! (selects) so that the sweep kernel that inlines them vectorises.

/// The exponent stored with a zero mantissa: below every real exponent (see [`MIN_EXP`]) and
/// far enough from `i32::MIN` that `e - e_max` never overflows.
pub(crate) const ZERO_EXP: i32 = -(1 << 30);

/// Values below `2^MIN_EXP` are flushed to 0, so that real exponents stay above [`ZERO_EXP`]
/// even if a region cut off by a repair decays for millions of sweeps. A build from zero does
/// not get near it: values only grow after the wave arrives, and an arrival value is at least
/// `min(w) / D` of a neighbour's, under 6.3 binades per cell of link distance for weights
/// within a factor 10 of each other (every published variant: 3.5 with the defaults). On the
/// largest grid (`2^26` cells) that stays above `-2^26 * 6.3 > -2^29`.
pub(crate) const MIN_EXP: i32 = -(1 << 29);

/// Contributions more than `2^-FLUSH` times smaller than the largest neighbour's are dropped.
/// They are below `f32` rounding (`2^-24`) by 76 binades, so dropping them changes nothing
/// that `f32` arithmetic could have represented.
pub(crate) const FLUSH: i32 = 100;

/// `2^k` for `k` in `[-126, 127]`, built from the bits (exact).
#[inline(always)]
pub(crate) fn pow2(k: i32) -> f32 {
    f32::from_bits(((k + 127) as u32) << 23)
}

/// `2^(b - 127)` for a biased exponent `b <= 127`, flushed to `2^-FLUSH` below that (the
/// mantissa it multiplies is then dropped relative to the largest term anyway). Biased, so
/// that the kernel folds the bias into one subtraction per cell instead of one per term.
#[inline(always)]
pub(crate) fn pow2_biased(b: i32) -> f32 {
    f32::from_bits((b.max(127 - FLUSH) as u32).wrapping_shl(23))
}

/// Splits a non-negative normal `f32` (or 0) times `2^(b_base - 127)` into mantissa and
/// exponent (the bias-folded form of [`split`]).
#[inline(always)]
pub(crate) fn split_biased(u: f32, b_base: i32) -> (f32, i32) {
    let bits = u.to_bits();
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    let e = b_base.wrapping_add((bits >> 23) as i32);
    if (bits == 0) | (e < MIN_EXP) {
        (0.0, ZERO_EXP)
    } else {
        (m, e)
    }
}

/// Splits a non-negative normal `f32` (or 0) times `2^e_base` into mantissa and exponent.
#[inline(always)]
pub(crate) fn split(u: f32, e_base: i32) -> (f32, i32) {
    split_biased(u, e_base.wrapping_sub(127))
}

/// The value as `f32` when it is a normal `f32`, else 0 (used for convergence deltas).
#[inline(always)]
pub(crate) fn to_f32_flushed(m: f32, e: i32) -> f32 {
    if e >= -126 {
        m * pow2(e.min(127))
    } else {
        0.0
    }
}

/// `log2` of the value (`-inf` for 0).
pub(crate) fn log2(m: f32, e: i32) -> f64 {
    if m == 0.0 {
        f64::NEG_INFINITY
    } else {
        f64::from(e) + f64::from(m).log2()
    }
}

/// An `f64` threshold in `(0, 1)` as mantissa and exponent (0 maps to the zero encoding).
pub(crate) fn from_f64(v: f64) -> (f32, i32) {
    if v <= 0.0 {
        return (0.0, ZERO_EXP);
    }
    let e = v.log2().floor() as i32;
    let mut m = (v / f64::from(e).exp2()) as f32;
    let mut e = e;
    // Guard against log2 rounding putting m just outside [1, 2).
    if m >= 2.0 {
        m /= 2.0;
        e += 1;
    } else if m < 1.0 {
        m *= 2.0;
        e -= 1;
    }
    (m, e)
}

/// `tanh` in `f32` for `x >= 0`: a (13, 6) rational minimax fit (the one Eigen uses), at most
/// about 3e-7 relative error on `[1e-5, 9]`, with no branches so that it vectorises.
#[inline(always)]
pub(crate) fn tanh(x: f32) -> f32 {
    let x = x.min(7.905_311);
    let x2 = x * x;
    let mut p = -2.760_768_5e-16_f32;
    p = p * x2 + 2.000_188e-13;
    p = p * x2 - 8.604_672e-11;
    p = p * x2 + 5.122_297e-8;
    p = p * x2 + 1.485_722_4e-5;
    p = p * x2 + 6.372_619_3e-4;
    p = p * x2 + 4.893_524_6e-3;
    let mut q = 1.198_258_4e-6_f32;
    q = q * x2 + 1.185_347_1e-4;
    q = q * x2 + 2.268_434_6e-3;
    q = q * x2 + 4.893_525e-3;
    (p * x) / q
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_and_log2_round_trip() {
        for v in [1.0f32, 0.75, 3.0e-5, 1.0e-30, 0.3] {
            let (m, e) = split(v, 0);
            assert!((1.0..2.0).contains(&m), "{v} {m}");
            assert_eq!(m * pow2(e), v);
            assert!((log2(m, e) - f64::from(v).log2()).abs() < 1e-12);
        }
        let (m, e) = split(1.5, -1000);
        assert_eq!((m, e), (1.5, -1000));
        assert_eq!(split(0.0, 7), (0.0, ZERO_EXP));
        assert_eq!(log2(0.0, ZERO_EXP), f64::NEG_INFINITY);
    }

    #[test]
    fn thresholds_encode() {
        let (m, e) = from_f64(1e-16);
        assert!((1.0..2.0).contains(&m));
        assert!((f64::from(m) * f64::from(e).exp2() / 1e-16 - 1.0).abs() < 1e-7);
        assert_eq!(from_f64(0.5), (1.0, -1));
        assert_eq!(from_f64(0.0), (0.0, ZERO_EXP));
    }

    #[test]
    fn tanh_is_accurate() {
        let mut x = 1e-5f64;
        while x < 8.0 {
            let got = f64::from(tanh(x as f32));
            let want = f64::from(x as f32).tanh();
            assert!(((got - want) / want).abs() < 5e-7, "x {x}: {got} vs {want}");
            x *= 1.001;
        }
        assert!(tanh(100.0) <= 1.0);
    }
}
