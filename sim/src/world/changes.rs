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
//! commanded to) with its centre within one cell of that cell's centre, about to enter it. It
//! looks only at cell centres, where it stands wholly in one cell: once it has set off into a
//! cell it walks through. The robots keep the other half of the bargain (the agent's rule,
//! `agent/src/navigator/movers.rs`): the view marks the cells a mover holds and the cell
//! beyond the one it is entering (see [`Changes::moving_cells`]), and a robot does not set off
//! into a marked cell. A mover with `yields = false` walks on regardless.

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
    /// Per robot: touching it at the last step.
    touching: Vec<bool>,
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
    /// Whether a robot is in cell `c` or about to enter it (in motion, within one cell of its
    /// centre).
    fn claim(&self, c: Cell) -> bool {
        let (x, y) = (i64::from(c.x), i64::from(c.y));
        let centre = Point2::new(
            (f64::from(c.x) + 0.5) * self.cell,
            (f64::from(c.y) + 0.5) * self.cell,
        );
        let near = self.cell * (1.0 + 1e-6);
        self.centres.iter().zip(self.in_motion).any(|(p, &moving)| {
            disc_overlaps_cell(p, self.radius, x, y, self.cell)
                || (moving && (p - centre).norm_squared() <= near * near)
        })
    }
}

impl Active {
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
                return;
            }
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
                        touching: vec![false; robots],
                        at: Point2::origin(),
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
            m.walk(t_s, robots);
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
        self.movers.iter().map(|m| (m.spec.name.as_str(), m.at))
    }

    /// The cells the views mark moving: per mover, the cells of its path from the one it
    /// stands in or leaves to the one beyond the one it enters. A robot that sets off into
    /// none of them cannot meet a mover in the period it sets off in (a mover walks a cell
    /// in far more than a period), and once it is under way it claims the cell ahead, for
    /// which a mover that yields waits.
    pub(crate) fn moving_cells(&self) -> impl Iterator<Item = Cell> + '_ {
        self.movers.iter().flat_map(|m| {
            let from = m.walked.floor() as u64;
            let to = (m.walked + 1.0).ceil() as u64;
            (from..=to).map(|k| m.spec.cell_at(k))
        })
    }

    /// How far each mover under way has walked, for the sim's checkpoint.
    pub(crate) fn walked(&self) -> impl Iterator<Item = f64> + '_ {
        self.movers.iter().map(|m| m.walked)
    }

    /// Takes how far each mover walked from a checkpoint taken at `t_s`; false if the count
    /// is not that of the movers under way.
    pub(crate) fn restore_walked(&mut self, walked: &[f64], t_s: f64, cell: f64) -> bool {
        if walked.len() != self.movers.len() {
            return false;
        }
        for (m, &w) in self.movers.iter_mut().zip(walked) {
            m.walked = w;
            m.moved_s = t_s;
            let (x, y) = m.spec.point_at(w);
            m.at = Point2::new((x + 0.5) * cell, (y + 0.5) * cell);
        }
        true
    }
}
