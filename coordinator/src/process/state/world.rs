//! The coordinator's side of the shared picture (`[sensing]`): the agents' sightings kept
//! until the round they precede is decided, and the restarted agents waiting for the map as
//! it stands.
//!
//! A sighting is stamped with the round of the candidate it was sent before, so a lockstep
//! round is decided on exactly the sightings sent before its candidates, whatever the
//! scheduling: the log stays a function of the scenario. Sightings of a later round wait.

use hnav_runtime::msg::{Sighting, WorldHeader};

use crate::process::error::CoordinatorError;
use crate::process::ports::Ports;
use crate::round::Arbiter;

/// Sightings waiting for their round, and agents waiting for the map.
#[derive(Default)]
pub(super) struct World {
    sightings: Vec<Sighting>,
    /// Restarted agents not answered yet.
    asking: Vec<usize>,
    /// The map's changed cells, kept so that an answer allocates nothing once warm.
    cells: Vec<u32>,
}

impl World {
    /// Agent `agent` (of `agents`) restarted: it gets the map as it stands.
    pub(super) fn asked_by(&mut self, agent: usize, agents: usize) {
        if agent < agents && !self.asking.contains(&agent) {
            self.asking.push(agent);
        }
    }

    /// Takes every sighting in; one naming an agent not in the run is dropped.
    pub(super) fn collect(&mut self, p: &Ports, agents: usize) -> Result<(), CoordinatorError> {
        let Some(rx) = &p.sightings else {
            return Ok(());
        };
        rx.drain(|s| {
            if (s.agent as usize) < agents {
                self.sightings.push(*s);
            } else {
                tracing::warn!(
                    agent = s.agent,
                    "a sighting of an agent not in the run: dropped"
                );
            }
        })?;
        Ok(())
    }

    /// Per agent (ascending), the cells it saw change before `round`'s candidate or earlier,
    /// oldest first; later sightings stay.
    pub(super) fn take_due(&mut self, round: u64) -> Vec<(u32, Vec<(u32, bool)>)> {
        let mut due: Vec<(u32, Vec<(u32, bool)>)> = Vec::new();
        if self.sightings.is_empty() {
            return due;
        }
        // Stable: each agent's sightings keep the order it sent them in.
        self.sightings.sort_by_key(|s| s.agent);
        for s in self.sightings.iter().filter(|s| s.round <= round) {
            match due.last_mut() {
                Some((a, cells)) if *a == s.agent => cells.extend(s.changes()),
                _ => due.push((s.agent, s.changes().collect())),
            }
        }
        self.sightings.retain(|s| s.round > round);
        due
    }

    /// Sends the map as it stands after `round` to the agents that asked, in one sample.
    pub(super) fn answer(
        &mut self,
        p: &Ports,
        arbiter: &Arbiter,
        round: u64,
    ) -> Result<(), CoordinatorError> {
        let Some(tx) = &p.world else {
            self.asking.clear();
            return Ok(());
        };
        if self.asking.is_empty() {
            return Ok(());
        }
        let closed = arbiter.world(&mut self.cells);
        let words = WorldHeader::words_for(arbiter.agents());
        let mut loan = tx.loan(words + self.cells.len())?;
        *loan.header_mut() = WorldHeader {
            round,
            closed: closed as u32,
            opened: (self.cells.len() - closed) as u32,
            to: words as u32,
            reserved: 0,
        };
        let (asking, cells) = (&self.asking, &self.cells);
        loan.fill_with(0, |slice| {
            let (to, rest) = slice.split_at_mut(words);
            asking.iter().for_each(|&a| WorldHeader::address(to, a));
            rest.copy_from_slice(cells);
            Ok::<(), CoordinatorError>(())
        })?;
        tracing::info!(
            agents = ?self.asking,
            closed,
            opened = self.cells.len() - closed,
            round,
            "sent the map as it stands to restarted agents"
        );
        self.asking.clear();
        Ok(())
    }
}
