//! Collisions on ground truth: robot against robot (discs) and robot against blocked cells
//! (squares; cells outside the grid count as blocked). A collision is recorded when a contact
//! begins, not on every step it lasts.
//!
//! Geometry is in nalgebra terms: robot centres are `Point2<f64>` (m), and a contact is a
//! squared distance between points below the squared contact radius.

use hnav_runtime::grid::geometry::signed_cell_centre_m;
use hnav_runtime::grid::Grid;
use nalgebra::Point2;

/// What a robot hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Hit {
    /// Another robot (index).
    Robot(u32),
    /// A blocked cell `(x, y)` (column, row; may lie outside the grid): a wall, or a cell an
    /// event closed.
    Cell(i64, i64),
    /// A moving obstacle of the scenario's events (its number, in the order they appeared).
    Mover(u32),
}

/// One recorded collision: when it began, who was involved and where they were.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Collision {
    /// Sim time of the step that began the contact, ns.
    pub time_ns: u64,
    /// The robot (the lower index for robot pairs).
    pub robot: u32,
    /// What it hit: another robot or a blocked cell.
    pub hit: Hit,
    /// The robot's centre, m.
    pub position: Point2<f64>,
    /// The other robot's centre, or the hit cell's centre, m.
    pub other_position: Point2<f64>,
}

/// Whether two discs overlap (touching counts as no contact).
#[inline]
pub fn discs_overlap(a: &Point2<f64>, b: &Point2<f64>, ra: f64, rb: f64) -> bool {
    let r = ra + rb;
    (a - b).norm_squared() < r * r
}

/// The centre of cell `(cx, cy)` (column, row; may lie outside the grid) of edge `cell`, m,
/// as the point a wall contact records.
#[inline]
fn cell_centre_point(cx: i64, cy: i64, cell: f64) -> Point2<f64> {
    let (x, y) = signed_cell_centre_m(cell, cx, cy);
    Point2::new(x, y)
}

/// Whether a disc overlaps the square of cell `(cx, cy)` of edge `cell`: the point of the
/// square nearest to the centre lies within the radius.
#[inline]
pub fn disc_overlaps_cell(p: &Point2<f64>, r: f64, cx: i64, cy: i64, cell: f64) -> bool {
    let (x0, y0) = (cx as f64 * cell, cy as f64 * cell);
    let nearest = Point2::new(p.x.clamp(x0, x0 + cell), p.y.clamp(y0, y0 + cell));
    (p - nearest).norm_squared() < r * r
}

/// `floor(v)` as an integer without the libm call `f64::floor` becomes on targets without
/// SSE4.1.
#[inline]
fn floor_i64(v: f64) -> i64 {
    let t = v as i64;
    if (t as f64) > v {
        t - 1
    } else {
        t
    }
}

/// Whether cell `(x, y)` is blocked; outside the grid is blocked.
#[inline]
fn blocked(grid: &Grid, x: i64, y: i64) -> bool {
    grid.cell_checked(x, y).is_none_or(|c| grid.is_blocked(c))
}

/// Whether cell `c` and its 8 neighbours are free and inside the grid.
fn open_around(grid: &Grid, c: hnav_runtime::grid::Cell) -> bool {
    let (x, y) = (i64::from(c.x), i64::from(c.y));
    (-1..=1).all(|dy| (-1..=1).all(|dx| !blocked(grid, x + dx, y + dy)))
}

/// The first blocked cell a disc of radius `r` overlaps, if any. Only cells meeting the
/// disc's bounding box are examined (one to four when the disc is no wider than a cell).
pub fn wall_contact(grid: &Grid, p: &Point2<f64>, r: f64, cell: f64) -> Option<(i64, i64)> {
    let inv = 1.0 / cell;
    let (x0, x1) = (floor_i64((p.x - r) * inv), floor_i64((p.x + r) * inv));
    let (y0, y1) = (floor_i64((p.y - r) * inv), floor_i64((p.y + r) * inv));
    for y in y0..=y1 {
        for x in x0..=x1 {
            if blocked(grid, x, y) && disc_overlaps_cell(p, r, x, y, cell) {
                return Some((x, y));
            }
        }
    }
    None
}

/// Contact detection for a whole world, with reusable buffers (no allocation per step once
/// warm). Robot pairs use a sorted cell hash: robots ordered by cell key, each checked
/// against its own and the neighbouring cells only.
#[derive(Debug, Clone, Default)]
pub struct Detector {
    order: Vec<u32>,
    keys: Vec<i64>,
    sorted: Vec<i64>,
    touching: Vec<(u32, u32)>,
    touching_next: Vec<(u32, u32)>,
    on_wall: Vec<bool>,
    /// Per cell of the grid it was built for: the cell and its 8 neighbours are free and
    /// inside the grid, so a disc centred in it (no wider than a cell) touches no wall.
    open: Vec<bool>,
    open_w: u32,
    cell: f64,
    radius: f64,
}

