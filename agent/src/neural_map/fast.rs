//! The fast path: `f32` activations with a per-neuron binary exponent, double buffers, a
//! padded grid and a bounding box that grows with the wave.
//!
//! # Underflow, and why the scheme keeps the ascent order
//!
//! Activations fall geometrically with the distance from the target. A neuron at the wave
//! front averages the few neighbours one ring closer, so the front shrinks by about 1/3 per
//! cell along a straight front and by about 1/10 per cell at a diagonal corner of the front
//! (`0.707 / 6.83`). Plain `f32` (smallest normal `2^-126`, about `1e-38`) flushes values to 0
//! some 40 cells from the target, `f64` a few hundred cells away; a zero neuron is "off", the
//! wave stops and the gradient ascent sees a flat plain.
//!
//! Each neuron therefore stores a mantissa `m` in `[1, 2)` (or 0) as `f32` and an exponent `e`
//! as `i32`; its value is `m * 2^e`, a float whose exponent reaches down to `-2^29` (below
//! that it flushes to 0). A build falls by at most about 3.5 binades per cell of link distance
//! with the default weights (`2^-3700` across a 1024 x 1024 map), so no grid that fits in
//! memory comes near the limit (`xfloat.rs` has the bound).
//!
//! * **Update.** `u_i = sum_j w_ij m_j 2^e_j / D_i` is computed as
//!   `2^e_max * (sum_j w_ij m_j 2^(e_j - e_max)) / D_i`, where `e_max` is the largest exponent
//!   among the linked neighbours (and the neuron itself with a self weight). Multiplying by
//!   `2^(e_j - e_max)` is exact in binary floating point; a term more than `2^100` below the
//!   largest one is dropped, which is 76 binades below `f32` rounding of the sum (the largest
//!   term is at least `min(w) * 1`). The sum is then renormalised into `(m, e)`, exactly. So
//!   the map is the sequence of numbers that `f32` arithmetic with an unbounded exponent would
//!   compute; only the order of summation and the `f32` `tanh` fit differ from the reference.
//! * **Activation.** Linear: the identity on `[0, 1]`, saturation tested on the exponent.
//!   tanh: evaluated on the real value when it is at least `2^-13`; below that
//!   `tanh x = x (1 - x^2/3 + ...)` rounds to `x` in `f32`, so the value is kept.
//! * **On-threshold.** "Non-zero" is `m != 0`: exactly "the wave has arrived", however far.
//!   A threshold such as `1e-16` is compared in `(m, e)` form.
//! * **Ascent order.** The path constructor compares `(E_j - E_i) * w_ij` over the current
//!   cell's neighbours. [`ActivationField::local`] returns the nine values of the 3x3 block
//!   multiplied by one common factor `2^-e_ref` (`e_ref` the largest exponent among them),
//!   formed in `f64`. For `c > 0`, `(c E_j - c E_i) w_ij = c (E_j - E_i) w_ij`, so the argmax,
//!   every sign and every comparison are those of the exact values, and a power-of-two factor
//!   is applied exactly. Wherever the plain `f64` dynamics are representable the fast path
//!   therefore sees the same values up to `f32` rounding and makes the same choices (the path
//!   constructor treats gradients within a relative `1e-5` as ties and takes the first
//!   clockwise, so rounding noise cannot flip a choice between two equal gradients); where
//!   they are not, it still follows the exact order.
//!
//! Rejected alternatives: one scale per sweep (the values of one sweep span thousands of
//! binades, from 1 at the target to `1e-1000` at the front of a 1024 x 1024 map); one scale
//! per row or band (one row holds both a straight stretch of the front and its diagonal
//! corner, `3.4^n` apart after `n` cells); a log-domain state (a `log-sum-exp` per neighbour,
//! eight `exp` per update).
//!
//! # Speed
//!
//! Buffers are allocated once in [`NeuralMap::new`] and reused by every build; a build first
//! clears only the rectangle the previous one touched. The grid is padded with one blocked
//! cell on each side, so every interior neuron has eight in-bounds neighbours and the kernel
//! needs no edge cases; `1 / D_i` and the cut-diagonal mask are precomputed per cell. Each
//! sweep covers the bounding box of the non-zero neurons grown by one cell; boxes (nearly) as
//! wide as the grid run as one long segment across the padding. The kernel (`kernel.rs`) is
//! compiled three times, for x86-64's baseline, AVX2 + FMA and AVX-512, and the best the CPU
//! has is picked at run time (`HNAV_SIMD=avx2` or `baseline` caps it, for benchmarks). tanh is
//! evaluated only in blocks of 256 cells that hold a value above `2^-13`, so on large maps
//! tanh costs about what linear does.

