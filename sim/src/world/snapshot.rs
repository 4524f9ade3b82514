//! The world's dynamic state as bytes, for the sim's restart checkpoint
//! ([`crate::process`] writes it to `DIR/sim.ckpt.{0,1}`).
//!
//! A restarted sim rebuilds its world from the scenario and then restores this: every value
//! that a step reads and the scenario does not fix (step count, poses with the carried
//! heading rotations, wheel speeds, commands, wheel angles, slip factors and each robot's
//! position in its slip stream, the collision detector's contacts in progress, the collisions
//! so far, the energy each robot's motors drew and when it first stood in its goal cell).
//! Floats travel as their bits, so a restored world steps on bit for bit as the original
//! would have: in lockstep a run resumed from a checkpoint decides what the run
//! without the kill decided.
//!
//! Encoding: little-endian `u64` words — a magic, the robot count, the step count, 23 words
//! per robot, the contacts and collisions each as a count and fixed-size entries, the
//! movers' walks (cells walked, seconds waited) as a count and two words each; the caller
//! frames it (the process adds its own header and a checksum).

use nalgebra::{Complex, Point2, UnitComplex};

use super::World;
use crate::collision::{Collision, Hit};

const MAGIC: u64 = 0x5753_5641_4e48_0003; // "HNAVSW" v3: with the criteria meter and the movers' walks
/// Words of one collision entry.
const COLLISION_WORDS: usize = 9;

/// Why bytes do not restore a world.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SnapshotError {
    /// Not a world snapshot, or one of another format version.
    #[error("not a world snapshot of this version")]
    Foreign,
    /// Written for a world of another size.
    #[error("written for {found} robots, the world has {expected}")]
    Robots {
        /// Robots of this world.
        expected: usize,
        /// Robots in the snapshot.
        found: u64,
    },
    /// Cut short or padded.
    #[error("truncated or overlong")]
    Length,
}

/// Reads words off a byte slice, failing once past its end.
struct Words<'b>(&'b [u8]);

impl Words<'_> {
    fn next(&mut self) -> Result<u64, SnapshotError> {
        let (w, rest) = self
            .0
            .split_first_chunk::<8>()
            .ok_or(SnapshotError::Length)?;
        self.0 = rest;
        Ok(u64::from_le_bytes(*w))
    }

    fn f64(&mut self) -> Result<f64, SnapshotError> {
        self.next().map(f64::from_bits)
    }

    fn option(&mut self) -> Result<Option<u64>, SnapshotError> {
        let (present, v) = (self.next()?, self.next()?);
        Ok((present != 0).then_some(v))
    }

    fn count(&mut self, words_each: usize) -> Result<usize, SnapshotError> {
        let n = self.next()?;
        // A count larger than what is left cannot be real: refuse it before allocating.
        match usize::try_from(n) {
            Ok(n) if n.saturating_mul(8 * words_each) <= self.0.len() => Ok(n),
            _ => Err(SnapshotError::Length),
        }
    }
}

fn put(out: &mut Vec<u8>, w: u64) {
    out.extend_from_slice(&w.to_le_bytes());
}

fn put_option(out: &mut Vec<u8>, v: Option<u64>) {
    put(out, u64::from(v.is_some()));
    put(out, v.unwrap_or(0));
}

