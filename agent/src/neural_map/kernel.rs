//! The fast path's sweep kernel: one synchronous update of a rectangle of the padded grid.
//!
//! Written for the auto-vectoriser: a segment of a row reads three rows of each plane (the
//! padding gives every interior cell eight in-bounds neighbours), the loop body is
//! straight-line arithmetic with selects instead of branches, and the options that change the
//! body (activation, cut diagonals, self weight, convergence deltas) are const generics so that
//! each combination compiles to its own loop. On x86-64 the same body is also compiled with
//! AVX2 + FMA and with AVX-512 and picked at run time.
//!
//! Per neuron: the largest exponent among the linked neighbours, each neighbour's mantissa
//! scaled by `2^(e_j - e_max)` (built from the exponent bits, flushed below `2^-100`), the
//! weighted sum times `1 / D_i`, and the renormalisation into mantissa and exponent; see
//! [`super::fast`] for why this is exact where `f32` is.

use super::xfloat::{pow2, pow2_biased, split, split_biased, tanh, to_f32_flushed, ZERO_EXP};

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
    /// Neuron updates computed (padding cells of merged rows included).
    pub cells: u64,
}

/// Which instruction set the kernel runs with.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Level {
    Baseline,
    #[cfg(target_arch = "x86_64")]
    Avx2,
    #[cfg(target_arch = "x86_64")]
    Avx512,
}

impl Level {
    /// The best level the CPU supports, capped by the environment variable `HNAV_SIMD`
    /// (`baseline`, `avx2`; for benchmarking the kernel variants against each other). Detected
    /// once per process.
    pub fn detect() -> Level {
        static LEVEL: std::sync::OnceLock<Level> = std::sync::OnceLock::new();
        *LEVEL.get_or_init(Self::detect_now)
    }

    fn detect_now() -> Level {
        let cap = std::env::var("HNAV_SIMD").unwrap_or_default();
        if cap == "baseline" {
            return Level::Baseline;
        }
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            let avx512 =
                has!("avx512f") && has!("avx512bw") && has!("avx512vl") && has!("avx512dq");
            if avx512 && cap != "avx2" {
                return Level::Avx512;
            }
            if has!("avx2") && has!("fma") {
                return Level::Avx2;
            }
        }
        Level::Baseline
    }
}

/// Runs one sweep over `r`: reads `*_in`, writes `*_out` inside `r`. When `r` is nearly as wide
/// as the grid the whole rows `y0..=y1` are written; the cells outside `r` have no non-zero
/// neighbour (`r` is the support grown by one) and so receive the 0 they already hold.
pub(crate) fn sweep(level: Level, f: Flags, p: &Params, pl: &mut Planes<'_>, r: Region) -> KStats {
    // Turn the run-time flags into const generics, one at a time.
    if f.tanh {
        sweep_t::<true>(level, f, p, pl, r)
    } else {
        sweep_t::<false>(level, f, p, pl, r)
    }
}

