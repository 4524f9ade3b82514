//! The swarm and its particle update: Pseudocode 1 of the notes (§2.2) with the discrete-grid
//! forms (8)-(9), the noise (20), the speed limit (3) and, for the modified algorithm, the
//! adaptive weights of [`super::weights`] and the exit of [`super::minimum`].
//!
//! All buffers live in [`Swarm`] and are reused from run to run: an iteration allocates
//! nothing (the trajectories are reserved to `k_max + 1` at reset).

use hnav_runtime::grid::Grid;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::field::{chebyshev, Field};
use super::minimum::{self, Detector, MinimumCounts};
use super::options::{
    Alternative, BestReset, Escape, NoiseForm, NoiseWhen, PsoOptions, Relocate, Rounding, Variant,
    WeightLaw,
};
use super::weights::{self, Weights};

/// One particle: integer position and velocity, its personal best and its weights.
#[derive(Clone, Debug)]
pub struct Particle {
    /// x_i.
    pub pos: [i64; 2],
    /// v_i, each component in [-v_max, v_max].
    pub vel: [i64; 2],
    /// x^L_i, the best cell it has reached.
    pub best: [i64; 2],
    /// J(x^L_i).
    pub best_j: f64,
    /// k^L_ij, k^G_ij per coordinate.
    pub weights: [Weights; 2],
    /// Every cell it stood on, in order (its trace).
    pub trajectory: Vec<[i64; 2]>,
}

/// The objective (4): Euclidean distance to the goal.
pub fn objective(p: [i64; 2], goal: [i64; 2]) -> f64 {
    let dx = (p[0] - goal[0]) as f64;
    let dy = (p[1] - goal[1]) as f64;
    (dx * dx + dy * dy).sqrt()
}

/// Noise (20) for the uniform draw `u` in [0, 1]: [`NoiseForm::Symmetric`] is
/// `round(-r_max + 2 r_max u)` (halves away from zero), [`NoiseForm::Uniform`] the integer
/// `floor(u (2 r_max + 1)) - r_max`.
pub fn noise(form: NoiseForm, r_max: i32, u: f64) -> i64 {
    let r = f64::from(r_max);
    let v = match form {
        NoiseForm::Symmetric => (-r + 2.0 * r * u).round(),
        NoiseForm::Uniform => (u * (2.0 * r + 1.0)).floor().min(2.0 * r) - r,
    };
    v as i64
}

/// A velocity component after rounding and the clamp (3).
pub fn saturate(v: f64, rounding: Rounding, v_max: i32) -> i64 {
    let whole = match rounding {
        Rounding::Nearest => v.round(),
        Rounding::Truncate => v.trunc(),
    };
    whole.clamp(-f64::from(v_max), f64::from(v_max)) as i64
}

/// The whole swarm's state for one run.
#[derive(Clone, Debug, Default)]
pub struct Swarm {
    /// The particles.
    pub particles: Vec<Particle>,
    /// x^G.
    pub best: [i64; 2],
    /// J(x^G).
    pub best_j: f64,
    /// The goal.
    pub goal: [i64; 2],
    /// Virtual obstacles and sensing.
    pub field: Field,
    /// d_lm.
    pub detector: Detector,
    /// What the local-minimum handling did this run.
    pub minima: MinimumCounts,
    positions: Vec<[i64; 2]>,
}

impl Swarm {
    /// Sets up Pseudocode 1 steps 1-2: particle 1 on `start`, the others on its 8 neighbours
    /// (3 x 3 block, §2.6); one whose cell is blocked starts on `start`. Zero velocity \[A\].
    pub fn reset(&mut self, grid: &Grid, start: [i64; 2], goal: [i64; 2], o: &PsoOptions) {
        const BLOCK: [[i64; 2]; 9] = [
            [0, 0],
            [-1, -1],
            [0, -1],
            [1, -1],
            [-1, 0],
            [1, 0],
            [-1, 1],
            [0, 1],
            [1, 1],
        ];
        self.field.reset(grid);
        self.goal = goal;
        self.detector = Detector::default();
        self.minima = MinimumCounts::default();
        self.particles.truncate(o.particles);
        for i in 0..o.particles {
            let d = BLOCK[i % BLOCK.len()];
            let mut pos = [start[0] + d[0], start[1] + d[1]];
            if !self.field.free(grid, pos) {
                pos = start;
            }
            let p = Particle {
                pos,
                vel: [0, 0],
                best: pos,
                best_j: objective(pos, goal),
                weights: [Weights::new(o.k_initial); 2],
                trajectory: Vec::new(),
            };
            match self.particles.get_mut(i) {
                Some(slot) => {
                    let mut trajectory = std::mem::take(&mut slot.trajectory);
                    trajectory.clear();
                    *slot = Particle { trajectory, ..p };
                }
                None => self.particles.push(p),
            }
            let t = &mut self.particles[i].trajectory;
            t.reserve(o.k_max as usize + 1);
            t.push(pos);
        }
        self.best_j = f64::INFINITY;
        self.update_global();
    }

