//! The process's node in a run, its ports, and the run's liveness view.

use core::fmt::Debug;
use std::time::Duration;

use iceoryx2::config::Config;
use iceoryx2::node::Node;
use iceoryx2::prelude::{IceoryxSend, NodeBuilder, NodeName, SignalHandlingMode, ZeroCopySend};

use super::nodes::{cleanup_dead_nodes_in, nodes_in, services_in, CleanupReport, NodeInfo};
use super::run::check_ipc_root;
use super::{
    run_config, Ipc, Qos, Receiver, RunId, Sender, SingleWaiter, SliceReceiver, SliceSender,
    TransportError, Waiter,
};

/// Builds a [`Transport`].
#[derive(Debug)]
pub struct TransportBuilder {
    run: RunId,
    name: Option<String>,
    handle_signals: bool,
}

impl TransportBuilder {
    /// The node name other processes see (`agent-3`, `coordinator`, ...); at most 128 bytes.
    pub fn node_name(mut self, name: &str) -> Self {
        self.name = Some(name.to_string());
        self
    }

    /// Whether iceoryx2 turns SIGINT/SIGTERM into a termination request that the transport's
    /// waiters return as [`Wake::Stop`](super::Wake::Stop) (default `true`). Turn it off when
    /// the process handles signals itself: its waiters then never install a signal handler
    /// and never stop.
    pub fn handle_signals(mut self, yes: bool) -> Self {
        self.handle_signals = yes;
        self
    }

    /// Creates the node.
    pub fn create(self) -> Result<Transport, TransportError> {
        let config = run_config(&self.run);
        check_ipc_root(&config)?;
        let signals = if self.handle_signals {
            SignalHandlingMode::HandleTerminationRequests
        } else {
            SignalHandlingMode::Disabled
        };
        let mut builder = NodeBuilder::new()
            .config(&config)
            .signal_handling_mode(signals);
        if let Some(name) = &self.name {
            let node_name = NodeName::new(name).map_err(|e| TransportError::InvalidName {
                name: name.clone(),
                why: super::error::in_words(&format!("{e:?}")),
            })?;
            builder = builder.name(&node_name);
        }
        let node = builder.create::<Ipc>().map_err(|e| {
            TransportError::ipc("create node", self.name.as_deref().unwrap_or(""), e)
        })?;
        Ok(Transport {
            run: self.run,
            config,
            node,
            signals,
        })
    }
}

/// One process's membership in a run: an iceoryx2 node under the run's config, and the
/// factory of its typed ports.
pub struct Transport {
    run: RunId,
    config: Config,
    node: Node<Ipc>,
    signals: SignalHandlingMode,
}

impl Transport {
    /// Starts building the transport of `run`.
    pub fn builder(run: &RunId) -> TransportBuilder {
        TransportBuilder {
            run: run.clone(),
            name: None,
            handle_signals: true,
        }
    }

    /// The run this transport belongs to.
    pub fn run(&self) -> &RunId {
        &self.run
    }

    /// The run's iceoryx2 config.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The underlying iceoryx2 node.
    pub fn node(&self) -> &Node<Ipc> {
        &self.node
    }

