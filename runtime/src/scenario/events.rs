//! `[[events]]`: a world that changes while the robots run (the dissertation's case for a
//! neural map that is repaired, seed 000 §2.1 criterion 6 and §2.10).
//!
//! ```toml
//! [[events]]               # a door closes at round 120 ...
//! at_round = 120           # or at_s = 1.2 (simulated seconds after Start)
//! close = [[5, 3]]         # cells that become obstacles; close_rect = [[x0, y0], [x1, y1]]
//!                          # closes a rectangle (corners included)
//!
//! [[events]]               # ... and opens again
//! at_s = 4.0
//! open = [[5, 3]]          # cells that become free: closed earlier, or walls of the map
//!                          # (a door drawn shut); open_rect likewise
//!
//! [[events]]               # a person or a forklift, never controlled by HNAV
//! at_s = 0.5
//! mover = "forklift"       # its name, unique
//! path = [[1, 1], [1, 8], [6, 8]]  # corners of a path of straight legs along rows or columns
//! speed = 0.5              # cells per second
//! repeat = true            # back and forth for ever (default: once, then it stays at the end)
//! yields = true            # waits at a cell centre while a robot is in or entering the next
//!                          # cell of its path (the default); false: walks on regardless
//! ```
//!
//! Each entry is exactly one change: `close`, `close_rect`, `open`, `open_rect` or `mover`
//! (with `path` and `speed`). Its time is `at_round` (the decision round, turned into
//! simulated time with the control period, as a fault's is) or `at_s`; the sim owns the world
//! and applies each change at the first step at or after that time, in lockstep as in
//! realtime, so a lockstep run with events stays reproducible byte for byte.
//!
//! Errors name the line: neither or both of `at_round` and `at_s`, a negative or infinite
//! `at_s`; an entry that is no change or two; entries out of time order; a cell off the map,
//! a rectangle whose corners are not ordered; closing a wall or a cell already closed, or a
//! robot's start (a robot would begin inside it); opening a free cell; a mover path with fewer
//! than two corners, a leg that is not along a row or a column, a cell of it on a wall (of
//! the map, or closed at that time) or on a robot's start, a speed that is not a positive
//! finite number, a name used twice.
//!
//! The entries are hashed only when there are some, so every earlier scenario keeps its hash.

use serde::Deserialize;
use toml::Spanned;

use super::error::{Loc, ScenarioError};
use super::fault_arg::check_at_s;
use super::lines::Lines;
use super::{AgentSpec, SimParams};
use crate::grid::{Cell, Grid};

/// A list of `[x, y]` as written, each with its place.
type RawCells = Spanned<Vec<Spanned<Vec<i64>>>>;

/// One `[[events]]` entry as `serde` sees it.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct RawEvent {
    pub at_round: Option<Spanned<u64>>,
    pub at_s: Option<Spanned<f64>>,
    pub close: Option<RawCells>,
    pub close_rect: Option<RawCells>,
    pub open: Option<RawCells>,
    pub open_rect: Option<RawCells>,
    pub mover: Option<Spanned<String>>,
    pub path: Option<RawCells>,
    pub speed: Option<Spanned<f64>>,
    pub repeat: Option<bool>,
    pub yields: Option<bool>,
}

/// One validated change of the world.
#[derive(Clone, PartialEq, Debug)]
pub struct EventSpec {
    /// When, in simulated seconds after `Start` (`at_round` times the control period).
    pub at_s: f64,
    /// What changes.
    pub change: WorldChange,
}

/// What an event changes.
#[derive(Clone, PartialEq, Debug)]
pub enum WorldChange {
    /// These cells become obstacles.
    Close(Vec<Cell>),
    /// These cells become free.
    Open(Vec<Cell>),
    /// A moving obstacle appears and follows its path.
    Mover(MoverSpec),
}

impl WorldChange {
    /// The cells a close or an open changes and whether they close; `None` for a mover,
    /// which changes no cell of the map.
    pub fn cells(&self) -> Option<(&[Cell], bool)> {
        match self {
            WorldChange::Close(c) => Some((c, true)),
            WorldChange::Open(c) => Some((c, false)),
            WorldChange::Mover(_) => None,
        }
    }
}