use hnav_runtime::grid::{Cell, Direction, Grid};

use super::driver::{self, SweepEngine, SweepStats};
use super::kernel::{self, Flags, Level, Params, Planes, Region};
use super::topology::Topology;
use super::xfloat::{self, ZERO_EXP};
use super::{
    validate_stop, Activation, ActivationField, BuildReport, DiagonalRule, Local, NeuralDynamics,
    NeuralMapOptions, OnThreshold, StopRule,
};
use crate::error::{check_inside, Error, Role};

/// A neural map on the fast path. Create it once per grid and rebuild it for each target.
#[derive(Clone, Debug)]
pub struct NeuralMap {
    topo: Topology,
    options: NeuralMapOptions,
    pw: usize,
    m: [Vec<f32>; 2],
    e: [Vec<i32>; 2],
    cur: usize,
    inv_den: Vec<f32>,
    diag: Vec<u8>,
    params: Params,
    flags: Flags,
    level: Level,
    target: Option<Cell>,
    /// Contains every non-zero neuron of the current buffer.
    support: Region,
    /// The region the pending (uncommitted) sweep wrote.
    pending: Region,
    /// Everything written in either buffer since the last reset.
    dirty: Region,
}

impl NeuralMap {
    /// Allocates the buffers for `grid` and precomputes the per-cell constants.
    pub fn new(grid: &Grid, options: NeuralMapOptions) -> Result<NeuralMap, Error> {
        options.validate()?;
        let topo = Topology::new(grid, options.diagonals);
        let (w, h) = (topo.width as usize, topo.height as usize);
        let pw = w + 2;
        let len = pw * (h + 2);
        let g = options.weights.gain;
        let (thr_m, thr_e) = match options.on_threshold {
            OnThreshold::NonZero => (0.0, ZERO_EXP),
            OnThreshold::Above(t) => xfloat::from_f64(t),
        };
        let mask = options.diagonals != DiagonalRule::Always;
        let mut map = NeuralMap {
            topo,
            options,
            pw,
            m: [vec![0.0; len], vec![0.0; len]],
            e: [vec![ZERO_EXP; len], vec![ZERO_EXP; len]],
            cur: 0,
            inv_den: vec![0.0; len],
            diag: if mask { vec![0; len] } else { Vec::new() },
            params: Params {
                ws: (g * options.weights.straight) as f32,
                wd: (g * options.weights.diagonal) as f32,
                wself: (g * options.weights.self_weight) as f32,
                thr_m,
                thr_e,
            },
            flags: Flags {
                tanh: options.activation == Activation::Tanh,
                mask,
                self_weight: options.weights.self_weight > 0.0,
                delta: false,
            },
            level: Level::detect(),
            target: None,
            support: Region::point(1, 1),
            pending: Region::point(1, 1),
            dirty: Region::point(1, 1),
        };
        for i in 0..map.topo.len() {
            map.refresh(map.topo.cell(i));
        }
        Ok(map)
    }

    /// The memory [`NeuralMap::new`] allocates for `grid`, in bytes: two buffers of mantissas
    /// and exponents, the denominators and the diagonal mask, each one value per cell of the
    /// padded grid. An agent reports it while it builds its map.
    pub fn footprint(grid: &Grid) -> usize {
        let cells = (grid.width() as usize + 2) * (grid.height() as usize + 2);
        let per_cell = 2 * (size_of::<f32>() + size_of::<i32>()) + size_of::<f32>() + 1;
        cells * per_cell
    }

    /// The options the map was created with.
    pub fn options(&self) -> &NeuralMapOptions {
        &self.options
    }

    /// Writes every activation as plain `f32` (row-major, unpadded) into `out`, flushing values
    /// below `f32`'s normal range to 0: what the runtime's neural-map snapshot carries. Fails if
    /// `out` does not have one slot per cell.
    pub fn write_values_f32(&self, out: &mut [f32]) -> Result<(), Error> {
        self.write_with(out, xfloat::to_f32_flushed)
    }

    /// Writes `log2` of every activation (`-inf` for 0) into `out`; never underflows.
    pub fn write_log2_f32(&self, out: &mut [f32]) -> Result<(), Error> {
        self.write_with(out, |m, e| xfloat::log2(m, e) as f32)
    }

