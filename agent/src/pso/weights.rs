//! The modified algorithm's adaptive local/global weights, eqs. (10)-(19) of the notes
//! (§2.4): per particle and per coordinate, k^L and k^G shift toward whichever best (the
//! particle's own or the swarm's) moved closer to the goal along that coordinate, by a step
//! `tanh(±0.5 η ΔB)` with a random η.

/// One coordinate's weights and the previous deviations the increments (11)-(12) need.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Weights {
    /// k^L: the weight of the particle's own best.
    pub local: f64,
    /// k^G: the weight of the swarm's best; `local + global == 1` after every update (10).
    pub global: f64,
    /// b^L(t-1) = |x^L - x_t| at the previous step, `None` before the first (Δb = 0 then).
    prev_local: Option<f64>,
    /// b^G(t-1).
    prev_global: Option<f64>,
}

impl Weights {
    /// Both weights at `k` and `1 - k` (the paper starts both at 0.5).
    pub fn new(k: f64) -> Weights {
        Weights {
            local: k,
            global: 1.0 - k,
            prev_local: None,
            prev_global: None,
        }
    }

    /// One step of (11)-(15): `b_local`/`b_global` are this step's |x^L_j - x_tj| and
    /// |x^G_j - x_tj|, `eta` the step's η (19). Returns ΔB (18) for the record.
    pub fn update(&mut self, b_local: f64, b_global: f64, eta: f64) -> f64 {
        // At t = 0 there is no b(t-1): Δb = 0, so ΔB = 0, λ = 0 and the weights stay (notes §2.4).
        let d_local = self.prev_local.map_or(0.0, |p| b_local - p);
        let d_global = self.prev_global.map_or(0.0, |p| b_global - p);
        self.prev_local = Some(b_local);
        self.prev_global = Some(b_global);
        let delta = d_global - d_local;
        let (local, global) = shift(self.local, self.global, delta, eta);
        self.local = local;
        self.global = global;
        delta
    }
}

/// λ of eq. (16): `tanh(0.5 η ΔB)`, in [0, 1) where it is used (ΔB >= 0).
pub fn lambda(eta: f64, delta: f64) -> f64 {
    (0.5 * eta * delta).tanh()
}

/// μ of eq. (17): `tanh(-0.5 η ΔB)`, in (0, 1) where it is used (ΔB < 0).
pub fn mu(eta: f64, delta: f64) -> f64 {
    (-0.5 * eta * delta).tanh()
}

/// η of eq. (19) for the uniform draw `gamma` in [0, 1].
pub fn eta(eta_min: f64, eta_max: f64, gamma: f64) -> f64 {
    eta_min + gamma * (eta_max - eta_min)
}

/// The update law (14)-(15): condition (13) `ΔB >= 0` (local no less successful) moves
/// weight from k^G to k^L, otherwise from k^L to k^G; the sum is kept.
pub fn shift(local: f64, global: f64, delta: f64, eta: f64) -> (f64, f64) {
    if delta >= 0.0 {
        let l = lambda(eta, delta);
        (local + l * global, global * (1.0 - l))
    } else {
        let m = mu(eta, delta);
        (local * (1.0 - m), global + m * local)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_step_leaves_the_weights_at_one_half() {
        let mut w = Weights::new(0.5);
        assert_eq!(w.update(7.0, 3.0, 1.3), 0.0);
        assert_eq!((w.local, w.global), (0.5, 0.5));
    }

    #[test]
    fn the_law_at_given_inputs() {
        // ΔB = 1, η = 2: λ = tanh(1) = 0.761594..., k^L = 0.5 + 0.5 λ, k^G = 0.5 (1 - λ).
        let (l, g) = shift(0.5, 0.5, 1.0, 2.0);
        let t = 1.0f64.tanh();
        assert!((t - 0.761_594_155_955_765).abs() < 1e-15);
        assert_eq!((l, g), (0.5 + 0.5 * t, 0.5 * (1.0 - t)));
        // ΔB = -1: μ = tanh(1) as well, the weight moves the other way by the same amount.
        let (l2, g2) = shift(0.5, 0.5, -1.0, 2.0);
        assert!((l2 - g).abs() < 1e-15 && (g2 - l).abs() < 1e-15);
        assert_eq!(eta(0.5, 2.0, 0.0), 0.5);
        assert_eq!(eta(0.5, 2.0, 1.0), 2.0);
        assert_eq!(eta(0.5, 2.0, 0.5), 1.25);
    }

    #[test]
    fn the_increments_compare_global_and_local_progress() {
        let mut w = Weights::new(0.5);
        w.update(10.0, 10.0, 1.0);
        // The particle's best came 2 closer, the swarm's 0: ΔB = 0 - (-2) = 2 >= 0, local gains.
        assert_eq!(w.update(8.0, 10.0, 1.0), 2.0);
        assert!(w.local > 0.5 && (w.local + w.global - 1.0).abs() < 1e-15);
        // Now the swarm's best gains 3 and the particle's nothing: ΔB = -3, global gains.
        let before = w.global;
        assert_eq!(w.update(8.0, 7.0, 1.0), -3.0);
        assert!(w.global > before);
    }

    #[test]
    fn the_weights_stay_normalised_and_in_range() {
        // Invariants of §6.3 over a deterministic sweep of ΔB and η.
        let (mut l, mut g) = (0.5, 0.5);
        for i in 0..2000 {
            let delta = ((i * 37) % 23) as f64 - 11.0;
            let e = eta(0.5, 2.0, ((i * 13) % 101) as f64 / 100.0);
            assert!((0.5..=2.0).contains(&e));
            if delta >= 0.0 {
                assert!((0.0..1.0).contains(&lambda(e, delta)));
            } else {
                assert!((0.0..1.0).contains(&mu(e, delta)));
            }
            (l, g) = shift(l, g, delta, e);
            assert!((l + g - 1.0).abs() < 1e-12, "{l} + {g}");
            assert!((0.0..=1.0).contains(&l) && (0.0..=1.0).contains(&g));
        }
    }
}
