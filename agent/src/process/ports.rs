//! The agent process's ports: the topics it reads and writes, in two parts. [`Ports`] are the
//! process's (one commit subscriber, one candidate publisher, its robots' odometry, views
//! and wheel commands, its side of the lifecycle protocol, however many robots it hosts);
//! [`RobotPorts`] are each robot's own topics.

use std::cell::Cell;

use hnav_runtime::grid::Grid;
use hnav_runtime::launch::LifecyclePorts;
use hnav_runtime::msg::{
    Candidate, Estimate, MapHeader, Role, Sighting, WheelCommand, WheelsHeader, WorldHeader,
};
use hnav_runtime::topics::{self, CommitReceiver, OdometryReceiver, ViewsReceiver, WheelsSender};
use hnav_runtime::transport::{
    Bell, BellWatch, Sender, SliceReceiver, SliceSender, Transport, TransportError,
};

/// The topics the agent process shares between its robots: the commits, the coordinator's
/// map and the robots' odometry and views in, candidates, sightings and wheel commands out,
/// and the lifecycle protocol.
pub(super) struct Ports {
    /// Every robot's odometry, one sample a control period.
    pub(super) odom: OdometryReceiver,
    /// Every robot's sensor view, when the scenario senses (`[sensing]`).
    pub(super) view: Option<ViewsReceiver>,
    pub(super) wheels: Wheels,
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

/// The wheel publisher: each robot posts its command when it is due, and the pass over the
/// robots sends every robot's latest in one sample ([`Wheels::flush`]). Every robot's, not
/// only the new ones: the sim's queue keeps the latest sample, and a robot whose command
/// went out in an older one must not lose it to a sample that names only the others.
pub(super) struct Wheels {
    sender: WheelsSender,
    first: u32,
    latest: Vec<Cell<Option<WheelCommand>>>,
    unsent: Cell<bool>,
}

impl Wheels {
    /// Records `c` as its robot's latest command; the sim gets it at the next
    /// [`Wheels::flush`].
    pub(super) fn post(&self, c: WheelCommand) {
        let slot = c.agent.checked_sub(self.first).map(|k| k as usize);
        if let Some(slot) = slot.and_then(|k| self.latest.get(k)) {
            slot.set(Some(c));
            self.unsent.set(true);
        }
    }

    /// Sends every robot's latest command if one was posted since the last flush.
    pub(super) fn flush(&self) -> Result<(), TransportError> {
        if !self.unsent.replace(false) {
            return Ok(());
        }
        let n = self.latest.iter().filter(|c| c.get().is_some()).count();
        let header = WheelsHeader {
            first: self.first,
            count: n as u32,
        };
        let mut posted = self.latest.iter().filter_map(Cell::get);
        self.sender
            .send_from_fn(header, n, |_| posted.next().unwrap_or_default())?;
        Ok(())
    }
}

/// The topics of one robot: its neural-map snapshots and dead-reckoned poses out.
pub(super) struct RobotPorts {
    pub(super) map: SliceSender<f32, MapHeader>,
    /// One publisher per robot: the topic keeps each publisher's latest pose only.
    pub(super) estimate: Sender<Estimate>,
}

impl Ports {
    /// Opens the shared ports of the process whose `count` robots start at `first`, in a
    /// swarm of `agents` (with the sensing topics if `sensing`); `Up` is announced later, by
    /// the handshake in [`AgentProcess::run`](super::AgentProcess::run).
    pub(super) fn open(
        transport: &Transport,
        (first, count, agents): (u32, u32, usize),
        sensing: bool,
    ) -> Result<Self, TransportError> {
        let (q, at) = (topics::state_qos(), first as usize);
        // With a bell the commit listener is one the coordinator does not send datagrams to;
        // it still reports a coordinator that appears or dies.
        let bell = Bell::from_env()?;
        let commit = match bell {
            Some(_) => transport.slice_bell_receiver(topics::COMMIT, topics::commit_qos(agents))?,
            None => transport.slice_receiver(topics::COMMIT, topics::commit_qos(agents))?,
        };
        Ok(Self {
            odom: transport.slice_receiver(&topics::odometry(at), q)?,
            view: sensing
                .then(|| transport.slice_receiver(&topics::view(at), q))
                .transpose()?,
            wheels: Wheels {
                sender: transport.slice_sender(&topics::wheels(at), count as usize, q)?,
                first,
                latest: (0..count).map(|_| Cell::new(None)).collect(),
                unsent: Cell::new(false),
            },
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
    /// Opens the topics of robot `index` of a swarm of `agents` on `grid`.
    pub(super) fn open(
        transport: &Transport,
        grid: &Grid,
        (index, agents): (u32, usize),
    ) -> Result<Self, TransportError> {
        let i = index as usize;
        Ok(Self {
            map: transport.slice_sender(&topics::map(i), grid.len(), topics::state_qos())?,
            estimate: transport.sender(topics::ESTIMATE, topics::estimate_qos(agents))?,
        })
    }
}