fn sweep_t<const T: bool>(
    level: Level,
    f: Flags,
    p: &Params,
    pl: &mut Planes<'_>,
    r: Region,
) -> KStats {
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
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Level::Avx512` is only constructed by `Level::detect` after the CPU reported
        // AVX-512 F, BW, VL and DQ.
        Level::Avx512 => unsafe { rows_avx512::<T, M, S, D>(p, pl, r) },
        Level::Baseline => rows::<T, M, S, D, false>(p, pl, r),
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn rows_avx2<const T: bool, const M: bool, const S: bool, const D: bool>(
    p: &Params,
    pl: &mut Planes<'_>,
    r: Region,
) -> KStats {
    rows::<T, M, S, D, true>(p, pl, r)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512bw,avx512vl,avx512dq,avx2,fma")]
fn rows_avx512<const T: bool, const M: bool, const S: bool, const D: bool>(
    p: &Params,
    pl: &mut Planes<'_>,
    r: Region,
) -> KStats {
    rows::<T, M, S, D, true>(p, pl, r)
}

#[inline(always)]
fn rows<const T: bool, const M: bool, const S: bool, const D: bool, const FMA: bool>(
    p: &Params,
    pl: &mut Planes<'_>,
    r: Region,
) -> KStats {
    let n = r.x1 - r.x0 + 1;
    let w = pl.pw - 2;
    let mut st = KStats::default();
    if w - n <= 64 {
        // (Nearly) full width: run the rows as one segment from (1, y0) to (w, y1). The
        // padding cells in between compute 0 (their 1/D is 0), so nothing changes but the
        // loop has no short row ends, which cost more than the few extra cells.
        let base = r.y0 * pl.pw + 1;
        row::<T, M, S, D, FMA>(p, pl, base, (r.y1 - r.y0) * pl.pw + w, &mut st);
    } else {
        for y in r.y0..=r.y1 {
            row::<T, M, S, D, FMA>(p, pl, y * pl.pw + r.x0, n, &mut st);
        }
    }
    st
}

/// `a * b + c`, fused when the instruction set has FMA (a libm call otherwise, hence the flag).
#[inline(always)]
fn fmadd<const FMA: bool>(a: f32, b: f32, c: f32) -> f32 {
    if FMA {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

/// Cells per block. The activation and the counts run block by block after the sums, so
/// that tanh is skipped for blocks far from the target (most of a big map).
const BLOCK: usize = 256;

/// One segment of `n` consecutive padded cells starting at index `base`, block by block.
#[inline(always)]
fn row<const TANH: bool, const MASK: bool, const SELF: bool, const DELTA: bool, const FMA: bool>(
    p: &Params,
    pl: &mut Planes<'_>,
    base: usize,
    n: usize,
    st: &mut KStats,
) {
    let mut b = 0;
    while b < n {
        let len = BLOCK.min(n - b);
        block::<TANH, MASK, SELF, DELTA, FMA>(p, pl, base + b, len, st);
        b += len;
    }
    st.cells += n as u64;
}

/// One block of at most [`BLOCK`] cells: pass 1 computes the weighted averages, pass 2 applies
/// tanh where it is not the identity, pass 3 counts what needs the final values.
#[inline(always)]
fn block<
    const TANH: bool,
    const MASK: bool,
    const SELF: bool,
    const DELTA: bool,
    const FMA: bool,
>(
    p: &Params,
    pl: &mut Planes<'_>,
    base: usize,
    n: usize,
    st: &mut KStats,
) {
    let pw = pl.pw;
    let (up, dn) = (base - pw, base + pw);
    let (m, e) = (pl.m_in, pl.e_in);
    // Three rows of n + 2 cells per plane (fewer live pointers than nine slices, which
    // matters for the unoptimised test builds); index i is the west neighbour of cell i.
    let (mu, mm, md) = (
        &m[up - 1..][..n + 2],
        &m[base - 1..][..n + 2],
        &m[dn - 1..][..n + 2],
    );
    let (eu, em, ed) = (
        &e[up - 1..][..n + 2],
        &e[base - 1..][..n + 2],
        &e[dn - 1..][..n + 2],
    );
    let inv = &pl.inv_den[base..][..n];
    let diag: &[u8] = if MASK { &pl.diag[base..][..n] } else { &[] };
    let out_m = &mut pl.m_out[base..][..n];
    let out_e = &mut pl.e_out[base..][..n];
    let (ws, wd, wself) = (p.ws, p.wd, p.wself);
    let (mut newly_on, mut nonzero) = (0u32, 0u32);
    let mut top = i32::MIN;
    // Pass 1: the weighted averages (and linear saturation). Integer arithmetic here cannot
    // overflow (exponents stay within +-2^28); `wrapping_*` only spares the unoptimised test
    // builds their overflow checks.
    for i in 0..n {
        // A cut diagonal carries nothing and must not set the common exponent.
        let link = |bit: u8, mv: f32, ev: i32| -> (f32, i32) {
            if !MASK || diag[i] & bit != 0 {
                (mv, ev)
            } else {
                (0.0, ZERO_EXP)
            }
        };
        let (m_n, e_n, m_s, e_s) = (mu[i + 1], eu[i + 1], md[i + 1], ed[i + 1]);
        let (m_w, e_w, m_e, e_e) = (mm[i], em[i], mm[i + 2], em[i + 2]);
        let (mne, ene) = link(1, mu[i + 2], eu[i + 2]);
        let (mse, ese) = link(2, md[i + 2], ed[i + 2]);
        let (msw, esw) = link(4, md[i], ed[i]);
        let (mnw, enw) = link(8, mu[i], eu[i]);
        let (mc, ec) = (mm[i + 1], em[i + 1]);
        // Common exponent: the largest neighbour's. Every term is then <= 2 and the sum
        // cannot overflow; terms 2^100 below the largest are flushed (see xfloat::FLUSH).
        let mut emax = e_n.max(e_e).max(e_s).max(e_w);
        emax = emax.max(ene).max(ese).max(esw).max(enw);
        if SELF {
            emax = emax.max(ec);
        }
        // One subtraction folds the exponent bias into the reference (see pow2_biased).
        let eb = emax.wrapping_sub(127);
        let term = |mv: f32, ev: i32| (mv, pow2_biased(ev.wrapping_sub(eb)));
        let [(a, pa), (b, pb), (c, pc), (d, pd)] = [
            term(m_n, e_n),
            term(m_e, e_e),
            term(m_s, e_s),
            term(m_w, e_w),
        ];
        let straight = fmadd::<FMA>(a, pa, fmadd::<FMA>(b, pb, fmadd::<FMA>(c, pc, d * pd)));
        let [(a, pa), (b, pb), (c, pc), (d, pd)] = [
            term(mne, ene),
            term(mse, ese),
            term(msw, esw),
            term(mnw, enw),
        ];
        let diagonal = fmadd::<FMA>(a, pa, fmadd::<FMA>(b, pb, fmadd::<FMA>(c, pc, d * pd)));
        let mut acc = fmadd::<FMA>(ws, straight, wd * diagonal);
        if SELF {
            acc = fmadd::<FMA>(wself * mc, pow2_biased(ec.wrapping_sub(eb)), acc);
        }
        let (mut nm, mut ne) = split_biased(acc * inv[i], eb);
        if !TANH {
            // Linear saturation: the average of values <= 1 is <= 1 up to rounding.
            let sat = ne >= 0;
            nm = if sat { 1.0 } else { nm };
            ne = if sat { 0 } else { ne };
        }
        out_m[i] = nm;
        out_e[i] = ne;
        top = top.max(ne);
        // phi keeps 0 at 0 and positive values positive: these counts hold after tanh too.
        newly_on = newly_on.wrapping_add(u32::from((mc == 0.0) & (nm != 0.0)));
        nonzero = nonzero.wrapping_add(u32::from(nm != 0.0));
    }
    // Pass 2: tanh(x) rounds to x in f32 below 2^-13, so only blocks near the target need it.
    if TANH && top >= -13 {
        for (om, oe) in out_m.iter_mut().zip(out_e.iter_mut()) {
            let x = *om * pow2((*oe).clamp(-13, 1));
            let (tm, te) = split(tanh(x), 0);
            let big = *oe >= -13;
            *om = if big { tm } else { *om };
            *oe = if big { te } else { *oe };
        }
    }
    st.newly_on += u64::from(newly_on);
    st.nonzero += u64::from(nonzero);
    // Pass 3: counts that need the final values.
    if p.thr_e == ZERO_EXP && !DELTA {
        st.above += u64::from(nonzero);
        return;
    }
    let (mut above, mut changed, mut max_delta) = (0u32, 0u32, 0u32);
    for i in 0..n {
        let (nm, ne) = (out_m[i], out_e[i]);
        above += u32::from((ne > p.thr_e) | ((ne == p.thr_e) & (nm > p.thr_m)));
        if DELTA {
            let (mc, ec) = (mm[i + 1], em[i + 1]);
            let active = inv[i] > 0.0;
            changed += u32::from(active & ((nm != mc) | (ne != ec)));
            let dv = (to_f32_flushed(nm, ne) - to_f32_flushed(mc, ec)).abs();
            let dv = if active { dv.to_bits() } else { 0 };
            max_delta = max_delta.max(dv);
        }
    }
    st.above += u64::from(above);
    st.changed += u64::from(changed);
    st.max_delta_bits = st.max_delta_bits.max(max_delta);
}