/// A moving obstacle: a person or a forklift that HNAV does not control.
#[derive(Clone, PartialEq, Debug)]
pub struct MoverSpec {
    /// Its name, for reports and contacts.
    pub name: String,
    /// Every cell it passes, in order: the legs between the corners written, each cell once.
    pub cells: Vec<Cell>,
    /// Cells per second.
    pub speed: f64,
    /// Back and forth for ever; otherwise once, then it stays at its last cell.
    pub repeat: bool,
    /// It waits for a robot in its way, as a person or a forklift driver does (the sim's
    /// rule, `sim/src/world/changes.rs`); `false`: it walks on regardless.
    pub yields: bool,
}

impl MoverSpec {
    /// Where it is `since_s` seconds after it appeared: a point in cell units (`x`, `y` of
    /// the cell centres), moving at `speed` along its cells,
    /// had it never waited.
    pub fn position(&self, since_s: f64) -> (f64, f64) {
        self.point_at(since_s.max(0.0) * self.speed)
    }

    /// Where it is after walking `walked` cells along its path (back and forth if it
    /// repeats, every return counted): a point in cell units.
    pub fn point_at(&self, walked: f64) -> (f64, f64) {
        let d = walked.clamp(0.0, self.end().unwrap_or(f64::MAX));
        let k = d.floor();
        let (a, b) = (self.cell_at(k as u64), self.cell_at(k as u64 + 1));
        let f = d - k;
        let lerp = |p: u32, q: u32| f64::from(p) + f * (f64::from(q) - f64::from(p));
        (lerp(a.x, b.x), lerp(a.y, b.y))
    }

    /// The `k`-th cell it passes (0: its first), counting every return of a repeating
    /// mover; a mover that does not repeat stays at its last cell.
    pub fn cell_at(&self, k: u64) -> Cell {
        let legs = (self.cells.len() - 1) as u64;
        let i = match (self.repeat, legs) {
            (_, 0) => 0,
            (true, _) => {
                let k = k % (2 * legs);
                if k > legs {
                    2 * legs - k
                } else {
                    k
                }
            }
            (false, _) => k.min(legs),
        };
        self.cells[i as usize]
    }

    /// How many cells it walks before it stops for good: none for a repeating mover.
    pub fn end(&self) -> Option<f64> {
        (!self.repeat || self.cells.len() < 2).then(|| (self.cells.len() - 1) as f64)
    }
}

/// Validates `[[events]]` against the map and the robots' starts, in time order.
pub(super) fn build_events(
    raw: Vec<Spanned<RawEvent>>,
    grid: &Grid,
    agents: &[AgentSpec],
    sim: &SimParams,
    lines: &Lines<'_>,
) -> Result<Vec<EventSpec>, ScenarioError> {
    let mut world = World {
        grid: grid.clone(),
        agents,
        movers: Vec::new(),
    };
    let mut events = Vec::with_capacity(raw.len());
    let mut last: Option<(f64, usize)> = None;
    for (i, entry) in raw.iter().enumerate() {
        let at = lines.at(entry);
        let e = entry.get_ref();
        let at_s = event_time(i, e, sim, lines, &at)?;
        if let Some((before, line)) = last.filter(|&(before, _)| at_s < before) {
            let p = format!(
                "happens at {at_s} s, before the event at line {line} ({before} s); \
                 list the events in time order"
            );
            return Err(bad(at, "events", p));
        }
        last = Some((at_s, at.line));
        let change = world.apply(i, e, lines, &at)?;
        events.push(EventSpec { at_s, change });
    }
    Ok(events)
}

fn bad(at: Loc, key: &str, problem: String) -> ScenarioError {
    ScenarioError::InvalidParameter {
        at,
        key: key.into(),
        problem,
    }
}

/// When event `i` happens, in simulated seconds: exactly one of `at_round` and `at_s`.
fn event_time(
    i: usize,
    e: &RawEvent,
    sim: &SimParams,
    lines: &Lines<'_>,
    at: &Loc,
) -> Result<f64, ScenarioError> {
    match (&e.at_round, &e.at_s) {
        (Some(r), None) => Ok(*r.get_ref() as f64 * sim.control_period_s()),
        (None, Some(s)) => {
            let secs = *s.get_ref();
            check_at_s(secs).map_err(|p| bad(lines.at(s), "events.at_s", p))?;
            Ok(secs)
        }
        (Some(_), Some(s)) => Err(bad(
            lines.at(s),
            "events.at_s",
            format!("event {i}: give one of `at_round` and `at_s`, not both"),
        )),
        (None, None) => Err(bad(
            at.clone(),
            "events",
            format!("event {i} needs `at_round` or `at_s`"),
        )),
    }
}

/// The world as the events so far left it, to check the next one against.
struct World<'a> {
    grid: Grid,
    agents: &'a [AgentSpec],
    movers: Vec<String>,
}

