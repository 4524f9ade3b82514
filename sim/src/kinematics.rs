//! Differential-drive kinematics (reference §D.2) in nalgebra terms: wheel travel to pose
//! increments, and the exact-arc pose update as a rigid motion.
//!
//! A pose is an [`Isometry2`]: a position (`Point2`, m) and a heading rotation
//! ([`Heading`] = `UnitComplex`, which *is* the unit vector `(cos θ, sin θ)`). Driving an arc
//! of length `Δs` that turns by `Δθ` is the body-frame rigid motion [`arc_motion`]: rotate by
//! `Δθ/2`, move the chord `Δs·sinc(Δθ/2)` straight ahead, rotate by the other `Δθ/2`. The new
//! pose is the old one composed with it, `pose * arc_motion(Δs, Δθ)` ([`arc_update`]).
//!
//! [`arc_step`] is the same update in the form the stepper's inner loop uses: position and
//! heading as separate values, the half-turn rotation from a Taylor series instead of the
//! library's `sin_cos`, and the heading carried from step to step as a rotation rather than
//! re-derived from the angle (the world re-derives it every 256 steps so rounding cannot
//! drift). Its operations are plain `f64` multiplications and additions in a fixed order, so
//! it is bit-for-bit deterministic on every platform Rust supports (no fused multiply-add is
//! introduced behind our back).

use hnav_runtime::msg::Pose;
use nalgebra::{Isometry2, Point2, Translation2, UnitComplex, Vector2};

/// A heading as a rotation: the unit complex number `cos θ + i·sin θ`.
pub type Heading = UnitComplex<f64>;

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

/// The rigid motion, in the robot's own frame, of driving an arc of length `ds` while
/// turning by `dtheta` (exact for a constant-curvature segment): the chord
/// `ds·sinc(dtheta/2)` in direction `dtheta/2`, and the rotation `dtheta`.
///
/// This is §D.2's exact-arc update `x' = x + R(sin θ' − sin θ)`, `y' = y − R(cos θ' − cos θ)`
/// with `R = Δs/Δθ`, rewritten with the sum-to-product identities: no division by a small
/// `Δθ`, and the midpoint (RK2) update as its `Δθ → 0` limit, so no switch between two forms
/// is needed.
#[inline]
pub fn arc_motion(ds: f64, dtheta: f64) -> Isometry2<f64> {
    let h = 0.5 * dtheta;
    let chord = ds * sinc(h);
    let (s, c) = h.sin_cos();
    Isometry2::from_parts(
        Translation2::new(chord * c, chord * s),
        UnitComplex::new(dtheta),
    )
}

/// Moves `pose` along an arc of length `ds` turning by `dtheta`: `pose * arc_motion(ds,
/// dtheta)`.
#[inline]
pub fn arc_update(pose: &Isometry2<f64>, ds: f64, dtheta: f64) -> Isometry2<f64> {
    pose * arc_motion(ds, dtheta)
}

/// The rigid transform of a [`Pose`] message.
#[inline]
pub fn isometry(p: Pose) -> Isometry2<f64> {
    Isometry2::new(Vector2::new(p.x_m, p.y_m), p.theta_rad)
}

/// [`arc_update`] on a [`Pose`]; its `theta` is carried on unwrapped (`theta + dtheta`).
pub fn arc_update_pose(p: Pose, ds: f64, dtheta: f64) -> Pose {
    let moved = arc_update(&isometry(p), ds, dtheta);
    Pose {
        x_m: moved.translation.x,
        y_m: moved.translation.y,
        theta_rad: p.theta_rad + dtheta,
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

/// The heading of angle `theta`: `UnitComplex::new` with the cosine and sine of one
/// `f64::sin_cos` call.
#[inline]
pub fn heading(theta: f64) -> Heading {
    let (s, c) = theta.sin_cos();
    UnitComplex::from_cos_sin_unchecked(c, s)
}

/// [`arc_update`] for the stepper's inner loop: `position` and `heading` after an arc of
/// length `ds` turning by `dtheta`, with no library trigonometry for the per-step angles.
/// The caller keeps `θ` itself by adding `dtheta`, and re-derives the heading from it now and
/// then (see [`heading`]) so rounding in the rotations cannot accumulate.
#[inline]
pub fn arc_step(
    position: &Point2<f64>,
    heading: &Heading,
    ds: f64,
    dtheta: f64,
) -> (Point2<f64>, Heading) {
    let h = 0.5 * dtheta;
    let (sh, ch) = small_sin_cos(h);
    let sinc = if h.abs() < SINC_SERIES_BELOW {
        sinc(h)
    } else {
        sh / h
    };
    let half = UnitComplex::from_cos_sin_unchecked(ch, sh);
    // Heading at mid-arc (the chord's direction), then at the end: two rotations by h.
    let mid = heading * half;
    let chord = Vector2::new(mid.cos_angle(), mid.sin_angle()) * (ds * sinc);
    (position + chord, mid * half)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_composes_to_a_circle() {
        // A quarter circle of radius 1 in 1000 pieces lands exactly on (1, 1, π/2).
        let mut p = Isometry2::identity();
        let n = 1000;
        let dt = std::f64::consts::FRAC_PI_2 / n as f64;
        for _ in 0..n {
            p = arc_update(&p, dt, dt);
        }
        let (x, y) = (p.translation.x, p.translation.y);
        assert!(
            (x - 1.0).abs() < 1e-12 && (y - 1.0).abs() < 1e-12,
            "{x} {y}"
        );
        assert!((p.rotation.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn matches_the_d2_exact_arc_form() {
        for &(t, ds, dt) in &[(0.3, 0.01, 0.2), (-2.0, 0.5, -1.3), (1.0, 0.001, 0.02)] {
            let r = ds / dt;
            let start = Pose {
                x_m: 1.0,
                y_m: 2.0,
                theta_rad: t,
            };
            let p = arc_update_pose(start, ds, dt);
            let t2: f64 = t + dt;
            assert!((p.x_m - (1.0 + r * (t2.sin() - t.sin()))).abs() < 1e-12);
            assert!((p.y_m - (2.0 - r * (t2.cos() - t.cos()))).abs() < 1e-12);
            assert_eq!(p.theta_rad, t2);
        }
    }

    #[test]
    fn small_sin_cos_and_the_step_form_agree_with_libm() {
        for h in [0.0, 1e-9, -3e-4, 0.0084, -0.05, 0.099, 0.3, -2.0] {
            let (s, c) = small_sin_cos(h);
            assert!(
                (s - h.sin()).abs() < 3e-16 && (c - h.cos()).abs() < 3e-16,
                "{h}"
            );
        }
        let (t, ds, dt) = (0.7, 0.004, 0.008);
        let p = arc_update(&Isometry2::new(Vector2::new(1.0, 2.0), t), ds, dt);
        let (q, h) = arc_step(&Point2::new(1.0, 2.0), &heading(t), ds, dt);
        assert!((p.translation.vector - q.coords).norm() < 1e-15);
        let th = t + dt;
        assert!(
            (th.cos() - h.cos_angle()).abs() < 1e-15 && (th.sin() - h.sin_angle()).abs() < 1e-15
        );
    }
}
