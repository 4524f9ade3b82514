//! The world's changes during a run (`[[events]]` of the scenario): cells that close or
//! open, and moving obstacles (a person, a forklift) that HNAV does not control.
//!
//! The sim owns the truth, so it alone applies them, at the first step at or after each
//! event's time, from the scenario and the sim time only: a lockstep run with events is as
//! reproducible as one without, and a restarted sim catches up to its checkpoint's time. A closed cell is a blocked cell of the sim's grid, so a robot that
//! enters one is a wall contact (`Hit::Cell`); a mover is a disc of the robots' body radius
//! at its point of the path, and a robot touching one is a `Hit::Mover` contact, recorded
//! when it begins as robot contacts are (a contact in progress when the sim restarts is
//! recorded again).

use hnav_runtime::scenario::{EventSpec, MoverSpec, WorldChange};
use nalgebra::Point2;

use crate::collision::{discs_overlap, Collision, Hit};
use hnav_runtime::grid::Grid;

/// A mover that has appeared.
#[derive(Debug, Clone)]
struct Active {
    spec: MoverSpec,
    /// When it appeared, s.
    from_s: f64,
    /// Per robot: touching it at the last step.
    touching: Vec<bool>,
    /// Where it is now, m.
    at: Point2<f64>,
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
                        from_s: e.at_s,
                        touching: vec![false; robots],
                        at: Point2::origin(),
                    });
                }
            }
            self.next += 1;
        }
        cells_changed
    }

    /// Moves the movers to time `t_s` and appends the contacts with the robots at `centres`
    /// (discs of radius `r`) that began now. Returns how many.
    pub(crate) fn mover_contacts(
        &mut self,
        t_s: f64,
        time_ns: u64,
        (centres, r, cell): (&[Point2<f64>], f64, f64),
        out: &mut Vec<Collision>,
    ) -> usize {
        let before = out.len();
        for (k, m) in self.movers.iter_mut().enumerate() {
            let (x, y) = m.spec.position(t_s - m.from_s);
            m.at = Point2::new((x + 0.5) * cell, (y + 0.5) * cell);
            for (i, p) in centres.iter().enumerate() {
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
}