impl Detector {
    /// A detector for `n` robots of body radius `radius` (at most `cell / 2`) on `grid`, whose
    /// cells have edge `cell` (m).
    pub fn new(n: usize, grid: &Grid, cell: f64, radius: f64) -> Detector {
        let open = grid.cells().map(|c| open_around(grid, c)).collect();
        Detector {
            open,
            open_w: grid.width(),
            cell,
            radius,
            order: (0..n as u32).collect(),
            keys: vec![0; n],
            sorted: Vec::with_capacity(n),
            touching: Vec::new(),
            touching_next: Vec::new(),
            on_wall: vec![false; n],
        }
    }

    /// Whether robot `i` touched a wall at the last check (a contact in progress is not
    /// recorded again).
    pub(crate) fn on_wall(&self, i: usize) -> bool {
        self.on_wall.get(i).copied().unwrap_or(false)
    }

    /// Restores [`Detector::on_wall`] of robot `i`.
    pub(crate) fn set_on_wall(&mut self, i: usize, v: bool) {
        if let Some(w) = self.on_wall.get_mut(i) {
            *w = v;
        }
    }

    /// The robot pairs in contact at the last check, sorted.
    pub(crate) fn touching(&self) -> &[(u32, u32)] {
        &self.touching
    }

    /// Restores [`Detector::touching`] (sorted here, as the check's binary search needs).
    pub(crate) fn set_touching(&mut self, mut pairs: Vec<(u32, u32)>) {
        pairs.sort_unstable();
        self.touching = pairs;
    }

    /// Whether centre `p` lies in an open cell (see `open`).
    #[inline]
    fn in_open_cell(&self, p: &Point2<f64>) -> bool {
        if !(p.x >= 0.0 && p.y >= 0.0) {
            return false;
        }
        let inv = 1.0 / self.cell;
        // Non-negative, so truncation is floor; far-off values saturate and fail the bounds.
        let (cx, cy) = ((p.x * inv) as u64, (p.y * inv) as u64);
        let w = u64::from(self.open_w);
        cx < w
            && self
                .open
                .get((cy.saturating_mul(w).saturating_add(cx)) as usize)
                == Some(&true)
    }

    /// Rebuilds the table of open cells after cells of `grid` closed or opened.
    pub(crate) fn refresh_open(&mut self, grid: &Grid) {
        for (open, c) in self.open.iter_mut().zip(grid.cells()) {
            *open = open_around(grid, c);
        }
    }