    fn write_with(&self, out: &mut [f32], f: impl Fn(f32, i32) -> f32) -> Result<(), Error> {
        if out.len() != self.topo.len() {
            return Err(Error::option(
                "out",
                format!("{} slots for {} cells", out.len(), self.topo.len()),
            ));
        }
        let (m, e) = (&self.m[self.cur], &self.e[self.cur]);
        for (i, o) in out.iter_mut().enumerate() {
            let p = self.padded(self.topo.cell(i));
            *o = f(m[p], e[p]);
        }
        Ok(())
    }

    fn padded(&self, cell: Cell) -> usize {
        (cell.y as usize + 1) * self.pw + cell.x as usize + 1
    }

    fn region_of(&self, cell: Cell) -> Region {
        Region::point(cell.x as usize + 1, cell.y as usize + 1)
    }

    /// Recomputes a cell's `1 / D` and diagonal mask from the topology.
    fn refresh(&mut self, cell: Cell) {
        let p = self.padded(cell);
        let free = !self.topo.is_blocked(cell);
        let den = if free {
            self.topo
                .denominator(cell, &self.options.weights, self.options.denominator)
        } else {
            0.0
        };
        self.inv_den[p] = if den > 0.0 && Some(cell) != self.target {
            (1.0 / den) as f32
        } else {
            0.0
        };
        if self.flags.mask {
            let links = if free { self.topo.links(cell) } else { 0 };
            let bit = |d: Direction, to: u8| ((links >> d.index()) & 1) << to;
            self.diag[p] = bit(Direction::NE, 0)
                | bit(Direction::SE, 1)
                | bit(Direction::SW, 2)
                | bit(Direction::NW, 3);
        }
    }

    fn set(&mut self, buffer: usize, p: usize, m: f32, e: i32) {
        self.m[buffer][p] = m;
        self.e[buffer][p] = e;
    }

    fn check_free(&self, cell: Cell, role: Role) -> Result<(), Error> {
        check_inside(cell, role, self.topo.width, self.topo.height)?;
        if self.topo.is_blocked(cell) {
            return Err(Error::Blocked { role, cell });
        }
        Ok(())
    }

    fn check_stop(&self, stop: &StopRule) -> Result<(), Error> {
        validate_stop(stop)?;
        if let StopRule::PartialActivation { start } = *stop {
            self.check_free(start, Role::Start)?;
        }
        Ok(())
    }

    fn cap(&self) -> u32 {
        self.options.sweep_cap(self.topo.len())
    }

    fn above(&self, m: f32, e: i32) -> bool {
        e > self.params.thr_e || (e == self.params.thr_e && m > self.params.thr_m)
    }
}

impl SweepEngine for NeuralMap {
    fn sweep(&mut self, want_delta: bool) -> SweepStats {
        let (w, h) = (self.topo.width as usize, self.topo.height as usize);
        let region = self.support.grow(w, h);
        let flags = Flags {
            delta: want_delta,
            ..self.flags
        };
        let (src, dst) = if self.cur == 0 { (0, 1) } else { (1, 0) };
        let [m0, m1] = &mut self.m;
        let [e0, e1] = &mut self.e;
        let (m_in, m_out) = if src == 0 { (&*m0, m1) } else { (&*m1, m0) };
        let (e_in, e_out) = if src == 0 { (&*e0, e1) } else { (&*e1, e0) };
        let mut planes = Planes {
            pw: self.pw,
            m_in,
            e_in,
            m_out,
            e_out,
            inv_den: &self.inv_den,
            diag: &self.diag,
        };
        let k = kernel::sweep(self.level, flags, &self.params, &mut planes, region);
        let mut s = SweepStats {
            newly_on: k.newly_on,
            nonzero: k.nonzero,
            above: k.above,
            changed: k.changed,
            max_delta: f64::from(f32::from_bits(k.max_delta_bits)),
            cells: k.cells,
        };
        if let Some(t) = self.target {
            // The kernel computed 0 for the target (its 1/D is 0); clamp it back to 1.
            let p = self.padded(t);
            self.set(dst, p, 1.0, 0);
            s.nonzero += 1;
            s.above += u64::from(self.above(1.0, 0));
        }
        self.pending = region;
        self.dirty = self.dirty.union(region);
        s
    }

    fn commit(&mut self) {
        self.cur ^= 1;
        self.support = self.pending;
    }

    fn counts(&self) -> (u64, u64) {
        let r = self.support;
        let (m, e) = (&self.m[self.cur], &self.e[self.cur]);
        let (mut nonzero, mut above) = (0, 0);
        for y in r.y0..=r.y1 {
            for p in y * self.pw + r.x0..=y * self.pw + r.x1 {
                nonzero += u64::from(m[p] != 0.0);
                above += u64::from(self.above(m[p], e[p]));
            }
        }
        (nonzero, above)
    }

