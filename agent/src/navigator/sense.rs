//! What the agent learns from its robot's view (`[sensing]`): cells that closed or opened
//! since its map was built, and the repair of its guide (§2.10).
//!
//! The view is the sim's truth within range and in line of sight. A cell seen blocked that
//! the agent's grid has free closed (a door, a pallet); one seen free that the grid has
//! blocked opened, unless it is a standing robot the agent learned (those are not in the
//! view: robots are known through the decision round). The cells the robot stands on,
//! drives to or heads for are never closed in its own grid. A cell seen moving (a mover holds
//! it) is neither: it says nothing about the map (`movers.rs`).
//!
//! The repair, for the neural map:
//! - **rebuild** (§2.10 Б, a new map from zero) when a cell opened (partial correction only
//!   adds obstacles), when `repair = "rebuild"`, or, with `repair = "auto"`, when a closed
//!   cell lies on the path the map leads the robot along now (§2.10: "Б rebuilds only then");
//! - **partial correction** (§2.10 A: the closed cells' neurons zeroed and
//!   [`PARTIAL_SWEEPS`] more sweeps from the current map) otherwise: a change beside the way
//!   bends the potential, which is all the robot needs.
//!
//! A route follower (PSO, GA) replans its route when a closed cell cuts it or a cell opens.

use std::time::Instant;

use hnav_runtime::grid::Cell;
use hnav_runtime::msg::View;
use hnav_runtime::scenario::RepairRule;

use super::{Guide, Navigator};
use crate::error::Error;

/// Sweeps of a partial correction: §2.10's larger example (Fig. 2-17 shows 1 and 5).
pub const PARTIAL_SWEEPS: u32 = 5;

/// How a guide was repaired.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RepairKind {
    /// §2.10 A.
    Partial,
    /// §2.10 Б.
    Rebuild,
    /// A route planner's new route.
    Replan,
}

/// One repair: what changed, what was done, how long it took.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Repair {
    /// Cells that closed.
    pub closed: usize,
    /// Cells that opened.
    pub opened: usize,
    /// What was done.
    pub kind: RepairKind,
    /// How long it took, µs.
    pub micros: u64,
}

impl Navigator {
    /// Folds `view` into the agent's grid and repairs the guide if a cell changed; returns
    /// the repair (none: the view matched the grid).
    pub fn sense(&mut self, view: &View, rule: RepairRule) -> Result<Option<Repair>, Error> {
        self.note_movers(view);
        // A mover's cells are transient, not a change of the map (`movers.rs`).
        let seen = view
            .cells()
            .filter(|&(x, y, _)| !view.is_moving(x, y))
            .map(|(x, y, blocked)| (Cell::new(x, y), blocked));
        self.learn(seen, rule, view.period)
    }

    /// Folds cells whose state is known (`(cell, blocked)`: seen at control period `period`,
    /// or the coordinator's map for a restarted agent) into the agent's grid and repairs the
    /// guide if one changed; returns the repair (none: nothing changed).
    pub fn learn(
        &mut self,
        cells: impl Iterator<Item = (Cell, bool)>,
        rule: RepairRule,
        period: u64,
    ) -> Result<Option<Repair>, Error> {
        let keep = [self.current, self.next, self.target];
        let (mut closed, mut opened) = (Vec::new(), Vec::new());
        for (c, blocked) in cells {
            if !self.grid.contains(c) || keep.contains(&c) {
                continue;
            }
            match (blocked, self.grid.is_blocked(c)) {
                (true, false) => closed.push(c),
                (false, true) if !self.learned.contains(&c) => opened.push(c),
                _ => {}
            }
        }
        if closed.is_empty() && opened.is_empty() {
            return Ok(None);
        }
        let started = Instant::now();
        for &c in &closed {
            self.grid.set_blocked(c, true);
        }
        for &c in &opened {
            self.grid.set_blocked(c, false);
        }
        let (from, target) = (self.next, self.target);
        let kind = match &mut self.guide {
            Guide::Climb(climb) => {
                let opened = !opened.is_empty();
                climb.repair(&self.grid, &closed, opened, (from, target), rule)?
            }
            Guide::Follow(f) => {
                if !opened.is_empty() || closed.iter().any(|&c| f.crosses(c)) {
                    f.plan(&self.grid, from, target);
                }
                RepairKind::Replan
            }
        };
        self.replanned = true;
        let repair = Repair {
            closed: closed.len(),
            opened: opened.len(),
            kind,
            micros: started.elapsed().as_micros() as u64,
        };
        tracing::info!(
            agent = self.task.index,
            period,
            closed = repair.closed,
            opened = repair.opened,
            kind = ?repair.kind,
            us = repair.micros,
            "repair"
        );
        Ok(Some(repair))
    }
}
