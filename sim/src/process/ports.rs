//! The topics of the `hnav-sim` process: one wheel-command receiver and one odometry sender
//! (and, when the scenario senses, one view sender) per agent process, each carrying the
//! process's robots in one sample; the Truth sender and, when joined to the run's lifecycle
//! protocol, its ports.

use hnav_runtime::launch::LifecyclePorts;
use std::ops::Range;

use hnav_runtime::msg::{MoverPlace, MoversHeader};
use hnav_runtime::topics::{self, OdometrySender, TruthSender, ViewsSender, WheelsReceiver};
use hnav_runtime::transport::{Attachment, SliceSender, Transport, TransportError, Waiter};

/// The process's open ports. Kept apart from the [`State`](super::state::State) so that the
/// waiter's attachments can borrow the receivers while the loop mutates the state.
pub(crate) struct Ports {
    /// The agent processes: each one's first robot and how many it hosts, in order.
    pub(crate) processes: Vec<(u32, u32)>,
    /// Process `p`'s wheel commands.
    pub(crate) wheels: Vec<WheelsReceiver>,
    /// Process `p`'s odometry.
    pub(crate) odom: Vec<OdometrySender>,
    /// Process `p`'s sensor views (empty when the scenario senses nothing).
    pub(crate) view: Vec<ViewsSender>,
    /// Ground truth of every robot, once per control period.
    pub(crate) truth: TruthSender,
    /// Where the movers are, once per control period (a world with movers only).
    pub(crate) movers: Option<SliceSender<MoverPlace, MoversHeader>>,
    /// The lifecycle protocol's ports, if joined.
    pub(crate) life: Option<LifecyclePorts>,
}

impl Ports {
    /// Opens the topics of a world whose robots the agent `processes` host (each one's first
    /// robot and count, in order), with their views if `sensing` and the movers' places if it
    /// has `movers`.
    pub(crate) fn open(
        transport: &Transport,
        processes: Vec<(u32, u32)>,
        sensing: bool,
        movers: usize,
    ) -> Result<Self, TransportError> {
        let q = topics::state_qos();
        let robots = processes.iter().map(|&(_, n)| n as usize).sum::<usize>();
        let wheels = (processes.iter())
            .map(|&(first, _)| transport.slice_receiver(&topics::wheels(first as usize), q))
            .collect::<Result<Vec<_>, _>>()?;
        let odom = (processes.iter())
            .map(|&(first, n)| {
                transport.slice_sender(&topics::odometry(first as usize), n as usize, q)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let views = if sensing { processes.len() } else { 0 };
        let view = (processes.iter().take(views))
            .map(|&(first, n)| transport.slice_sender(&topics::view(first as usize), n as usize, q))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            processes,
            wheels,
            odom,
            view,
            truth: transport.slice_sender(topics::TRUTH, robots, topics::truth_qos())?,
            movers: (movers > 0)
                .then(|| transport.slice_sender(topics::MOVERS, movers, topics::truth_qos()))
                .transpose()?,
            life: None,
        })
    }

    /// The robots process `p` hosts.
    pub(crate) fn robots_of(&self, p: usize) -> Range<u32> {
        let (first, n) = self.processes[p];
        first..first + n
    }

    /// Attaches every wheel receiver and the supervisor's events to `waiter`; the loop waits
    /// as long as the returned attachments live.
    pub(crate) fn attach<'w>(
        &self,
        waiter: &'w Waiter,
    ) -> Result<Vec<Attachment<'w, '_>>, TransportError> {
        let mut attached = Vec::with_capacity(self.wheels.len() + 1);
        for rx in &self.wheels {
            attached.push(waiter.attach(rx)?);
        }
        if let Some(life) = &self.life {
            attached.push(waiter.attach(life.events())?);
        }
        Ok(attached)
    }
}
