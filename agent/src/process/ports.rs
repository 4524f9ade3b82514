//! The agent's ports: the topics one agent process reads and writes.

use hnav_runtime::grid::Grid;
use hnav_runtime::launch::LifecyclePorts;
use hnav_runtime::msg::{
    Candidate, Commit, Estimate, MapHeader, Odometry, Role, Sighting, View, WheelCommand,
    WorldHeader,
};
use hnav_runtime::topics;
use hnav_runtime::transport::{
    Bell, BellWatch, Receiver, Sender, SliceReceiver, SliceSender, Transport, TransportError,
};

/// The topics of agent `index`: its odometry and the commits in, its wheel commands,
/// candidates, neural-map snapshots and dead-reckoned poses out, and its side of the lifecycle protocol.
pub(super) struct Ports {
    pub(super) odom: Receiver<Odometry>,
    /// The robot's sensor view, when the scenario senses (`[sensing]`).
    pub(super) view: Option<Receiver<View>>,
    /// The cells the robot saw change, to the coordinator (with `[sensing]`).
    pub(super) sightings: Option<Sender<Sighting>>,
    /// The coordinator's map as it stands, sent when this agent restarted (with `[sensing]`).
    pub(super) world: Option<SliceReceiver<u32, WorldHeader>>,
    pub(super) commit: Receiver<Commit>,
    /// The run's commit bell, watched in place of a datagram per commit (under a supervisor).
    pub(super) bell: Option<BellWatch>,
    pub(super) wheels: Sender<WheelCommand>,
    pub(super) candidates: Sender<Candidate>,
    pub(super) map: SliceSender<f32, MapHeader>,
    pub(super) estimate: Sender<Estimate>,
    pub(super) life: LifecyclePorts,
}

impl Ports {
    /// Opens the ports of agent `index` in a swarm of `agents` on `grid` (with its view if
    /// `sensing`); `Up` is announced later, by the handshake in
    /// [`AgentProcess::run`](super::AgentProcess::run).
    pub(super) fn open(
        transport: &Transport,
        grid: &Grid,
        (index, agents): (u32, usize),
        sensing: bool,
    ) -> Result<Self, TransportError> {
        let i = index as usize;
        // With a bell the commit listener is one the coordinator does not send datagrams to;
        // it still reports a coordinator that appears or dies.
        let bell = Bell::from_env()?;
        let commit = match bell {
            Some(_) => transport.bell_receiver(topics::COMMIT, topics::commit_qos(agents))?,
            None => transport.receiver(topics::COMMIT, topics::commit_qos(agents))?,
        };
        Ok(Self {
            odom: transport.receiver(&topics::odometry(i), topics::state_qos())?,
            view: sensing
                .then(|| transport.receiver(&topics::view(i), topics::state_qos()))
                .transpose()?,
            sightings: sensing
                .then(|| transport.sender(topics::SIGHTINGS, topics::candidates_qos(agents)))
                .transpose()?,
            world: sensing
                .then(|| transport.slice_receiver(topics::WORLD, topics::world_qos(agents)))
                .transpose()?,
            commit,
            bell: bell.map(Bell::into_watch).transpose()?,
            wheels: transport.sender(&topics::wheels(i), topics::state_qos())?,
            candidates: transport.sender(topics::CANDIDATES, topics::candidates_qos(agents))?,
            map: transport.slice_sender(&topics::map(i), grid.len(), topics::state_qos())?,
            estimate: transport.sender(topics::ESTIMATE, topics::estimate_qos(agents))?,
            life: LifecyclePorts::open(transport, Role::Agent, index, agents)?,
        })
    }
}
