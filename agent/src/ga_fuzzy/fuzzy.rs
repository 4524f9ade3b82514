//! Seed 004's fine subsystem: the fuzzy controller (§B.4 of the notes).
//!
//! What the seed fixes: two inputs, `A` (the free area of the working zone in each of the
//! eight movement directions, from the onboard short-range sensors) and `b` (the deviation of
//! the heading from the direction to the target); two outputs, the linear speed `V` and the
//! direction of motion `phi` (an angular shift that need not equal `b`); linguistic variables
//! with term sets; a production-rule base of **72 rules: nine nested rules for each of eight
//! values of the angular deviation**. Term names, membership functions, the `A` encoding
//! (Fig. 2a, an image) and the inference method are not in the text. Filled in here
//! `\[inferred\]`:
//!
//! * `b` has eight terms, the eight 45° sectors (triangles centred on `0, 45, ..., 315` degrees,
//!   half-width 45°, so the memberships sum to 1 at every angle).
//! * From `A` the rules read the direction of the target `d` (the one of the eight nearest
//!   the bearing): `F`, the free distance along `d` (terms near / mid / far), and the side
//!   balance `free(d + 1) - free(d - 1)` (terms counter-clockwise freer / even / clockwise
//!   freer). `3 x 3 = 9` nested rules per `b` term, `8 x 9 = 72`.
//! * Consequents are singletons (zero-order Sugeno), the conjunction is the product and the
//!   output the weighted mean: `V` is a fraction of the top speed (the `b` sector sets how
//!   fast the robot may go while turning, `F` how close it may come to what is ahead); the
//!   shift turns away from the closer side, more the nearer the obstacle ahead.
//! * `A` is normalised by the sensor range: distance / range, clamped to `[0, 1]`.

use std::f64::consts::{FRAC_PI_4, PI};

use hnav_runtime::grid::geometry::wrap_angle_shifted;

/// Number of movement directions (and of `b` terms).
pub const DIRECTIONS: usize = 8;

/// Number of rules: nine for each of the eight `b` terms (the seed's 72).
pub const RULES: usize = 72;

/// The angle of direction `k` in [`hnav_runtime::grid::Direction::ALL`] order (N, NE, E, ...),
/// in the pose's frame (x east, y down, so N is `-90°`).
pub fn direction_angle(k: usize) -> f64 {
    (k as f64) * FRAC_PI_4 - PI / 2.0
}

/// Terms of the free distance ahead, `F`.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Ahead {
    /// An obstacle within half the sensor range.
    Near,
    /// Around half the range.
    Mid,
    /// Nothing within the range.
    Far,
}

/// Terms of the side balance.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Side {
    /// More free space counter-clockwise of the target direction.
    CcwFreer,
    /// Both sides alike.
    Even,
    /// More free space clockwise.
    CwFreer,
}

/// One production rule: IF `b` is sector `b` AND `F` is `ahead` AND the balance is `side`
/// THEN `V` is `speed` AND the shift is `shift`.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Rule {
    /// The `b` term: sector `b * 45°`.
    pub b: u8,
    /// The `F` term.
    pub ahead: Ahead,
    /// The balance term.
    pub side: Side,
    /// `V` as a fraction of the top speed.
    pub speed: f64,
    /// Angular shift added to `b`, radians.
    pub shift: f64,
}

/// The 72 rules, nine per `b` term, in `b`, then `F`, then side order.
pub fn rule_base() -> [Rule; RULES] {
    // Sector speed: full ahead, half at 45°, turn in place beyond [inferred].
    const SECTOR_SPEED: [f64; DIRECTIONS] = [1.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5];
    let ahead = [
        (Ahead::Near, 0.4, FRAC_PI_4),
        (Ahead::Mid, 0.7, 0.35),
        (Ahead::Far, 1.0, 0.15),
    ];
    let side = [
        (Side::CcwFreer, -1.0),
        (Side::Even, 0.0),
        (Side::CwFreer, 1.0),
    ];
    let mut rules = [Rule {
        b: 0,
        ahead: Ahead::Far,
        side: Side::Even,
        speed: 0.0,
        shift: 0.0,
    }; RULES];
    let mut n = 0;
    for (b, sector) in SECTOR_SPEED.iter().enumerate() {
        for &(a, a_speed, turn) in &ahead {
            for &(s, sign) in &side {
                rules[n] = Rule {
                    b: b as u8,
                    ahead: a,
                    side: s,
                    speed: sector * a_speed,
                    shift: sign * turn,
                };
                n += 1;
            }
        }
    }
    rules
}

/// Membership of `b` (radians) in sector `j` (centre `j * 45°`).
pub fn mu_sector(b: f64, j: usize) -> f64 {
    let d = wrap_angle_shifted(b - (j as f64) * FRAC_PI_4).abs();
    (1.0 - d / FRAC_PI_4).max(0.0)
}

/// Membership of the normalised free distance `f` in `term`.
pub fn mu_ahead(f: f64, term: Ahead) -> f64 {
    let f = f.clamp(0.0, 1.0);
    match term {
        Ahead::Near => (1.0 - 2.0 * f).max(0.0),
        Ahead::Mid => 1.0 - (2.0 * f - 1.0).abs(),
        Ahead::Far => (2.0 * f - 1.0).max(0.0),
    }
}