impl World<'_> {
    /// Event `i`'s change, checked against the world so far and applied to it.
    fn apply(
        &mut self,
        i: usize,
        e: &RawEvent,
        lines: &Lines<'_>,
        at: &Loc,
    ) -> Result<WorldChange, ScenarioError> {
        let kinds = [
            ("close", e.close.is_some()),
            ("close_rect", e.close_rect.is_some()),
            ("open", e.open.is_some()),
            ("open_rect", e.open_rect.is_some()),
            ("mover", e.mover.is_some()),
        ];
        let given: Vec<&str> = kinds.iter().filter(|k| k.1).map(|k| k.0).collect();
        if given.len() != 1 {
            let p = format!(
                "event {i} must be exactly one of close, close_rect, open, open_rect and mover; \
                 it gives {}",
                if given.is_empty() {
                    "none".to_string()
                } else {
                    given.join(" and ")
                }
            );
            return Err(bad(at.clone(), "events", p));
        }
        let mover_keys = [
            e.path.is_some(),
            e.speed.is_some(),
            e.repeat.is_some(),
            e.yields.is_some(),
        ];
        if e.mover.is_none() && mover_keys.contains(&true) {
            let p = format!("event {i}: `path`, `speed`, `repeat` and `yields` are for a `mover`");
            return Err(bad(at.clone(), "events", p));
        }
        let cells = |raw: &RawCells, key: &str, rect: bool| {
            if rect {
                rect_cells(raw, &self.grid, lines, key)
            } else {
                list_cells(raw, &self.grid, lines, key)
            }
        };
        if let Some(raw) = e.close.as_ref().or(e.close_rect.as_ref()) {
            let key = if e.close.is_some() {
                "events.close"
            } else {
                "events.close_rect"
            };
            let cells = cells(raw, key, e.close_rect.is_some())?;
            for &(c, ref at) in &cells {
                self.closable(c).map_err(|p| bad(at.clone(), key, p))?;
                self.grid.set_blocked(c, true);
            }
            return Ok(WorldChange::Close(cells.into_iter().map(|c| c.0).collect()));
        }
        if let Some(raw) = e.open.as_ref().or(e.open_rect.as_ref()) {
            let key = if e.open.is_some() {
                "events.open"
            } else {
                "events.open_rect"
            };
            let cells = cells(raw, key, e.open_rect.is_some())?;
            for &(c, ref at) in &cells {
                if !self.grid.is_blocked(c) {
                    let p = format!("({}, {}) is free already: nothing to open", c.x, c.y);
                    return Err(bad(at.clone(), key, p));
                }
                self.grid.set_blocked(c, false);
            }
            return Ok(WorldChange::Open(cells.into_iter().map(|c| c.0).collect()));
        }
        self.mover(i, e, lines, at).map(WorldChange::Mover)
    }

    /// Why cell `c` cannot be closed now, if it cannot.
    fn closable(&self, c: Cell) -> Result<(), String> {
        if self.grid.is_blocked(c) {
            return Err(format!("({}, {}) is a wall or closed already", c.x, c.y));
        }
        self.not_a_start(c)
    }

    fn not_a_start(&self, c: Cell) -> Result<(), String> {
        match self.agents.iter().position(|a| a.start == c) {
            Some(k) => Err(format!(
                "({}, {}) is agent {k}'s start: the robot would begin inside it",
                c.x, c.y
            )),
            None => Ok(()),
        }
    }

    /// The mover of event `i`, its path expanded and checked against the world now.
    fn mover(
        &mut self,
        i: usize,
        e: &RawEvent,
        lines: &Lines<'_>,
        at: &Loc,
    ) -> Result<MoverSpec, ScenarioError> {
        let name = e.mover.as_ref().expect("apply checked it");
        let name_at = lines.at(name);
        let name = name.get_ref().trim().to_string();
        if name.is_empty() {
            return Err(bad(name_at, "events.mover", "the name is empty".into()));
        }
        if self.movers.contains(&name) {
            let p = format!("a mover is named `{name}` already");
            return Err(bad(name_at, "events.mover", p));
        }
        let (Some(path), Some(speed)) = (&e.path, &e.speed) else {
            let p = format!("mover `{name}` (event {i}) needs `path` and `speed`");
            return Err(bad(at.clone(), "events", p));
        };
        let v = *speed.get_ref();
        if !(v.is_finite() && v > 0.0) {
            let p = format!("must be a positive number of cells per second, got {v}");
            return Err(bad(lines.at(speed), "events.speed", p));
        }
        let corners = list_cells(path, &self.grid, lines, "events.path")?;
        if corners.len() < 2 {
            let p = "needs at least two corners, [[x0, y0], [x1, y1]]".to_string();
            return Err(bad(lines.at(path), "events.path", p));
        }
        let mut cells = vec![corners[0].0];
        for pair in corners.windows(2) {
            let (a, (b, b_at)) = (pair[0].0, &pair[1]);
            let b = *b;
            if a.x != b.x && a.y != b.y || a == b {
                let p = format!(
                    "the leg from ({}, {}) to ({}, {}) is not along a row or a column",
                    a.x, a.y, b.x, b.y
                );
                return Err(bad(b_at.clone(), "events.path", p));
            }
            let (dx, dy) = (
                (b.x as i64 - a.x as i64).signum(),
                (b.y as i64 - a.y as i64).signum(),
            );
            let mut c = a;
            while c != b {
                c = Cell::new((c.x as i64 + dx) as u32, (c.y as i64 + dy) as u32);
                if self.grid.is_blocked(c) {
                    let p = format!("passes ({}, {}), a wall or a closed cell", c.x, c.y);
                    return Err(bad(b_at.clone(), "events.path", p));
                }
                self.not_a_start(c)
                    .map_err(|p| bad(b_at.clone(), "events.path", p))?;
                cells.push(c);
            }
        }
        let first = corners[0].0;
        if self.grid.is_blocked(first) {
            let p = format!(
                "starts on ({}, {}), a wall or a closed cell",
                first.x, first.y
            );
            return Err(bad(corners[0].1.clone(), "events.path", p));
        }
        self.not_a_start(first)
            .map_err(|p| bad(corners[0].1.clone(), "events.path", p))?;
        self.movers.push(name.clone());
        Ok(MoverSpec {
            name,
            cells,
            speed: v,
            repeat: e.repeat.unwrap_or(false),
            yields: e.yields.unwrap_or(true),
        })
    }
}

