//! The topics of the `hnav-sim` process: one wheel-command receiver and one odometry sender
//! (and, when the scenario senses, one view sender) per robot, the Truth sender and, when joined to the run's lifecycle protocol, its ports.

use hnav_runtime::launch::LifecyclePorts;
use hnav_runtime::msg::{MoverPlace, MoversHeader, Odometry, View, WheelCommand};
use hnav_runtime::topics::{self, TruthSender};
use hnav_runtime::transport::{
    Attachment, Receiver, Sender, SliceSender, Transport, TransportError, Waiter,
};

/// The process's open ports. Kept apart from the [`State`](super::state::State) so that the
/// waiter's attachments can borrow the receivers while the loop mutates the state.
pub(crate) struct Ports {
    /// Robot `i`'s wheel commands.
    pub(crate) wheels: Vec<Receiver<WheelCommand>>,
    /// Robot `i`'s odometry.
    pub(crate) odom: Vec<Sender<Odometry>>,
    /// Robot `i`'s sensor view (empty when the scenario senses nothing).
    pub(crate) view: Vec<Sender<View>>,
    /// Ground truth of every robot, once per control period.
    pub(crate) truth: TruthSender,
    /// Where the movers are, once per control period (a world with movers only).
    pub(crate) movers: Option<SliceSender<MoverPlace, MoversHeader>>,
    /// The lifecycle protocol's ports, if joined.
    pub(crate) life: Option<LifecyclePorts>,
}

impl Ports {
    /// Opens the topics of a world of `robots` robots, with their views if `sensing` and the
    /// movers' places if it has `movers`.
    pub(crate) fn open(
        transport: &Transport,
        robots: usize,
        sensing: bool,
        movers: usize,
    ) -> Result<Self, TransportError> {
        let q = topics::state_qos();
        let wheels = (0..robots)
            .map(|i| transport.receiver(&topics::wheels(i), q))
            .collect::<Result<Vec<_>, _>>()?;
        let odom = (0..robots)
            .map(|i| transport.sender(&topics::odometry(i), q))
            .collect::<Result<Vec<_>, _>>()?;
        let views = if sensing { robots } else { 0 };
        let view = (0..views)
            .map(|i| transport.sender(&topics::view(i), q))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
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