    fn is_above(&self, cell: Cell) -> bool {
        let p = self.padded(cell);
        self.above(self.m[self.cur][p], self.e[self.cur][p])
    }

    fn is_nonzero(&self, cell: Cell) -> bool {
        self.m[self.cur][self.padded(cell)] != 0.0
    }
}

impl ActivationField for NeuralMap {
    fn width(&self) -> u32 {
        self.topo.width
    }

    fn height(&self) -> u32 {
        self.topo.height
    }

    fn is_blocked(&self, cell: Cell) -> bool {
        self.topo.is_blocked(cell)
    }

    fn diagonal_rule(&self) -> DiagonalRule {
        self.topo.rule
    }

    fn target(&self) -> Option<Cell> {
        self.target
    }

    fn local(&self, cell: Cell) -> Local {
        let mut values = [0.0; 9];
        if !self.topo.contains(cell) {
            return Local {
                values,
                log2_scale: 0,
            };
        }
        let (m, e) = (&self.m[self.cur], &self.e[self.cur]);
        let centre = self.padded(cell);
        let pw = self.pw as isize;
        let mut at = [centre; 9];
        for d in Direction::ALL {
            let off = d.dy() as isize * pw + d.dx() as isize;
            // Padding cells exist around every inside cell and hold 0.
            at[d.index()] = centre.wrapping_add_signed(off);
        }
        let e_ref = at
            .iter()
            .filter(|&&p| m[p] != 0.0)
            .map(|&p| e[p])
            .max()
            .unwrap_or(0);
        for (v, &p) in values.iter_mut().zip(&at) {
            // 2^d built from the bits (exact); a value 2^1022 below the block's largest is
            // flushed to 0, which cannot change the argmax of the gradients.
            let d = i64::from(e[p]) - i64::from(e_ref);
            if m[p] != 0.0 && d >= -1022 {
                *v = f64::from(m[p]) * f64::from_bits(((d + 1023) as u64) << 52);
            }
        }
        Local {
            values,
            log2_scale: i64::from(e_ref),
        }
    }

    fn log2_value(&self, cell: Cell) -> f64 {
        if !self.topo.contains(cell) {
            return f64::NEG_INFINITY;
        }
        let p = self.padded(cell);
        xfloat::log2(self.m[self.cur][p], self.e[self.cur][p])
    }
}

impl NeuralDynamics for NeuralMap {
    fn build(&mut self, target: Cell, stop: StopRule) -> Result<BuildReport, Error> {
        self.check_free(target, Role::Target)?;
        self.check_stop(&stop)?;
        // Clear what the previous builds wrote, in both buffers.
        let d = self.dirty;
        for b in 0..2 {
            for y in d.y0..=d.y1 {
                let row = y * self.pw + d.x0..=y * self.pw + d.x1;
                self.m[b][row.clone()].fill(0.0);
                self.e[b][row].fill(ZERO_EXP);
            }
        }
        let old = self.target.replace(target);
        if let Some(old) = old {
            self.refresh(old);
        }
        self.refresh(target);
        let p = self.padded(target);
        self.set(0, p, 1.0, 0);
        self.set(1, p, 1.0, 0);
        self.cur = 0;
        self.support = self.region_of(target);
        self.pending = self.support;
        self.dirty = self.support;
        Ok(driver::run(self, stop, self.cap()))
    }

    fn continue_sweeps(&mut self, stop: StopRule) -> Result<BuildReport, Error> {
        if self.target.is_none() {
            return Err(Error::option(
                "target",
                "build the map before continuing it",
            ));
        }
        self.check_stop(&stop)?;
        Ok(driver::run(self, stop, self.cap()))
    }

    fn add_obstacles(&mut self, cells: &[Cell]) -> Result<(), Error> {
        for &cell in cells {
            check_inside(cell, Role::Obstacle, self.topo.width, self.topo.height)?;
            if Some(cell) == self.target {
                return Err(Error::Blocked {
                    role: Role::Target,
                    cell,
                });
            }
        }
        for &cell in cells {
            let i = self.topo.index(cell);
            self.topo.blocked[i] = true;
            let p = self.padded(cell);
            self.set(0, p, 0.0, ZERO_EXP);
            self.set(1, p, 0.0, ZERO_EXP);
        }
        // A cell's links and denominator depend only on its 3x3 neighbourhood.
        for &cell in cells {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    if let Some(c) = cell.offset(dx, dy).filter(|&c| self.topo.contains(c)) {
                        self.refresh(c);
                    }
                }
            }
        }
        Ok(())
    }
}
