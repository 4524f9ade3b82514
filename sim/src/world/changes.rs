//! The world's changes during a run (`[[events]]` of the scenario): cells that close or
//! open, and moving obstacles (a person, a forklift) that HNAV does not control.
//!
//! The sim owns the truth, so it alone applies them, at the first step at or after each
//! event's time, from the scenario and the sim time only: a lockstep run with events is as
//! reproducible as one without, and a restarted sim catches up to its checkpoint's time (and
//! takes how far each mover walked from the checkpoint). A closed cell is a blocked cell of
//! the sim's grid, so a robot that enters one is a wall contact (`Hit::Cell`); a mover is a
//! disc of the robots' body radius at its point of the path, and a robot touching one is a
//! `Hit::Mover` contact, recorded when it begins as robot contacts are (a contact in progress
//! when the sim restarts is recorded again).
//!
//! **Who yields.** A person or a forklift driver stops for a robot in the way, so a mover that
//! yields (the default) waits at a cell centre while the next cell of its path is *claimed*
//! by a robot: the robot's disc overlaps it, or the robot is in motion (its wheels turn or are
//! commanded to) with its centre within one move (straight or diagonal) of that cell's
//! centre, about to enter it. It
//! looks only at cell centres, where it stands wholly in one cell: once it has set off into a
//! cell it walks through. The robots keep the other half of the bargain (the agent's rule,
//! `agent/src/navigator/movers.rs`): the view marks the cells a mover holds (see
//! [`Changes::moving_cells`]), and a robot asks for none of them nor for a cell next to one
//! (where a mover may go next), and does not set off into a held one. A robot in motion
//! claims the cell it enters, so a mover that yields never walks into a robot's way; a robot
//! standing next to a mover's next cell does not claim it, so the mover passes it, a cell
//! away (with the default body, two radii are 0.725 cell: robots a cell apart do not touch).
//! A mover that walks back and forth and has waited [`TURN_BACK_S`] turns back: the robot it
//! waits for may itself be waiting for the mover to leave (pushed into the mover's cell by
//! the coordinator, or head-on in a one-cell corridor), and a person would give way. At an
//! end of its path turning back is the way it waits for, so there it steps off the floor
//! instead (a person steps out of the aisle's end) and comes back on at that cell once no
//! robot claims it or the cell it walks to next: a robot that waits for it to leave, a cell
//! away, is otherwise held for good (robot 6 and walker 0 of the 50-robot dynamic
//! experiment). A mover with `yields = false` walks on regardless.

use hnav_runtime::scenario::{EventSpec, MoverSpec, WorldChange};
use nalgebra::Point2;

use crate::collision::{disc_overlaps_cell, discs_overlap, Collision, Hit};
use hnav_runtime::grid::{Cell, Grid};

/// A mover that has appeared.
#[derive(Debug, Clone)]
struct Active {
    spec: MoverSpec,
    /// Cells walked along its path so far (every return counted).
    walked: f64,
    /// The time it was moved to last, s.
    moved_s: f64,
    /// How long it has waited at its cell centre, s.
    waited_s: f64,
    /// Per robot: touching it at the last step.
    touching: Vec<bool>,
    /// On the floor: a mover that yields comes on at its first cell only when no robot
    /// claims that cell (a person waits at the aisle's end for a robot to pass); until then
    /// it is nowhere: no contact, no view, no moving cell.
    on_floor: bool,
    /// Off the floor after waiting at an end of its path (see the module docs): it comes
    /// back on at its cell once no robot claims that cell or the next.
    stepped_off: bool,
    /// Where it is now, m.
    at: Point2<f64>,
}

/// The robots as a mover sees them at one step.
pub(crate) struct Robots<'a> {
    /// Centres, m.
    pub(crate) centres: &'a [Point2<f64>],
    /// Whether each is in motion (its wheels turn or are commanded to).
    pub(crate) in_motion: &'a [bool],
    /// Body radius, m.
    pub(crate) radius: f64,
    /// Cell edge, m.
    pub(crate) cell: f64,
}

impl Robots<'_> {
    /// Whether a robot is in cell `c` or about to enter it (in motion, one move, straight or
    /// diagonal, from its centre).
    fn claim(&self, c: Cell) -> bool {
        let (x, y) = (i64::from(c.x), i64::from(c.y));
        let centre = Point2::new(
            (f64::from(c.x) + 0.5) * self.cell,
            (f64::from(c.y) + 0.5) * self.cell,
        );
        // One move away, straight or diagonal.
        let near = self.cell * (std::f64::consts::SQRT_2 + 1e-6);
        self.centres.iter().zip(self.in_motion).any(|(p, &moving)| {
            disc_overlaps_cell(p, self.radius, x, y, self.cell)
                || (moving && (p - centre).norm_squared() <= near * near)
        })
    }
}

/// How long a mover that yields and walks back and forth waits for a robot before it turns
/// back, s: a robot committed to the cell it stands in may be waiting for it to leave (a
/// robot pushed there by the coordinator, or one in a one-cell corridor), and one of the two
/// must give way.
pub(crate) const TURN_BACK_S: f64 = 3.0;