impl World {
    /// Appends the world's dynamic state to `out`: every value a step reads that the scenario
    /// does not fix, floats as their bits. With `out` reused, no allocation once it has grown
    /// to the snapshot's size.
    pub fn write_snapshot(&self, out: &mut Vec<u8>) {
        put(out, MAGIC);
        put(out, self.robots() as u64);
        put(out, self.steps);
        for i in 0..self.robots() {
            let word = self.noise[i].word_pos();
            for v in [
                self.pos[i].x,
                self.pos[i].y,
                self.theta[i],
                self.heading[i].re,
                self.heading[i].im,
                self.wl[i],
                self.wr[i],
                self.cmd_l[i],
                self.cmd_r[i],
                self.phil[i],
                self.phir[i],
                self.slip_l[i],
                self.slip_r[i],
                self.meter.energy_j[i],
            ] {
                put(out, v.to_bits());
            }
            put_option(out, self.cmd_at[i]);
            put_option(out, self.cmd_period[i]);
            put_option(out, self.meter.goal_at_ns[i]);
            put(out, word as u64);
            put(out, (word >> 64) as u64);
            put(out, u64::from(self.detector.on_wall(i)));
        }
        let touching = self.detector.touching();
        put(out, touching.len() as u64);
        for &(a, b) in touching {
            put(out, u64::from(a) | (u64::from(b) << 32));
        }
        put(out, self.collisions.len() as u64);
        for c in &self.collisions {
            let (kind, x, y) = match c.hit {
                Hit::Robot(j) => (0, i64::from(j), 0),
                Hit::Cell(x, y) => (1, x, y),
                Hit::Mover(k) => (2, i64::from(k), 0),
            };
            for w in [c.time_ns, u64::from(c.robot), kind, x as u64, y as u64] {
                put(out, w);
            }
            for v in [c.position, c.other_position] {
                put(out, v.x.to_bits());
                put(out, v.y.to_bits());
            }
        }
        put(out, self.changes.walked().count() as u64);
        for (walked, waited) in self.changes.walked() {
            put(out, walked.to_bits());
            put(out, waited.to_bits());
        }
    }