    /// x^G = the best personal best (strictly smaller J wins, ties keep the lower index);
    /// true if it moved.
    fn update_global(&mut self) -> bool {
        let mut best = (f64::INFINITY, self.best);
        for p in &self.particles {
            if p.best_j < best.0 {
                best = (p.best_j, p.best);
            }
        }
        let changed = best.0 < self.best_j;
        if changed {
            (self.best_j, self.best) = best;
        }
        changed
    }

    /// One iteration (Pseudocode 1 steps 3.1-3.5); returns the index of a particle whose J is
    /// below ε after it, if any (stopping rule (6)).
    pub fn step(&mut self, grid: &Grid, o: &PsoOptions, rng: &mut ChaCha8Rng) -> Option<usize> {
        for i in 0..self.particles.len() {
            let vel = self.velocity(i, o, rng);
            let p = &mut self.particles[i];
            p.vel = vel;
            let target = self.move_target(grid, i, o, rng);
            let p = &mut self.particles[i];
            p.pos = target;
            p.trajectory.push(target);
            let j = objective(target, self.goal);
            if j < p.best_j {
                p.best_j = j;
                p.best = target;
            }
        }
        let changed = self.update_global();
        if o.escape != Escape::Off && self.detector.observe(changed, o.n_lm) {
            if self.detector.count == o.n_lm + 1 {
                self.minima.detections += 1;
            }
            if o.escape == Escape::VirtualObstacles {
                self.exit_minimum(grid, o, rng);
            }
        }
        self.particles
            .iter()
            .position(|p| objective(p.pos, self.goal) < o.epsilon)
    }

    /// Velocity (2) ([`WeightLaw::Fixed`]) or (9) ([`WeightLaw::Adaptive`], after the weight
    /// update), rounded and clamped.
    fn velocity(&mut self, i: usize, o: &PsoOptions, rng: &mut ChaCha8Rng) -> [i64; 2] {
        let (goal, gbest) = (self.goal, self.best);
        let p = &mut self.particles[i];
        let mut out = [0; 2];
        for j in 0..2 {
            let to_local = (p.best[j] - p.pos[j]) as f64;
            let to_global = (gbest[j] - p.pos[j]) as f64;
            let inertia = o.inertia * p.vel[j] as f64;
            let v = match o.weight_law {
                WeightLaw::Fixed => {
                    // (5): r2 = 1 - r1, with k1 = k2 = k_initial fixed.
                    let r1: f64 = rng.gen();
                    inertia
                        + o.k_initial * r1 * to_local
                        + (1.0 - o.k_initial) * (1.0 - r1) * to_global
                }
                WeightLaw::Adaptive => {
                    let b_local = (p.best[j] - goal[j]).abs() as f64;
                    let b_global = (gbest[j] - goal[j]).abs() as f64;
                    let eta = weights::eta(o.eta_min, o.eta_max, rng.gen());
                    p.weights[j].update(b_local, b_global, eta);
                    let w = p.weights[j];
                    inertia + w.local * to_local + w.global * to_global
                }
            };
            out[j] = saturate(v, o.rounding, o.v_max);
        }
        out
    }

    fn draw_noise(o: &PsoOptions, rng: &mut ChaCha8Rng) -> [i64; 2] {
        match o.variant {
            // [P]: -1, 0 or +1 with equal probability.
            Variant::Modified => [rng.gen_range(-1..=1), rng.gen_range(-1..=1)],
            Variant::Original => {
                let r = o.noise_amplitude();
                [
                    noise(o.noise_form, r, rng.gen()),
                    noise(o.noise_form, r, rng.gen()),
                ]
            }
        }
    }

    /// Step 3.3 with the noise rule of §2.3: the intended cell if free, else one random
    /// alternative, else stay.
    fn move_target(&self, grid: &Grid, i: usize, o: &PsoOptions, rng: &mut ChaCha8Rng) -> [i64; 2] {
        let p = &self.particles[i];
        let always = o.variant == Variant::Original && o.noise_when == NoiseWhen::Always;
        let r0 = if always {
            Self::draw_noise(o, rng)
        } else {
            [0, 0]
        };
        let intended = [p.pos[0] + p.vel[0] + r0[0], p.pos[1] + p.vel[1] + r0[1]];
        if self.field.free(grid, intended) {
            return intended;
        }
        let r = Self::draw_noise(o, rng);
        let v_max = i64::from(o.v_max);
        let alt = match o.alternative {
            Alternative::Noise => [p.pos[0] + r[0], p.pos[1] + r[1]],
            Alternative::ClampedSum => [
                p.pos[0] + (p.vel[0] + r[0]).clamp(-v_max, v_max),
                p.pos[1] + (p.vel[1] + r[1]).clamp(-v_max, v_max),
            ],
            Alternative::Sum => [p.pos[0] + p.vel[0] + r[0], p.pos[1] + p.vel[1] + r[1]],
        };
        if self.field.free(grid, alt) {
            alt
        } else {
            p.pos
        }
    }