impl Active {
    /// Walks the other way from its cell centre: the same cell of its back-and-forth path,
    /// the other direction.
    fn turn_back(&mut self) {
        let period = 2 * (self.spec.cells.len() as u64 - 1);
        if period == 0 {
            return;
        }
        let k = self.walked as u64 % period;
        self.walked += ((period - k) % period) as f64 - k as f64;
        self.waited_s = 0.0;
        tracing::info!(mover = self.spec.name, "mover turned back");
    }

    /// Whether it stands at an end of its back-and-forth path, where turning back is the
    /// way it came.
    fn at_an_end(&self) -> bool {
        let period = 2 * (self.spec.cells.len() as u64).saturating_sub(1);
        period > 0 && self.walked.fract() == 0.0 && (self.walked as u64).is_multiple_of(period / 2)
    }

    /// Steps off the floor where it stands (see the module docs).
    fn step_off(&mut self, t_s: f64) {
        self.on_floor = false;
        self.stepped_off = true;
        self.waited_s = 0.0;
        self.moved_s = t_s;
        tracing::info!(
            mover = self.spec.name,
            t_s,
            "mover stepped off at its path's end"
        );
    }

    /// Walks on to `t_s`, waiting at a cell centre while a robot claims the next cell if it
    /// yields. It stops at every centre it reaches, so it looks there before going on.
    fn walk(&mut self, t_s: f64, robots: &Robots<'_>) {
        let mut left = (t_s - self.moved_s).max(0.0) * self.spec.speed;
        self.moved_s = t_s;
        let end = self.spec.end().unwrap_or(f64::INFINITY);
        while left > 0.0 && self.walked < end {
            let from = self.walked.floor();
            let ahead = self.spec.cell_at(from as u64 + 1);
            if self.walked == from && self.spec.yields && robots.claim(ahead) {
                if self.waited_s == 0.0 {
                    let (x, y) = (ahead.x, ahead.y);
                    tracing::info!(mover = self.spec.name, x, y, t_s, "mover waits for a robot");
                }
                self.waited_s += left / self.spec.speed;
                match (
                    self.spec.repeat && self.waited_s >= TURN_BACK_S,
                    self.at_an_end(),
                ) {
                    (true, true) => self.step_off(t_s),
                    (true, false) => self.turn_back(),
                    (false, _) => {}
                }
                return;
            }
            self.waited_s = 0.0;
            let to = from + 1.0;
            let step = (to - self.walked).min(left);
            left -= step;
            self.walked += step;
            if to - self.walked < 1e-12 {
                self.walked = to;
            }
        }
    }
}

/// The scenario's events, those applied so far and the movers under way.
#[derive(Debug, Clone, Default)]
pub(crate) struct Changes {
    events: Vec<EventSpec>,
    /// The first event not applied yet.
    next: usize,
    movers: Vec<Active>,
}

impl Changes {
    pub(crate) fn new(events: Vec<EventSpec>) -> Self {
        Changes {
            events,
            next: 0,
            movers: Vec::new(),
        }
    }

    /// Whether there is nothing to do now or later (no events).
    pub(crate) fn is_empty(&self) -> bool {
        self.events.is_empty()
    }

    /// Applies the events due by `t_s` to `grid`, in order; returns whether a cell changed
    /// (the collision detector's table of open cells must then be rebuilt).
    pub(crate) fn apply_due(&mut self, t_s: f64, grid: &mut Grid, robots: usize) -> bool {
        let mut cells_changed = false;
        while let Some(e) = self.events.get(self.next).filter(|e| e.at_s <= t_s + 1e-9) {
            match &e.change {
                WorldChange::Close(cells) | WorldChange::Open(cells) => {
                    let close = matches!(e.change, WorldChange::Close(_));
                    for &c in cells {
                        grid.set_blocked(c, close);
                    }
                    tracing::info!(t_s, close, cells = cells.len(), "world changed");
                    cells_changed = true;
                }
                WorldChange::Mover(m) => {
                    tracing::info!(t_s, mover = m.name, "mover appeared");
                    self.movers.push(Active {
                        spec: m.clone(),
                        walked: 0.0,
                        moved_s: e.at_s,
                        waited_s: 0.0,
                        touching: vec![false; robots],
                        at: Point2::origin(),
                        on_floor: false,
                        stepped_off: false,
                    });
                }
            }
            self.next += 1;
        }
        cells_changed
    }

