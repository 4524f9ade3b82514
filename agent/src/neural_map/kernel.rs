//! The fast path's sweep kernel: one synchronous update of a rectangle of the padded grid.
//!
//! Written for the auto-vectoriser: each row is nine equal-length slices (the cell and its
//! eight neighbours, which exist for every interior cell thanks to the 1-cell padding), the
//! loop body is straight-line arithmetic with selects instead of branches, and the options
//! that change the body (activation, cut diagonals, self weight, convergence deltas) are
//! const generics so that each combination compiles to its own loop. On x86-64 the same body
//! is also compiled with AVX2 + FMA and picked at run time when the CPU has them.

use super::xfloat::{pow2, pow2_rel, split, tanh, to_f32_flushed, ZERO_EXP};

/// Loop-invariant numbers of a sweep.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Params {
    /// Straight link weight (gain applied).
    pub ws: f32,
    /// Diagonal link weight (gain applied).
    pub wd: f32,
    /// Self weight (gain applied).
    pub wself: f32,
    /// On-threshold as mantissa and exponent (`(0, ZERO_EXP)` for "non-zero").
    pub thr_m: f32,
    /// See `thr_m`.
    pub thr_e: i32,
}

/// Which loop body to run.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Flags {
    pub tanh: bool,
    pub mask: bool,
    pub self_weight: bool,
    pub delta: bool,
}

/// Source and destination planes plus the per-cell constants, all padded, row-major.
pub(crate) struct Planes<'a> {
    pub pw: usize,
    pub m_in: &'a [f32],
    pub e_in: &'a [i32],
    pub m_out: &'a mut [f32],
    pub e_out: &'a mut [i32],
    /// `1 / D_i`, 0 for obstacles, padding, isolated cells and the target.
    pub inv_den: &'a [f32],
    /// Bits 0..4: the NE, SE, SW, NW links exist (only read when `Flags::mask`).
    pub diag: &'a [u8],
}

/// A rectangle of padded coordinates, inclusive, inside `1..=width` x `1..=height`.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) struct Region {
    pub x0: usize,
    pub x1: usize,
    pub y0: usize,
    pub y1: usize,
}

impl Region {
    pub fn point(x: usize, y: usize) -> Region {
        Region {
            x0: x,
            x1: x,
            y0: y,
            y1: y,
        }
    }

    /// Grown by one cell on every side, clipped to the interior of a `w x h` grid.
    pub fn grow(self, w: usize, h: usize) -> Region {
        Region {
            x0: (self.x0 - 1).max(1),
            x1: (self.x1 + 1).min(w),
            y0: (self.y0 - 1).max(1),
            y1: (self.y1 + 1).min(h),
        }
    }

    pub fn union(self, o: Region) -> Region {
        Region {
            x0: self.x0.min(o.x0),
            x1: self.x1.max(o.x1),
            y0: self.y0.min(o.y0),
            y1: self.y1.max(o.y1),
        }
    }

    pub fn cells(self) -> u64 {
        ((self.x1 - self.x0 + 1) * (self.y1 - self.y0 + 1)) as u64
    }
}

/// Counts over a sweep (target not yet corrected for; see `fast.rs`).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct KStats {
    pub newly_on: u64,
    pub nonzero: u64,
    pub above: u64,
    pub changed: u64,
    /// Bits of the largest `|delta|` (non-negative floats order like their bits).
    pub max_delta_bits: u32,
}

/// Which instruction set the kernel runs with.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Level {
    Baseline,
    #[cfg(target_arch = "x86_64")]
    Avx2,
}

impl Level {
    pub fn detect() -> Level {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            return Level::Avx2;
        }
        Level::Baseline
    }
}

/// Runs one sweep over `r`: reads `*_in`, writes `*_out` inside `r` only.
pub(crate) fn sweep(level: Level, f: Flags, p: &Params, pl: &mut Planes<'_>, r: Region) -> KStats {
    // Turn the run-time flags into const generics, one at a time.
    if f.tanh {
        sweep_t::<true>(level, f, p, pl, r)
    } else {
        sweep_t::<false>(level, f, p, pl, r)
    }
}

fn sweep_t<const T: bool>(level: Level, f: Flags, p: &Params, pl: &mut Planes<'_>, r: Region) -> KStats {
    if f.mask {
        sweep_tm::<T, true>(level, f, p, pl, r)
    } else {
        sweep_tm::<T, false>(level, f, p, pl, r)
    }
}

fn sweep_tm<const T: bool, const M: bool>(
    level: Level,
    f: Flags,
    p: &Params,
    pl: &mut Planes<'_>,
    r: Region,
) -> KStats {
    if f.self_weight {
        sweep_tms::<T, M, true>(level, f, p, pl, r)
    } else {
        sweep_tms::<T, M, false>(level, f, p, pl, r)
    }
}

fn sweep_tms<const T: bool, const M: bool, const S: bool>(
    level: Level,
    f: Flags,
    p: &Params,
    pl: &mut Planes<'_>,
    r: Region,
) -> KStats {
    if f.delta {
        dispatch::<T, M, S, true>(level, p, pl, r)
    } else {
        dispatch::<T, M, S, false>(level, p, pl, r)
    }
}

