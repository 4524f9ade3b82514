//! The coordinator's topics of the rounds: what it hears (candidates) and what it says
//! (commits, progress), and with `[sensing]` the shared picture of a changing world (the
//! agents' sightings in, the map as it stands out to restarted agents). The lifecycle ports with the supervisor are opened beside them, by
//! every replica; these only by the one that decides.

use hnav_runtime::msg::{Candidate, Progress, Sighting, WorldHeader};
use hnav_runtime::topics::{self, CommitSender};
use hnav_runtime::transport::{Bell, Receiver, Sender, SliceSender, Transport, TransportError};

/// The ports of the rounds: a single coordinator opens them before it announces itself, a
/// replica when it comes to lead.
pub(super) struct Ports {
    /// The agents' candidate steps.
    pub(super) candidates: Receiver<Candidate>,
    /// The decided rounds, to every agent: a slice of one decision per agent.
    pub(super) commit: CommitSender,
    /// The run's progress, for the supervisor (`hnav run`), `hnav top` and the bridge.
    pub(super) progress: Sender<Progress>,
    /// The cells the agents saw change (with `[sensing]`).
    pub(super) sightings: Option<Receiver<Sighting>>,
    /// The map as it stands, for restarted agents (with `[sensing]`).
    pub(super) world: Option<SliceSender<u32, WorldHeader>>,
}

impl Ports {
    /// Opens the ports of the coordinator of a swarm of `agents`, with the world's ports for
    /// a map of `world_cells` cells when the run senses (`[sensing]`): a sample of the world
    /// holds the addressees' bits and at most every cell of the map. Under a supervisor the
    /// commits ring the run's [`Bell`], which wakes every agent with one write.
    pub(super) fn open(
        transport: &Transport,
        agents: usize,
        world_cells: Option<usize>,
    ) -> Result<Self, TransportError> {
        // The candidates' subscriber first: creating the commit sender tells every agent that
        // a coordinator is up, and a restarted coordinator's agents answer with their open
        // candidate at once, which a subscriber created after that would never see.
        let candidates = transport.receiver(topics::CANDIDATES, topics::candidates_qos(agents))?;
        // Sightings go out just before their candidate: their subscriber comes first too.
        let sightings = world_cells
            .map(|_| transport.receiver(topics::SIGHTINGS, topics::candidates_qos(agents)))
            .transpose()?;
        let world = world_cells
            .map(|cells| {
                let len = WorldHeader::words_for(agents) + cells;
                transport.slice_sender(topics::WORLD, len, topics::world_qos(agents))
            })
            .transpose()?;
        let mut commit =
            transport.slice_sender(topics::COMMIT, agents, topics::commit_qos(agents))?;
        if let Some(bell) = Bell::from_env()? {
            commit = commit.ringing(bell);
        }
        Ok(Self {
            candidates,
            commit,
            progress: transport.sender(topics::PROGRESS, topics::progress_qos())?,
            sightings,
            world,
        })
    }
}