/// Membership of the balance `q in [-1, 1]` in `term`.
pub fn mu_side(q: f64, term: Side) -> f64 {
    let q = q.clamp(-1.0, 1.0);
    match term {
        Side::CcwFreer => (-q).max(0.0),
        Side::Even => 1.0 - q.abs(),
        Side::CwFreer => q.max(0.0),
    }
}

/// The controller's answer.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct FuzzyOutput {
    /// `V`, a fraction of the top speed in `[0, 1]`.
    pub speed: f64,
    /// `phi`, the heading change to make, radians (`b` plus the rules' shift).
    pub turn: f64,
}

/// The fuzzy controller: the rule base, evaluated without allocating.
#[derive(Clone, Debug)]
pub struct FuzzyRules {
    // Boxed: 72 rules inline would make every controller holding them 2 kB.
    rules: Box<[Rule; RULES]>,
}

impl Default for FuzzyRules {
    fn default() -> Self {
        FuzzyRules {
            rules: Box::new(rule_base()),
        }
    }
}

impl FuzzyRules {
    /// The rules.
    pub fn rules(&self) -> &[Rule; RULES] {
        &self.rules
    }

    /// Infers `V` and `phi` from the free areas `free` (normalised, [`direction_angle`]
    /// order), the heading `theta` and the bearing to the target `bearing` (radians).
    pub fn infer(&self, free: &[f64; DIRECTIONS], theta: f64, bearing: f64) -> FuzzyOutput {
        let b = wrap_angle_shifted(bearing - theta);
        let d = nearest_direction(bearing);
        let ahead = free[d];
        let q = free[(d + 1) % DIRECTIONS] - free[(d + DIRECTIONS - 1) % DIRECTIONS];
        let (mut w_sum, mut v, mut s) = (0.0, 0.0, 0.0);
        for r in self.rules.iter() {
            let w = mu_sector(b, usize::from(r.b)) * mu_ahead(ahead, r.ahead) * mu_side(q, r.side);
            w_sum += w;
            v += w * r.speed;
            s += w * r.shift;
        }
        // The three partitions sum to 1, so w_sum is 1 up to rounding; divide anyway.
        let (v, s) = if w_sum > 0.0 {
            (v / w_sum, s / w_sum)
        } else {
            (0.0, 0.0)
        };
        FuzzyOutput {
            speed: v.clamp(0.0, 1.0),
            turn: wrap_angle_shifted(b + s),
        }
    }
}

/// The index of the movement direction nearest the angle `a`.
pub fn nearest_direction(a: f64) -> usize {
    let k = ((a + PI / 2.0) / FRAC_PI_4).round() as i64;
    k.rem_euclid(DIRECTIONS as i64) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rule_base_has_nine_rules_for_each_of_eight_deviations() {
        let rules = rule_base();
        assert_eq!(rules.len(), 72);
        for b in 0..8u8 {
            let of_b: Vec<&Rule> = rules.iter().filter(|r| r.b == b).collect();
            assert_eq!(of_b.len(), 9, "b term {b}");
            for a in [Ahead::Near, Ahead::Mid, Ahead::Far] {
                for s in [Side::CcwFreer, Side::Even, Side::CwFreer] {
                    let n = of_b.iter().filter(|r| r.ahead == a && r.side == s).count();
                    assert_eq!(n, 1, "b {b} {a:?} {s:?}");
                }
            }
        }
    }

    #[test]
    fn memberships_partition_unity() {
        for i in 0..=720 {
            let b = f64::from(i) * PI / 360.0 - PI;
            let sum: f64 = (0..8).map(|j| mu_sector(b, j)).sum();
            assert!((sum - 1.0).abs() < 1e-12, "{b}: {sum}");
        }
        for i in 0..=100 {
            let f = f64::from(i) / 100.0;
            let a: f64 = [Ahead::Near, Ahead::Mid, Ahead::Far]
                .iter()
                .map(|&t| mu_ahead(f, t))
                .sum();
            let q = 2.0 * f - 1.0;
            let s: f64 = [Side::CcwFreer, Side::Even, Side::CwFreer]
                .iter()
                .map(|&t| mu_side(q, t))
                .sum();
            assert!((a - 1.0).abs() < 1e-12 && (s - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn heads_for_open_targets_and_turns_away_from_the_closer_side() {
        let fr = FuzzyRules::default();
        let open = [1.0; 8];
        let o = fr.infer(&open, 0.0, 0.0);
        assert_eq!((o.speed, o.turn), (1.0, 0.0));
        // Target behind: turn in place towards it.
        let back = fr.infer(&open, 0.0, 3.0);
        assert_eq!(back.speed, 0.0);
        assert!((back.turn - 3.0).abs() < 1e-12);
        // Heading east (index 2) with a wall close on the north-east side: shift towards
        // south-east (positive angles, y down).
        let mut wall = open;
        wall[1] = 0.2;
        let w = fr.infer(&wall, 0.0, 0.0);
        assert!(w.turn > 0.05 && w.turn < FRAC_PI_4, "{w:?}");
        // Something close ahead slows the robot down.
        let mut ahead = open;
        ahead[2] = 0.1;
        assert!(fr.infer(&ahead, 0.0, 0.0).speed < 0.5);
        assert_eq!(nearest_direction(-PI / 2.0), 0);
        assert_eq!(nearest_direction(PI), 6);
    }
}