    /// Checks all contacts of the robot centres `centres` and appends the contacts that
    /// began this step to `out`. Returns how many were appended.
    pub fn check(
        &mut self,
        grid: &Grid,
        centres: &[Point2<f64>],
        time_ns: u64,
        out: &mut Vec<Collision>,
    ) -> usize {
        let before = out.len();
        let (cell, r) = (self.cell, self.radius);
        for (i, p) in centres.iter().enumerate() {
            let hit = if self.in_open_cell(p) {
                None
            } else {
                wall_contact(grid, p, r, cell)
            };
            match hit {
                Some((cx, cy)) if !self.on_wall[i] => out.push(Collision {
                    time_ns,
                    robot: i as u32,
                    hit: Hit::Cell(cx, cy),
                    position: *p,
                    other_position: cell_centre_point(cx, cy, cell),
                }),
                _ => {}
            }
            self.on_wall[i] = hit.is_some();
        }
        if centres.len() < 2 {
            return out.len() - before;
        }
        // Broad phase: robots sorted by the key of their (clamped) cell. A disc is no wider
        // than a cell, so a robot can only touch robots in its own cell and the 8 around it;
        // each pair is found once, from the robot whose cell comes first in key order.
        let (kw, kh) = (i64::from(grid.width()) + 2, i64::from(grid.height()) + 2);
        let inv = 1.0 / cell;
        for (k, p) in self.keys.iter_mut().zip(centres) {
            let cx = (floor_i64(p.x * inv) + 1).clamp(0, kw - 1);
            let cy = (floor_i64(p.y * inv) + 1).clamp(0, kh - 1);
            *k = cy * kw + cx;
        }
        // Insertion sort (stable, deterministic, ~O(n): last step's order is nearly sorted).
        let (order, keys) = (&mut self.order, &self.keys);
        for k in 1..order.len() {
            let v = order[k];
            let mut j = k;
            while j > 0 && keys[order[j - 1] as usize] > keys[v as usize] {
                order[j] = order[j - 1];
                j -= 1;
            }
            order[j] = v;
        }
        self.sorted.clear();
        self.sorted.extend(order.iter().map(|&i| keys[i as usize]));
        let (sorted, n) = (&self.sorted, order.len());
        self.touching_next.clear();
        let mut below = 0; // first index whose key may lie in the next row's window
        for a in 0..n {
            let (i, k) = (order[a] as usize, sorted[a]);
            let mut test = |b: usize| {
                let j = order[b] as usize;
                if discs_overlap(&centres[i], &centres[j], r, r) {
                    self.touching_next.push((i.min(j) as u32, i.max(j) as u32));
                }
            };
            // Own cell (later robots) and the cell to the right.
            let mut b = a + 1;
            while b < n && sorted[b] <= k + 1 {
                test(b);
                b += 1;
            }
            // The three cells of the next row; their window only moves forward with `a`.
            let lo = k + kw - 1;
            while below < n && sorted[below] < lo {
                below += 1;
            }
            let mut b = below;
            while b < n && sorted[b] <= k + kw + 1 {
                test(b);
                b += 1;
            }
        }
        self.touching_next.sort_unstable();
        for &(i, j) in &self.touching_next {
            if self.touching.binary_search(&(i, j)).is_err() {
                out.push(Collision {
                    time_ns,
                    robot: i,
                    hit: Hit::Robot(j),
                    position: centres[i as usize],
                    other_position: centres[j as usize],
                });
            }
        }
        std::mem::swap(&mut self.touching, &mut self.touching_next);
        out.len() - before
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disc_and_cell_geometry() {
        let p = Point2::new;
        assert!(discs_overlap(&p(0.0, 0.0), &p(0.1, 0.0), 0.058, 0.058));
        assert!(!discs_overlap(&p(0.0, 0.0), &p(0.12, 0.0), 0.058, 0.058));
        // Cell (1, 0) spans x in [0.12, 0.24).
        assert!(disc_overlaps_cell(&p(0.07, 0.06), 0.058, 1, 0, 0.12));
        assert!(!disc_overlaps_cell(&p(0.06, 0.06), 0.058, 1, 0, 0.12));
        assert_eq!(cell_centre_point(-1, 2, 0.12), p(-0.06, 0.3));
    }

    #[test]
    fn contact_is_recorded_once_when_it_begins() {
        let grid = Grid::new(10, 10).unwrap();
        let mut d = Detector::new(2, &grid, 0.12, 0.058);
        let mut out = Vec::new();
        let ps = [Point2::new(0.5, 0.5), Point2::new(0.6, 0.5)];
        assert_eq!(d.check(&grid, &ps, 1, &mut out), 1);
        assert_eq!(d.check(&grid, &ps, 2, &mut out), 0);
        assert_eq!(out[0].hit, Hit::Robot(1));
        assert_eq!((out[0].time_ns, out[0].robot), (1, 0));
        assert_eq!((out[0].position, out[0].other_position), (ps[0], ps[1]));
        // Outside the grid counts as blocked.
        let ps = [Point2::new(0.03, 0.54), Point2::new(0.6, 0.54)];
        let n = d.check(&grid, &ps, 3, &mut out);
        assert_eq!(n, 1);
        assert_eq!(out[1].hit, Hit::Cell(-1, 4));
        assert_eq!(out[1].position, ps[0]);
        assert_eq!(out[1].other_position, cell_centre_point(-1, 4, 0.12));
    }

    #[test]
    fn broad_phase_finds_exactly_the_brute_force_pairs() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let grid = Grid::new(12, 9).unwrap();
        let (cell, r) = (0.12, 0.058);
        for round in 0..50 {
            let n = 60;
            // Some robots off the grid too, where cells clamp.
            let ps: Vec<_> = (0..n)
                .map(|_| Point2::new(rng.gen_range(-0.3..1.7), rng.gen_range(-0.3..1.3)))
                .collect();
            let mut d = Detector::new(n, &grid, cell, r);
            let mut out = Vec::new();
            d.check(&grid, &ps, 0, &mut out);
            let mut got: Vec<_> = out
                .iter()
                .filter_map(|c| match c.hit {
                    Hit::Robot(j) => Some((c.robot, j)),
                    Hit::Cell(..) | Hit::Mover(_) => None,
                })
                .collect();
            got.sort_unstable();
            let mut want = Vec::new();
            for i in 0..n {
                for j in i + 1..n {
                    if discs_overlap(&ps[i], &ps[j], r, r) {
                        want.push((i as u32, j as u32));
                    }
                }
            }
            assert_eq!(got, want, "round {round}");
        }
    }
}