    /// Pseudocode 2 step 2 with the 24-cell analysis: maybe place virtual obstacles at x^G,
    /// displace the particles there, reset the bests that became blocked, recompute x^G.
    fn exit_minimum(&mut self, grid: &Grid, o: &PsoOptions, rng: &mut ChaCha8Rng) {
        let m = self.best;
        self.minima.checks += 1;
        self.positions.clear();
        self.positions.extend(self.particles.iter().map(|p| p.pos));
        let radius = i64::from(o.sensing_radius);
        let axes = minimum::blocked_axes(grid, &self.field, m, &self.positions, radius);
        if !minimum::accepts(o.corner_rule, axes) {
            return;
        }
        if minimum::place(grid, &mut self.field, o.footprint, m, axes, self.goal) == 0 {
            return;
        }
        self.minima.accepted += 1;
        for i in 0..self.particles.len() {
            let pos = self.particles[i].pos;
            let near = match o.relocate {
                Relocate::Near => chebyshev(pos, m) <= 1,
                Relocate::OnCell => pos == m,
            };
            if near || !self.field.free(grid, pos) {
                let to = self.displace(grid, pos, rng);
                let p = &mut self.particles[i];
                if to != pos {
                    p.pos = to;
                    p.trajectory.push(to);
                }
            }
        }
        for i in 0..self.particles.len() {
            if !self.field.is_virtual(self.particles[i].best) {
                continue;
            }
            let best = match o.best_reset {
                BestReset::Current => self.particles[i].pos,
                BestReset::BestVisited => self.best_visited(grid, i),
            };
            let p = &mut self.particles[i];
            p.best = best;
            p.best_j = objective(best, self.goal);
        }
        // x^G is recomputed from scratch: the old one lies on an obstacle now.
        self.best_j = f64::INFINITY;
        self.update_global();
        self.detector.reset();
    }

    /// A random free neighbour of `pos` (up to 8 draws), else the first free one in a fixed
    /// order, else `pos`; the displacement stays within one cell so the trace stays connected.
    fn displace(&self, grid: &Grid, pos: [i64; 2], rng: &mut ChaCha8Rng) -> [i64; 2] {
        for _ in 0..8 {
            let r: [i64; 2] = [rng.gen_range(-1..=1), rng.gen_range(-1..=1)];
            let to = [pos[0] + r[0], pos[1] + r[1]];
            if r != [0, 0] && self.field.free(grid, to) {
                return to;
            }
        }
        for dy in -1..=1 {
            for dx in -1..=1 {
                let to = [pos[0] + dx, pos[1] + dy];
                if self.field.free(grid, to) {
                    return to;
                }
            }
        }
        pos
    }

    fn best_visited(&self, grid: &Grid, i: usize) -> [i64; 2] {
        let p = &self.particles[i];
        let mut best = (objective(p.pos, self.goal), p.pos);
        for &c in &p.trajectory {
            let j = objective(c, self.goal);
            if j < best.0 && self.field.free(grid, c) {
                best = (j, c);
            }
        }
        best.1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_20_symmetric_reading_has_the_notes_probabilities() {
        // r_max = 1: round(-1 + 2u) is -1 below u = 1/4, 0 up to 3/4, +1 above: 1/4, 1/2, 1/4.
        let f = |u| noise(NoiseForm::Symmetric, 1, u);
        assert_eq!(
            [
                f(0.0),
                f(0.249),
                f(0.251),
                f(0.5),
                f(0.749),
                f(0.751),
                f(1.0)
            ],
            [-1, -1, 0, 0, 0, 1, 1]
        );
        let n = 100_000;
        let mut counts = [0u32; 3];
        for k in 0..n {
            counts[(f((k as f64 + 0.5) / n as f64) + 1) as usize] += 1;
        }
        assert_eq!(counts, [25_000, 50_000, 25_000]);
        // The literal OCR reading round(-r_max + r_max u) would stay in [-r_max, 0]; ours spans both signs.
        assert_eq!(
            (
                noise(NoiseForm::Symmetric, 4, 0.0),
                noise(NoiseForm::Symmetric, 4, 1.0)
            ),
            (-4, 4)
        );
    }

    #[test]
    fn uniform_noise_is_equiprobable() {
        let n = 90_000;
        let mut counts = [0u32; 5];
        for k in 0..n {
            counts[(noise(NoiseForm::Uniform, 2, (k as f64 + 0.5) / n as f64) + 2) as usize] += 1;
        }
        assert_eq!(counts, [18_000; 5]);
        assert_eq!(noise(NoiseForm::Uniform, 2, 1.0), 2);
    }

    #[test]
    fn velocities_saturate_to_v_max() {
        assert_eq!(saturate(1.6, Rounding::Nearest, 1), 1);
        assert_eq!(saturate(-3.2, Rounding::Nearest, 1), -1);
        assert_eq!(saturate(0.49, Rounding::Nearest, 1), 0);
        assert_eq!(saturate(0.5, Rounding::Nearest, 1), 1);
        assert_eq!(saturate(0.9, Rounding::Truncate, 1), 0);
        assert_eq!(saturate(-2.5, Rounding::Nearest, 2), -2);
    }

    #[test]
    fn objective_is_the_euclidean_distance() {
        assert_eq!(objective([3, 4], [0, 0]), 5.0);
        assert_eq!(objective([7, 7], [7, 7]), 0.0);
    }
}