/// `[[x, y], ...]` as cells on the map, each with its line.
fn list_cells(
    raw: &RawCells,
    grid: &Grid,
    lines: &Lines<'_>,
    key: &str,
) -> Result<Vec<(Cell, Loc)>, ScenarioError> {
    if raw.get_ref().is_empty() {
        let p = "is empty; give at least one [x, y]".to_string();
        return Err(bad(lines.at(raw), key, p));
    }
    raw.get_ref()
        .iter()
        .map(|xy| {
            let at = lines.at(xy);
            on_map(xy.get_ref(), grid)
                .map(|c| (c, at.clone()))
                .map_err(|p| bad(at, key, p))
        })
        .collect()
}

/// `[[x0, y0], [x1, y1]]` as the cells of that rectangle, corners included, row by row.
fn rect_cells(
    raw: &RawCells,
    grid: &Grid,
    lines: &Lines<'_>,
    key: &str,
) -> Result<Vec<(Cell, Loc)>, ScenarioError> {
    let corners = list_cells(raw, grid, lines, key)?;
    let [(a, _), (b, ref b_at)] = corners.as_slice() else {
        let p = format!(
            "needs two corners, [[x0, y0], [x1, y1]]; got {}",
            corners.len()
        );
        return Err(bad(lines.at(raw), key, p));
    };
    if a.x > b.x || a.y > b.y {
        let p = format!(
            "the corners ({}, {}) and ({}, {}) are not top-left then bottom-right",
            a.x, a.y, b.x, b.y
        );
        return Err(bad(b_at.clone(), key, p));
    }
    let at = lines.at(raw);
    Ok((a.y..=b.y)
        .flat_map(|y| (a.x..=b.x).map(move |x| Cell::new(x, y)))
        .map(|c| (c, at.clone()))
        .collect())
}

/// `[x, y]` as a cell of `grid`, or what is wrong with it.
pub(super) fn on_map(xy: &[i64], grid: &Grid) -> Result<Cell, String> {
    let [x, y] = xy else {
        return Err(format!("a cell must be [x, y], got {} numbers", xy.len()));
    };
    let inside = |v: i64, n: u32| u32::try_from(v).ok().filter(|&v| v < n);
    match (inside(*x, grid.width()), inside(*y, grid.height())) {
        (Some(cx), Some(cy)) => Ok(Cell::new(cx, cy)),
        _ => Err(format!(
            "({x}, {y}) is outside the {}x{} map",
            grid.width(),
            grid.height()
        )),
    }
}
