//! The agent process's ports: the topics it reads and writes, in two parts. [`Ports`] are the
//! process's (one commit subscriber, one candidate publisher, its side of the lifecycle
//! protocol, however many robots it hosts); [`RobotPorts`] are each robot's own topics.

use std::cell::Cell;

use hnav_runtime::grid::Grid;
use hnav_runtime::launch::LifecyclePorts;
use hnav_runtime::msg::{
    Candidate, Estimate, MapHeader, Odometry, Role, Sighting, View, WheelCommand, WorldHeader,
};
use hnav_runtime::topics::{self, CommitReceiver};
use hnav_runtime::transport::{
    Bell, BellWatch, Receiver, Sender, SliceReceiver, SliceSender, Transport, TransportError,
};

/// The topics the agent process shares between its robots: the commits and the
/// coordinator's map in, candidates and sightings out, and the lifecycle protocol.
pub(super) struct Ports {
    /// The cells the robots saw change, to the coordinator (with `[sensing]`).
    pub(super) sightings: Option<Sender<Sighting>>,
    /// The coordinator's map as it stands, sent when an agent restarted (with `[sensing]`).
    pub(super) world: Option<SliceReceiver<u32, WorldHeader>>,
    pub(super) commit: CommitReceiver,
    /// The run's commit bell, watched in place of a datagram per commit (under a supervisor).
    pub(super) bell: Option<BellWatch>,
    pub(super) candidates: Candidates,
    pub(super) life: LifecyclePorts,
}

/// The candidate publisher: every robot's candidates go out silently and the coordinator is
/// woken once per pass over the robots ([`Candidates::flush`]), not once per robot.
pub(super) struct Candidates {
    sender: Sender<Candidate>,
    unannounced: Cell<bool>,
}

impl Candidates {
    /// Publishes `c`; the coordinator learns of it at the next [`Candidates::flush`].
    pub(super) fn post(&self, c: Candidate) -> Result<(), TransportError> {
        self.sender.send_silently(c)?;
        self.unannounced.set(true);
        Ok(())
    }

    /// Wakes the coordinator if a candidate was posted since the last flush.
    pub(super) fn flush(&self) -> Result<(), TransportError> {
        if self.unannounced.replace(false) {
            self.sender.notify()?;
        }
        Ok(())
    }
}

/// The topics of one robot: its odometry (and view) in; its wheel commands, neural-map
/// snapshots and dead-reckoned poses out.
pub(super) struct RobotPorts {
    pub(super) odom: Receiver<Odometry>,
    /// The robot's sensor view, when the scenario senses (`[sensing]`).
    pub(super) view: Option<Receiver<View>>,
    pub(super) wheels: Sender<WheelCommand>,
    pub(super) map: SliceSender<f32, MapHeader>,
    /// One publisher per robot: the topic keeps each publisher's latest pose only.
    pub(super) estimate: Sender<Estimate>,
}

impl Ports {
    /// Opens the shared ports of the process whose first robot is `first`, in a swarm of
    /// `agents` (with the sensing topics if `sensing`); `Up` is announced later, by the
    /// handshake in [`AgentProcess::run`](super::AgentProcess::run).
    pub(super) fn open(
        transport: &Transport,
        (first, agents): (u32, usize),
        sensing: bool,
    ) -> Result<Self, TransportError> {
        // With a bell the commit listener is one the coordinator does not send datagrams to;
        // it still reports a coordinator that appears or dies.
        let bell = Bell::from_env()?;
        let commit = match bell {
            Some(_) => transport.slice_bell_receiver(topics::COMMIT, topics::commit_qos(agents))?,
            None => transport.slice_receiver(topics::COMMIT, topics::commit_qos(agents))?,
        };
        Ok(Self {
            sightings: sensing
                .then(|| transport.sender(topics::SIGHTINGS, topics::candidates_qos(agents)))
                .transpose()?,
            world: sensing
                .then(|| transport.slice_receiver(topics::WORLD, topics::world_qos(agents)))
                .transpose()?,
            commit,
            bell: bell.map(Bell::into_watch).transpose()?,
            candidates: Candidates {
                sender: transport.sender(topics::CANDIDATES, topics::candidates_qos(agents))?,
                unannounced: Cell::new(false),
            },
            life: LifecyclePorts::open(transport, Role::Agent, first, agents)?,
        })
    }
}

impl RobotPorts {
    /// Opens the topics of robot `index` of a swarm of `agents` on `grid` (with its view if
    /// `sensing`).
    pub(super) fn open(
        transport: &Transport,
        grid: &Grid,
        (index, agents): (u32, usize),
        sensing: bool,
    ) -> Result<Self, TransportError> {
        let i = index as usize;
        Ok(Self {
            odom: transport.receiver(&topics::odometry(i), topics::state_qos())?,
            view: sensing
                .then(|| transport.receiver(&topics::view(i), topics::state_qos()))
                .transpose()?,
            wheels: transport.sender(&topics::wheels(i), topics::state_qos())?,
            map: transport.slice_sender(&topics::map(i), grid.len(), topics::state_qos())?,
            estimate: transport.sender(topics::ESTIMATE, topics::estimate_qos(agents))?,
        })
    }
}
