//! Differential-drive kinematics (reference §D.2): wheel travel to pose increments and the
//! exact-arc pose update.

use hnav_runtime::msg::Pose;

/// Below this half-angle `sin(h)/h` is evaluated by its series (error < 1e-22), which avoids
/// the cancellation of `sin(h)/h` near zero.
const SINC_SERIES_BELOW: f64 = 1e-2;

/// Centre travel and heading change from the two wheels' ground travel.
#[inline]
pub fn increments(ds_left: f64, ds_right: f64, axle_track: f64) -> (f64, f64) {
    (
        0.5 * (ds_right + ds_left),
        (ds_right - ds_left) / axle_track,
    )
}

/// `sin(h) / h`, 1 at 0.
#[inline]
fn sinc(h: f64) -> f64 {
    if h.abs() < SINC_SERIES_BELOW {
        let h2 = h * h;
        1.0 - h2 * (1.0 / 6.0) * (1.0 - h2 * (1.0 / 20.0) * (1.0 - h2 * (1.0 / 42.0)))
    } else {
        h.sin() / h
    }
}

/// Moves `(x, y, theta)` along an arc of length `ds` turning by `dtheta` (exact for a
/// constant-curvature segment). Returns the new pose; `theta` is not wrapped.
///
/// This is §D.2's exact-arc update `x' = x + R(sin θ' − sin θ)`, `y' = y − R(cos θ' − cos θ)`
/// with `R = Δs/Δθ`, rewritten with the sum-to-product identities as
/// `x' = x + Δs·sinc(Δθ/2)·cos(θ + Δθ/2)` (and `sin` for `y`): one `sin_cos` instead of two,
/// no division by a small `Δθ`, and the midpoint (RK2) update as its `Δθ → 0` limit, so no
/// switch between the two forms is needed.
#[inline]
pub fn arc_update(x: f64, y: f64, theta: f64, ds: f64, dtheta: f64) -> (f64, f64, f64) {
    let h = 0.5 * dtheta;
    let chord = ds * sinc(h);
    let (s, c) = (theta + h).sin_cos();
    (x + chord * c, y + chord * s, theta + dtheta)
}

/// [`arc_update`] on a [`Pose`].
pub fn arc_update_pose(p: Pose, ds: f64, dtheta: f64) -> Pose {
    let (x_m, y_m, theta_rad) = arc_update(p.x_m, p.y_m, p.theta_rad, ds, dtheta);
    Pose {
        x_m,
        y_m,
        theta_rad,
    }
}

/// Above this angle [`small_sin_cos`] falls back to the library functions.
const SMALL_ANGLE: f64 = 0.1;

/// `(sin h, cos h)` for the small per-step angles of the stepper by their Taylor series
/// (error below 1e-19 for `|h| < 0.1`), far cheaper than the library calls; larger angles
/// use `f64::sin_cos`.
#[inline]
pub fn small_sin_cos(h: f64) -> (f64, f64) {
    if h.abs() >= SMALL_ANGLE {
        return h.sin_cos();
    }
    let h2 = h * h;
    // Horner form; reciprocal constants fold at compile time (multiplications, not divisions).
    let s = 1.0 - h2 * (1.0 / 72.0);
    let s = 1.0 - h2 * (1.0 / 42.0) * s;
    let s = 1.0 - h2 * (1.0 / 20.0) * s;
    let s = h * (1.0 - h2 * (1.0 / 6.0) * s);
    let c = 1.0 - h2 * (1.0 / 90.0);
    let c = 1.0 - h2 * (1.0 / 56.0) * c;
    let c = 1.0 - h2 * (1.0 / 30.0) * c;
    let c = 1.0 - h2 * (1.0 / 12.0) * c;
    let c = 1.0 - h2 * 0.5 * c;
    (s, c)
}

/// [`arc_update`] for a heading carried as its unit vector `(cos θ, sin θ)`: no library
/// trigonometry per step. Returns `(x', y', cos θ', sin θ')`; the caller keeps `θ` itself
/// by adding `Δθ`, and re-derives the vector from it now and then so rounding cannot drift.
#[inline]
pub fn arc_update_vec(
    x: f64,
    y: f64,
    c: f64,
    s: f64,
    ds: f64,
    dtheta: f64,
) -> (f64, f64, f64, f64) {
    let h = 0.5 * dtheta;
    let (sh, ch) = small_sin_cos(h);
    let sinc = if h.abs() < SINC_SERIES_BELOW {
        sinc(h)
    } else {
        sh / h
    };
    // Heading at mid-arc, then at the end: two rotations by h.
    let (cm, sm) = (c * ch - s * sh, s * ch + c * sh);
    let chord = ds * sinc;
    (
        x + chord * cm,
        y + chord * sm,
        cm * ch - sm * sh,
        sm * ch + cm * sh,
    )
}

/// Wraps an angle into `(-π, π]`.
#[inline]
pub fn wrap_angle(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    if a > -PI && a <= PI {
        return a;
    }
    let w = a.rem_euclid(TAU);
    if w > PI {
        w - TAU
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_composes_to_a_circle() {
        // A quarter circle of radius 1 in 1000 pieces lands exactly on (1, 1, π/2).
        let (mut x, mut y, mut t) = (0.0, 0.0, 0.0);
        let n = 1000;
        let dt = std::f64::consts::FRAC_PI_2 / n as f64;
        for _ in 0..n {
            (x, y, t) = arc_update(x, y, t, dt, dt);
        }
        assert!(
            (x - 1.0).abs() < 1e-12 && (y - 1.0).abs() < 1e-12,
            "{x} {y}"
        );
        assert!((t - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn matches_the_d2_exact_arc_form() {
        for &(t, ds, dt) in &[(0.3, 0.01, 0.2), (-2.0, 0.5, -1.3), (1.0, 0.001, 0.02)] {
            let r = ds / dt;
            let (x, y, th) = arc_update(1.0, 2.0, t, ds, dt);
            let t2: f64 = t + dt;
            assert!((x - (1.0 + r * (t2.sin() - t.sin()))).abs() < 1e-12);
            assert!((y - (2.0 - r * (t2.cos() - t.cos()))).abs() < 1e-12);
            assert_eq!(th, t2);
        }
    }

    #[test]
    fn small_sin_cos_and_vector_form_agree_with_libm() {
        for h in [0.0, 1e-9, -3e-4, 0.0084, -0.05, 0.099, 0.3, -2.0] {
            let (s, c) = small_sin_cos(h);
            assert!(
                (s - h.sin()).abs() < 3e-16 && (c - h.cos()).abs() < 3e-16,
                "{h}"
            );
        }
        let (t, ds, dt) = (0.7, 0.004, 0.008);
        let (x, y, th) = arc_update(1.0, 2.0, t, ds, dt);
        let (x2, y2, c2, s2) = arc_update_vec(1.0, 2.0, t.cos(), t.sin(), ds, dt);
        assert!((x - x2).abs() < 1e-15 && (y - y2).abs() < 1e-15);
        assert!((th.cos() - c2).abs() < 1e-15 && (th.sin() - s2).abs() < 1e-15);
    }

    #[test]
    fn wrap_angle_range() {
        use std::f64::consts::PI;
        assert_eq!(wrap_angle(0.5), 0.5);
        assert!((wrap_angle(3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap_angle(-3.5 * PI) - 0.5 * PI).abs() < 1e-12);
    }
}