    /// Moves the movers to time `t_s` (a mover that yields waits for the robots that claim
    /// its next cell) and appends the contacts with the robots (discs of their body radius)
    /// that began now. Returns how many.
    pub(crate) fn mover_contacts(
        &mut self,
        t_s: f64,
        time_ns: u64,
        robots: &Robots<'_>,
        out: &mut Vec<Collision>,
    ) -> usize {
        let before = out.len();
        let (r, cell) = (robots.radius, robots.cell);
        for (k, m) in self.movers.iter_mut().enumerate() {
            if !m.on_floor {
                let here = m.walked.floor() as u64;
                let (first, ahead) = (m.spec.cell_at(here), m.spec.cell_at(here + 1));
                let claimed = robots.claim(first) || (m.stepped_off && robots.claim(ahead));
                if m.spec.yields && claimed {
                    // moved_s is -1 once it has said that it waits (it restarts at entry).
                    if m.moved_s >= 0.0 {
                        let (x, y) = (first.x, first.y);
                        tracing::info!(mover = m.spec.name, x, y, t_s, "mover waits to come on");
                        m.moved_s = -1.0;
                    }
                    continue;
                }
                m.on_floor = true;
                m.stepped_off = false;
                m.moved_s = t_s;
                tracing::info!(mover = m.spec.name, t_s, "mover came on");
            }
            m.walk(t_s, robots);
            if !m.on_floor {
                m.touching.iter_mut().for_each(|t| *t = false);
                continue;
            }
            let (x, y) = m.spec.point_at(m.walked);
            m.at = Point2::new((x + 0.5) * cell, (y + 0.5) * cell);
            for (i, p) in robots.centres.iter().enumerate() {
                let touching = discs_overlap(p, &m.at, r, r);
                if touching && !m.touching[i] {
                    out.push(Collision {
                        time_ns,
                        robot: i as u32,
                        hit: Hit::Mover(k as u32),
                        position: *p,
                        other_position: m.at,
                    });
                }
                m.touching[i] = touching;
            }
        }
        out.len() - before
    }

    /// The movers under way: name and centre (m), in the order they appeared.
    pub(crate) fn movers(&self) -> impl Iterator<Item = (&str, Point2<f64>)> {
        self.on_floor().map(|(_, m)| (m.spec.name.as_str(), m.at))
    }

    /// The movers on the floor, with their index (in the order they appeared).
    fn on_floor(&self) -> impl Iterator<Item = (usize, &Active)> {
        self.movers.iter().enumerate().filter(|(_, m)| m.on_floor)
    }

    /// The `n`-th mover on the floor: its index (in the order the movers appeared), its
    /// centre (m) and its heading along the leg it walks (rad, 0 along +x; 0 on a path of
    /// one cell).
    pub(crate) fn mover_pose(&self, n: usize) -> Option<(usize, Point2<f64>, f64)> {
        let (k, m) = self.on_floor().nth(n)?;
        let leg = m.walked.floor() as u64;
        let (a, b) = (m.spec.cell_at(leg), m.spec.cell_at(leg + 1));
        let (dx, dy) = (
            f64::from(b.x) - f64::from(a.x),
            f64::from(b.y) - f64::from(a.y),
        );
        let heading = if dx == 0.0 && dy == 0.0 {
            0.0
        } else {
            dy.atan2(dx)
        };
        Some((k, m.at, heading))
    }

    /// How many movers are on the floor.
    pub(crate) fn movers_on_floor(&self) -> usize {
        self.on_floor().count()
    }

    /// The cells the movers hold, which the views mark moving: the cell a mover stands in
    /// at a centre, or the two of the leg it walks (the one it leaves and the one it
    /// enters). The cells next to those are where a mover may go next; the agents keep out
    /// of them too (`agent/src/navigator/movers.rs`).
    pub(crate) fn moving_cells(&self) -> impl Iterator<Item = Cell> + '_ {
        self.on_floor().flat_map(|(_, m)| {
            let (from, to) = (m.walked.floor() as u64, m.walked.ceil() as u64);
            (from..=to).map(|k| m.spec.cell_at(k))
        })
    }

    /// How far each mover under way has walked and how long it has waited, for the sim's
    /// checkpoint; a mover not on the floor yet has walked -1, one that stepped off after
    /// walking `w` -(w + 2) (a walk is never negative).
    pub(crate) fn walked(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.movers.iter().map(|m| {
            let w = match (m.on_floor, m.stepped_off) {
                (true, _) => m.walked,
                (false, false) => -1.0,
                (false, true) => -(m.walked + 2.0),
            };
            (w, m.waited_s)
        })
    }

    /// Takes how far each mover walked and how long it waited from a checkpoint taken at
    /// `t_s`; false if the count is not that of the movers under way.
    pub(crate) fn restore_walked(&mut self, walked: &[(f64, f64)], t_s: f64, cell: f64) -> bool {
        if walked.len() != self.movers.len() {
            return false;
        }
        for (m, &(w, waited)) in self.movers.iter_mut().zip(walked) {
            m.on_floor = w >= 0.0;
            m.stepped_off = w <= -2.0;
            let w = if m.stepped_off { -w - 2.0 } else { w.max(0.0) };
            m.walked = w;
            m.waited_s = waited;
            m.moved_s = t_s;
            let (x, y) = m.spec.point_at(w);
            m.at = Point2::new((x + 0.5) * cell, (y + 0.5) * cell);
        }
        true
    }
}