    /// Replaces the world's dynamic state by a snapshot of a world built from the same
    /// scenario. On error the world is left unchanged.
    pub fn restore_snapshot(&mut self, bytes: &[u8]) -> Result<(), SnapshotError> {
        let mut w = Words(bytes);
        if w.next()? != MAGIC {
            return Err(SnapshotError::Foreign);
        }
        let n = self.robots();
        let found = w.next()?;
        if found != n as u64 {
            return Err(SnapshotError::Robots { expected: n, found });
        }
        let mut next = self.clone();
        next.steps = w.next()?;
        for i in 0..n {
            next.pos[i] = Point2::new(w.f64()?, w.f64()?);
            next.theta[i] = w.f64()?;
            let (re, im) = (w.f64()?, w.f64()?);
            next.heading[i] = UnitComplex::new_unchecked(Complex::new(re, im));
            next.wl[i] = w.f64()?;
            next.wr[i] = w.f64()?;
            next.cmd_l[i] = w.f64()?;
            next.cmd_r[i] = w.f64()?;
            next.phil[i] = w.f64()?;
            next.phir[i] = w.f64()?;
            next.slip_l[i] = w.f64()?;
            next.slip_r[i] = w.f64()?;
            next.meter.energy_j[i] = w.f64()?;
            next.cmd_at[i] = w.option()?;
            next.cmd_period[i] = w.option()?;
            next.meter.goal_at_ns[i] = w.option()?;
            let (lo, hi) = (w.next()?, w.next()?);
            next.noise[i].set_word_pos(u128::from(lo) | (u128::from(hi) << 64));
            let on_wall = w.next()? != 0;
            next.detector.set_on_wall(i, on_wall);
        }
        let contacts = w.count(1)?;
        let mut touching = Vec::with_capacity(contacts);
        for _ in 0..contacts {
            let v = w.next()?;
            touching.push((v as u32, (v >> 32) as u32));
        }
        next.detector.set_touching(touching);
        let count = w.count(COLLISION_WORDS)?;
        next.collisions.clear();
        for _ in 0..count {
            let (time_ns, robot, kind, x, y) =
                (w.next()?, w.next()?, w.next()?, w.next()?, w.next()?);
            let hit = match kind {
                0 => Hit::Robot(x as u32),
                2 => Hit::Mover(x as u32),
                _ => Hit::Cell(x as i64, y as i64),
            };
            next.collisions.push(Collision {
                time_ns,
                robot: robot as u32,
                hit,
                position: Point2::new(w.f64()?, w.f64()?),
                other_position: Point2::new(w.f64()?, w.f64()?),
            });
        }
        let movers = w.count(2)?;
        let walked = (0..movers)
            .map(|_| Ok((w.f64()?, w.f64()?)))
            .collect::<Result<Vec<_>, SnapshotError>>()?;
        if !w.0.is_empty() {
            return Err(SnapshotError::Length);
        }
        // The cells change by the scenario and the time alone: catch up to the snapshot's;
        // the movers are where they had walked to (they wait for robots).
        next.apply_changes();
        let t_s = next.time_ns() as f64 * 1e-9;
        if !next
            .changes
            .restore_walked(&walked, t_s, next.model.cell_size_m)
        {
            return Err(SnapshotError::Length);
        }
        *self = next;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::grid::geometry::cell_centre_pose;
    use hnav_runtime::grid::{Cell, Grid};
    use hnav_runtime::msg::Truth;
    use hnav_runtime::scenario::params::{RobotParams, SimParams};

    /// Two robots driven head-on with slip on, so that the snapshot holds slip streams under
    /// way, a contact in progress and recorded collisions.
    fn world() -> World {
        let robot = RobotParams::default();
        let sim = SimParams {
            slip_std: 0.02,
            ..SimParams::default()
        };
        let cs = robot.cell_size_m;
        let starts = [
            cell_centre_pose(cs, Cell::new(1, 2), 0.0),
            cell_centre_pose(cs, Cell::new(4, 2), std::f64::consts::PI),
        ];
        World::new(&robot, &sim, Grid::new(8, 5).unwrap(), &starts).unwrap()
    }

    /// Steps `w` `n` times, commanding both robots ahead every 10 ms (the watchdog brakes a
    /// robot whose command is older than 100 ms).
    fn drive(w: &mut World, n: usize) {
        for _ in 0..n {
            if w.steps().is_multiple_of(10) {
                for i in 0..2 {
                    w.apply_command(i, w.steps() / 10, 8.0, 8.0, w.time_ns())
                        .unwrap();
                }
            }
            w.step();
        }
    }

    fn truth_bytes(w: &World) -> Vec<u64> {
        let mut t = Box::new(Truth::default());
        w.fill_truth(0, &mut t);
        let mut v = vec![t.sim_time_ns, u64::from(t.collisions)];
        for p in t.poses().iter() {
            v.extend([p.x_m.to_bits(), p.y_m.to_bits(), p.theta_rad.to_bits()]);
        }
        for i in 0..2 {
            let (l, r) = w.ticks(i).unwrap();
            v.extend([l as u64, r as u64]);
        }
        v
    }

    /// A world restored from a snapshot taken mid-run steps on bit for bit as the original.
    #[test]
    fn a_restored_world_steps_on_as_the_original() {
        let mut a = world();
        drive(&mut a, 1700);
        assert!(!a.collisions().is_empty(), "the test needs a collision");
        let mut bytes = Vec::new();
        a.write_snapshot(&mut bytes);
        let mut b = world();
        b.restore_snapshot(&bytes).unwrap();
        assert_eq!(truth_bytes(&a), truth_bytes(&b));
        drive(&mut a, 900);
        drive(&mut b, 900);
        assert_eq!(truth_bytes(&a), truth_bytes(&b));
        assert_eq!(a.collisions(), b.collisions());
        assert_eq!(a.criteria(), b.criteria());
        assert!(a.criteria().robots.iter().all(|r| r.energy_j > 0.0));
    }

    #[test]
    fn a_damaged_or_foreign_snapshot_is_refused_and_changes_nothing() {
        let mut a = world();
        a.step();
        let mut bytes = Vec::new();
        a.write_snapshot(&mut bytes);
        let mut b = world();
        let before = truth_bytes(&b);
        assert_eq!(
            b.restore_snapshot(&bytes[..bytes.len() - 3]),
            Err(SnapshotError::Length)
        );
        let mut foreign = bytes.clone();
        foreign[0] ^= 1;
        assert_eq!(b.restore_snapshot(&foreign), Err(SnapshotError::Foreign));
        let mut more = bytes.clone();
        more[8] = 3;
        assert_eq!(
            b.restore_snapshot(&more),
            Err(SnapshotError::Robots {
                expected: 2,
                found: 3
            })
        );
        assert_eq!(truth_bytes(&b), before);
    }
}
