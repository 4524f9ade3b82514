//! Quality of service, sized from the swarm instead of iceoryx2's two-publisher default.

/// What a subscriber whose buffer is full does to the publisher.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Delivery {
    /// The oldest unread sample is overwritten: right for state that supersedes itself
    /// (odometry, ground truth, neural-map snapshots).
    LatestOnly,
    /// The publisher waits until the subscriber has room (iceoryx2's backpressure
    /// `RetryUntilDelivered`): right for streams where every sample counts (candidates,
    /// commits, lifecycle events). A subscriber that stops reading stalls its publishers, so
    /// size `buffer` for the expected burst.
    Reliable,
}

/// The QoS of one service. Creating processes set these values; opening processes require
/// at least these, so every process of a run should derive them from the same agent count.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Qos {
    /// Publishers (and notifiers) the service admits.
    pub max_publishers: usize,
    /// Subscribers (and listeners) the service admits.
    pub max_subscribers: usize,
    /// Samples buffered per subscriber.
    pub buffer: usize,
    /// Samples kept for late joiners (0 = none).
    pub history: usize,
    /// Overflow behaviour.
    pub delivery: Delivery,
}

impl Qos {
    /// Processes besides the agents that may open any service: sim, up to
    /// [`MAX_REPLICAS`](crate::msg::MAX_REPLICAS) coordinator replicas, supervisor, and one
    /// observer (a viewer, `hnav ps`, a test or a benchmark).
    pub const EXTRA_NODES: usize = 3 + crate::msg::MAX_REPLICAS as usize;

    /// A stream where every sample counts, for a swarm of `agents`, any of which may publish
    /// and any of which may subscribe.
    pub fn reliable(agents: usize) -> Self {
        let n = agents.max(1) + Self::EXTRA_NODES;
        Self {
            max_publishers: n,
            max_subscribers: n,
            buffer: 2 * n.max(8),
            history: 0,
            delivery: Delivery::Reliable,
        }
    }

    /// Superseding state with one publisher and a few readers (per-robot topics), keeping the
    /// latest sample for late joiners such as a restarted coordinator.
    pub fn latest() -> Self {
        Self {
            max_publishers: 2,
            max_subscribers: Self::EXTRA_NODES,
            buffer: 4,
            history: 1,
            delivery: Delivery::LatestOnly,
        }
    }

    /// Nodes that may open the service: every possible publisher and subscriber.
    pub fn max_nodes(&self) -> usize {
        self.max_publishers + self.max_subscribers
    }

    /// Returns a copy with another subscriber buffer size.
    pub fn with_buffer(mut self, buffer: usize) -> Self {
        self.buffer = buffer.max(1);
        self
    }

    /// Returns a copy with another delivery mode.
    pub fn with_delivery(mut self, delivery: Delivery) -> Self {
        self.delivery = delivery;
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reliable_qos_grows_with_the_swarm() {
        let small = Qos::reliable(2);
        let big = Qos::reliable(128);
        assert!(big.max_publishers >= 128 + Qos::EXTRA_NODES);
        assert!(big.max_subscribers > small.max_subscribers);
        assert!(big.max_nodes() >= 2 * 128);
        assert_eq!(big.delivery, Delivery::Reliable);
    }
}