    /// Opens the sending half of `topic` (`hnav/<run>/<topic>`).
    pub fn sender<T: Debug + ZeroCopySend + 'static>(
        &self,
        topic: &str,
        qos: Qos,
    ) -> Result<Sender<T>, TransportError> {
        Sender::open(&self.node, self.run.service_name(topic)?, qos)
    }

    /// Opens the receiving half of `topic`.
    pub fn receiver<T: Debug + ZeroCopySend + 'static>(
        &self,
        topic: &str,
        qos: Qos,
    ) -> Result<Receiver<T>, TransportError> {
        Receiver::open(&self.node, self.run.service_name(topic)?, qos, None)
    }

    /// [`Transport::receiver`] for a process that watches the run's [`Bell`](super::Bell):
    /// its listener is a [`BELL_LISTENER`](super::BELL_LISTENER), which a
    /// sender made [`ringing`](super::Sender::ringing) wakes by the bell instead of a
    /// datagram. It still reports publishers that appear, leave or die.
    pub fn bell_receiver<T: Debug + ZeroCopySend + 'static>(
        &self,
        topic: &str,
        qos: Qos,
    ) -> Result<Receiver<T>, TransportError> {
        Receiver::open(
            &self.node,
            self.run.service_name(topic)?,
            qos,
            Some(super::BELL_LISTENER),
        )
    }

    /// Opens the sending half of a slice topic whose samples hold at most `max_len` elements.
    pub fn slice_sender<E, H>(
        &self,
        topic: &str,
        max_len: usize,
        qos: Qos,
    ) -> Result<SliceSender<E, H>, TransportError>
    where
        E: Debug + ZeroCopySend + 'static,
        H: Debug + ZeroCopySend + Default + 'static,
    {
        SliceSender::open_slice(&self.node, self.run.service_name(topic)?, max_len, qos)
    }

    /// Opens the receiving half of a slice topic.
    pub fn slice_receiver<E, H>(
        &self,
        topic: &str,
        qos: Qos,
    ) -> Result<SliceReceiver<E, H>, TransportError>
    where
        E: Debug + ZeroCopySend + 'static,
        H: Debug + ZeroCopySend + 'static,
    {
        SliceReceiver::open_slice(&self.node, self.run.service_name(topic)?, qos, None)
    }

    /// Opens the receiving half of a slice topic whose senders ring the run's bell, as
    /// [`bell_receiver`](Self::bell_receiver) does for a fixed-size one (the commit stream).
    pub fn slice_bell_receiver<E, H>(
        &self,
        topic: &str,
        qos: Qos,
    ) -> Result<SliceReceiver<E, H>, TransportError>
    where
        E: Debug + ZeroCopySend + 'static,
        H: Debug + ZeroCopySend + 'static,
    {
        SliceReceiver::open_slice(
            &self.node,
            self.run.service_name(topic)?,
            qos,
            Some(super::BELL_LISTENER),
        )
    }

    /// A [`Waiter`] with the same signal handling as the node: what every process loop
    /// blocks in.
    pub fn waiter(&self) -> Result<Waiter, TransportError> {
        Waiter::create(self.run.as_str(), self.signals)
    }

    /// A [`SingleWaiter`] on `receiver`, with the same signal handling as the node: for a loop
    /// whose only event source is that receiver (no interval, no second receiver, no bell);
    /// it waits on the receiver's own descriptor, without a `WaitSet`.
    pub fn single_waiter<'a, P, H>(&self, receiver: &'a Receiver<P, H>) -> SingleWaiter<'a>
    where
        P: Debug + IceoryxSend + ?Sized + 'static,
        H: Debug + ZeroCopySend + 'static,
    {
        SingleWaiter::new(
            receiver,
            self.signals == SignalHandlingMode::HandleTerminationRequests,
        )
    }

    /// Every node of this run, alive or dead.
    pub fn nodes(&self) -> Result<Vec<NodeInfo>, TransportError> {
        nodes_in(&self.config)
    }

    /// Removes the stale resources of the run's dead nodes (after a SIGKILL, say).
    pub fn cleanup_dead_nodes(&self) -> Result<CleanupReport, TransportError> {
        cleanup_dead_nodes_in(&self.config)
    }

    /// [`Transport::cleanup_dead_nodes`] from another thread, which holds a copy of
    /// [`Transport::config`] (a node stays on the thread that made it).
    pub fn cleanup_dead_nodes_with(config: &Config) -> Result<CleanupReport, TransportError> {
        cleanup_dead_nodes_in(config)
    }

    /// Like [`Transport::cleanup_dead_nodes`], but waits up to `timeout` for another cleaner.
    pub fn blocking_cleanup_dead_nodes(&self, timeout: Duration) -> u64 {
        self.node.blocking_cleanup_dead_nodes(timeout).cleanups
    }

    /// The names of the run's services (`hnav/<run>/...`), sorted, each listed once.
    pub fn services(&self) -> Result<Vec<String>, TransportError> {
        services_in(&self.config)
    }

    /// The nodes of another run, for tools such as `hnav ps` that are not part of it.
    pub fn nodes_of(run: &RunId) -> Result<Vec<NodeInfo>, TransportError> {
        nodes_in(&run_config(run))
    }

    /// Removes the stale resources of another run's dead nodes, without joining the run (a
    /// node created in the run would already clean up as it starts).
    pub fn cleanup_dead_nodes_of(run: &RunId) -> Result<CleanupReport, TransportError> {
        cleanup_dead_nodes_in(&run_config(run))
    }

    /// The services of another run.
    pub fn services_of(run: &RunId) -> Result<Vec<String>, TransportError> {
        services_in(&run_config(run))
    }
}