fn dispatch<const T: bool, const M: bool, const S: bool, const D: bool>(
    level: Level,
    p: &Params,
    pl: &mut Planes<'_>,
    r: Region,
) -> KStats {
    match level {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Level::Avx2` is only constructed by `Level::detect` after the CPU reported
        // both AVX2 and FMA.
        Level::Avx2 => unsafe { rows_avx2::<T, M, S, D>(p, pl, r) },
        Level::Baseline => rows::<T, M, S, D>(p, pl, r),
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn rows_avx2<const T: bool, const M: bool, const S: bool, const D: bool>(
    p: &Params,
    pl: &mut Planes<'_>,
    r: Region,
) -> KStats {
    rows::<T, M, S, D>(p, pl, r)
}

#[inline(always)]
fn rows<const T: bool, const M: bool, const S: bool, const D: bool>(
    p: &Params,
    pl: &mut Planes<'_>,
    r: Region,
) -> KStats {
    let n = r.x1 - r.x0 + 1;
    let mut st = KStats::default();
    for y in r.y0..=r.y1 {
        let base = y * pl.pw + r.x0;
        row::<T, M, S, D>(p, pl, base, n, &mut st);
    }
    st
}

/// One row segment of `n` cells starting at padded index `base`.
#[inline(always)]
fn row<const TANH: bool, const MASK: bool, const SELF: bool, const DELTA: bool>(
    p: &Params,
    pl: &mut Planes<'_>,
    base: usize,
    n: usize,
    st: &mut KStats,
) {
    let pw = pl.pw;
    let (up, dn) = (base - pw, base + pw);
    let (m, e) = (pl.m_in, pl.e_in);
    // Nine slices of length n: the compiler then proves every index below in bounds.
    let (m_nw, m_n, m_ne) = (&m[up - 1..][..n], &m[up..][..n], &m[up + 1..][..n]);
    let (m_w, m_c, m_e) = (&m[base - 1..][..n], &m[base..][..n], &m[base + 1..][..n]);
    let (m_sw, m_s, m_se) = (&m[dn - 1..][..n], &m[dn..][..n], &m[dn + 1..][..n]);
    let (e_nw, e_n, e_ne) = (&e[up - 1..][..n], &e[up..][..n], &e[up + 1..][..n]);
    let (e_w, e_c, e_e) = (&e[base - 1..][..n], &e[base..][..n], &e[base + 1..][..n]);
    let (e_sw, e_s, e_se) = (&e[dn - 1..][..n], &e[dn..][..n], &e[dn + 1..][..n]);
    let inv = &pl.inv_den[base..][..n];
    let diag: &[u8] = if MASK { &pl.diag[base..][..n] } else { &[] };
    let out_m = &mut pl.m_out[base..][..n];
    let out_e = &mut pl.e_out[base..][..n];
    let (ws, wd, wself) = (p.ws, p.wd, p.wself);
    let (mut newly_on, mut nonzero, mut above, mut changed) = (0u32, 0u32, 0u32, 0u32);
    let mut max_delta = 0u32;
    for i in 0..n {
        // A cut diagonal carries nothing and must not set the common exponent.
        let link = |bit: u8, mv: f32, ev: i32| -> (f32, i32) {
            if !MASK || diag[i] & bit != 0 {
                (mv, ev)
            } else {
                (0.0, ZERO_EXP)
            }
        };
        let (mne, ene) = link(1, m_ne[i], e_ne[i]);
        let (mse, ese) = link(2, m_se[i], e_se[i]);
        let (msw, esw) = link(4, m_sw[i], e_sw[i]);
        let (mnw, enw) = link(8, m_nw[i], e_nw[i]);
        let (mc, ec) = (m_c[i], e_c[i]);
        // Common exponent: the largest neighbour's. Every term is then <= 2 and the sum
        // cannot overflow; terms 2^100 below the largest are flushed (see xfloat::FLUSH).
        let mut emax = e_n[i].max(e_e[i]).max(e_s[i]).max(e_w[i]);
        emax = emax.max(ene).max(ese).max(esw).max(enw);
        if SELF {
            emax = emax.max(ec);
        }
        let straight = m_n[i] * pow2_rel(e_n[i] - emax)
            + m_e[i] * pow2_rel(e_e[i] - emax)
            + m_s[i] * pow2_rel(e_s[i] - emax)
            + m_w[i] * pow2_rel(e_w[i] - emax);
        let diagonal = mne * pow2_rel(ene - emax)
            + mse * pow2_rel(ese - emax)
            + msw * pow2_rel(esw - emax)
            + mnw * pow2_rel(enw - emax);
        let mut acc = ws * straight + wd * diagonal;
        if SELF {
            acc += wself * mc * pow2_rel(ec - emax);
        }
        let (mut nm, mut ne) = split(acc * inv[i], emax);
        if TANH {
            // tanh(x) rounds to x in f32 below 2^-13, so only larger values need it.
            let x = nm * pow2(ne.clamp(-13, 1));
            let (tm, te) = split(tanh(x), 0);
            let big = ne >= -13;
            nm = if big { tm } else { nm };
            ne = if big { te } else { ne };
        } else {
            // Linear saturation: the average of values <= 1 is <= 1 up to rounding.
            let sat = ne >= 0;
            nm = if sat { 1.0 } else { nm };
            ne = if sat { 0 } else { ne };
        }
        out_m[i] = nm;
        out_e[i] = ne;
        newly_on += u32::from((mc == 0.0) & (nm != 0.0));
        nonzero += u32::from(nm != 0.0);
        above += u32::from((ne > p.thr_e) | ((ne == p.thr_e) & (nm > p.thr_m)));
        if DELTA {
            let active = inv[i] > 0.0;
            changed += u32::from(active & ((nm != mc) | (ne != ec)));
            let dv = (to_f32_flushed(nm, ne) - to_f32_flushed(mc, ec)).abs();
            let dv = if active { dv.to_bits() } else { 0 };
            max_delta = max_delta.max(dv);
        }
    }
    st.newly_on += u64::from(newly_on);
    st.nonzero += u64::from(nonzero);
    st.above += u64::from(above);
    st.changed += u64::from(changed);
    st.max_delta_bits = st.max_delta_bits.max(max_delta);
}
