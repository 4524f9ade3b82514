//! Fixed-size payload channels: publisher + notifier, subscriber + listener.

use core::fmt::Debug;

use iceoryx2::node::Node;
use iceoryx2::port::backpressure_strategy::BackpressureStrategy;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::notifier::NotifierNotifyError;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::{
    CallbackProgression, EventId, IceoryxSend, PortName, ServiceName, ZeroCopySend,
};
use iceoryx2::sample::Sample;
use iceoryx2::sample_mut::SampleMut;
use iceoryx2::service::builder::event::{EventCreateError, EventOpenError, EventOpenOrCreateError};
use iceoryx2::service::builder::publish_subscribe::{
    PublishSubscribeCreateError, PublishSubscribeOpenError, PublishSubscribeOpenOrCreateError,
};
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;

use super::bell::{Bell, BELL_LISTENER};
use super::{event_id, Delivery, Ipc, Qos, TransportError};

/// How often and how long opening a service is retried while another process is creating or
/// removing it (iceoryx2's builder docs ask callers to retry these "with a little delay").
const OPEN_ATTEMPTS: u32 = 20;
const OPEN_BACKOFF: std::time::Duration = std::time::Duration::from_millis(5);

/// Runs `open` until it succeeds, fails for good, or the transient failures run out of tries.
pub(crate) fn open_with_retry<T, E: Debug>(
    op: &'static str,
    name: &ServiceName,
    transient: impl Fn(&E) -> bool,
    mut open: impl FnMut() -> Result<T, E>,
) -> Result<T, TransportError> {
    let mut attempt = 0;
    loop {
        match open() {
            Ok(v) => return Ok(v),
            Err(e) if transient(&e) && attempt + 1 < OPEN_ATTEMPTS => {
                attempt += 1;
                tracing::debug!(service = name.as_str(), ?e, attempt, "retrying {op}");
                std::thread::sleep(OPEN_BACKOFF * attempt);
            }
            Err(e) => return Err(TransportError::ipc(op, name.as_str(), e)),
        }
    }
}

/// Opens (or creates) a publish-subscribe service with a run's QoS. A macro because iceoryx2's
/// builder has separate `open_or_create` impls for sized and slice payloads.
macro_rules! open_pubsub {
    ($node:expr, $name:expr, $qos:expr, $payload:ty $(, $header:ty)?) => {
        $crate::transport::channel::open_with_retry(
            "open publish-subscribe service",
            $name,
            $crate::transport::channel::pubsub_transient,
            || {
                $node
                    .service_builder($name)
                    .publish_subscribe::<$payload>()
                    $(.user_header::<$header>())?
                    .max_publishers($qos.max_publishers)
                    .max_subscribers($qos.max_subscribers)
                    .max_nodes($qos.max_nodes())
                    .subscriber_max_buffer_size($qos.buffer)
                    .history_size($qos.history)
                    .enable_safe_overflow($qos.delivery == $crate::transport::Delivery::LatestOnly)
                    .open_or_create()
            },
        )
    };
}
pub(crate) use open_pubsub;

pub(crate) fn pubsub_transient(e: &PublishSubscribeOpenOrCreateError) -> bool {
    use PublishSubscribeCreateError as C;
    use PublishSubscribeOpenError as O;
    use PublishSubscribeOpenOrCreateError as E;
    matches!(
        e,
        E::SystemInFlux
            | E::PublishSubscribeOpenError(
                O::IsMarkedForDestruction | O::HangsInCreation | O::ServiceInCorruptedState
            )
            | E::PublishSubscribeCreateError(
                C::IsBeingCreatedByAnotherInstance | C::HangsInCreation | C::AlreadyExists
            )
    )
}

fn event_transient(e: &EventOpenOrCreateError) -> bool {
    use EventCreateError as C;
    use EventOpenError as O;
    use EventOpenOrCreateError as E;
    matches!(
        e,
        E::SystemInFlux
            | E::EventOpenError(
                O::IsMarkedForDestruction | O::HangsInCreation | O::ServiceInCorruptedState
            )
            | E::EventCreateError(C::IsBeingCreatedByAnotherInstance | C::AlreadyExists)
    )
}

/// Opens (or creates) the event service that accompanies a data service of the same name.
fn open_event(
    node: &Node<Ipc>,
    name: &ServiceName,
    qos: &Qos,
) -> Result<EventFactory<Ipc>, TransportError> {
    open_with_retry("open event service", name, event_transient, || {
        node.service_builder(name)
            .event()
            .max_notifiers(qos.max_publishers)
            .max_listeners(qos.max_subscribers)
            .max_nodes(qos.max_nodes())
            .event_id_max_value(event_id::MAX)
            .notifier_created_event(EventId::new(event_id::PEER_UP))
            .notifier_dropped_event(EventId::new(event_id::PEER_LEFT))
            .notifier_dead_event(EventId::new(event_id::PEER_DEAD))
            .open_or_create()
    })
}

pub(crate) fn backpressure(qos: &Qos) -> BackpressureStrategy {
    match qos.delivery {
        Delivery::LatestOnly => BackpressureStrategy::DiscardData,
        Delivery::Reliable => BackpressureStrategy::RetryUntilDelivered,
    }
}

fn create_notifier(
    events: &EventFactory<Ipc>,
    name: &ServiceName,
) -> Result<Notifier<Ipc>, TransportError> {
    events
        .notifier_builder()
        .default_event_id(EventId::new(event_id::DATA))
        .create()
        .map_err(|e| TransportError::ipc("create notifier", name.as_str(), e))
}

/// A listener, named `port` if given (a [`BELL_LISTENER`] is woken by the bell, not by a
/// datagram).
fn create_listener(
    events: &EventFactory<Ipc>,
    name: &ServiceName,
    port: Option<&str>,
) -> Result<Listener<Ipc>, TransportError> {
    let mut builder = events.listener_builder();
    if let Some(port) = port {
        let port = PortName::new(port).map_err(|e| TransportError::InvalidName {
            name: port.to_string(),
            why: format!("{e:?}"),
        })?;
        builder = builder.name(&port);
    }
    builder
        .create()
        .map_err(|e| TransportError::ipc("create listener", name.as_str(), e))
}

/// What woke a receiver: the events gathered since the last call, by kind.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Wakeup {
    /// Samples were published (coalesced: one or more).
    pub data: bool,
    /// A publisher appeared.
    pub peer_up: bool,
    /// A publisher left cleanly.
    pub peer_left: bool,
    /// A publisher's process died and its node was cleaned up.
    pub peer_dead: bool,
}

impl Wakeup {
    pub(crate) fn record(&mut self, id: EventId) {
        match id.as_value() {
            event_id::DATA => self.data = true,
            event_id::PEER_UP => self.peer_up = true,
            event_id::PEER_LEFT => self.peer_left = true,
            event_id::PEER_DEAD => self.peer_dead = true,
            _ => {}
        }
    }
}

/// What one [`Receiver::drain_pending`] found.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Drained {
    /// The listener's events, consumed before the samples were received.
    pub wakeup: Wakeup,
    /// How many samples were received.
    pub samples: usize,
}

/// Which publisher a sample came from: a bridge skips what its own senders published, so
/// that nothing it brought in goes back out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PublisherId(pub(crate) iceoryx2::identifiers::UniquePublisherId);

/// The sending half of a topic: a publisher of `P` (a fixed-size type, or `[E]` for a slice
/// topic, see [`SliceSender`](super::SliceSender)) with user header `H`, plus a notifier that
/// wakes receivers.
pub struct Sender<P, H = ()>
where
    P: Debug + IceoryxSend + ?Sized + 'static,
    H: Debug + ZeroCopySend + 'static,
{
    name: ServiceName,
    publisher: Publisher<Ipc, P, H>,
    notifier: Notifier<Ipc>,
    /// The run's commit bell, if this sender rings it ([`Sender::ringing`]).
    bell: Option<Bell>,
}

impl<P, H> Sender<P, H>
where
    P: Debug + IceoryxSend + ?Sized + 'static,
    H: Debug + ZeroCopySend + 'static,
{
    /// Completes a sender around a freshly created publisher: its notifier, and connections to
    /// the subscribers that already exist, so the first sample is not lost.
    pub(crate) fn assemble(
        node: &Node<Ipc>,
        name: ServiceName,
        qos: &Qos,
        publisher: Publisher<Ipc, P, H>,
    ) -> Result<Self, TransportError> {
        let events = open_event(node, &name, qos)?;
        let notifier = create_notifier(&events, &name)?;
        let sender = Self {
            name,
            publisher,
            notifier,
            bell: None,
        };
        sender.update_connections()?;
        Ok(sender)
    }

    /// The full service name.
    pub fn name(&self) -> &str {
        self.name.as_str()
    }

    /// From now on every send rings `bell`, which wakes the receivers whose listener is a
    /// [`BELL_LISTENER`] ([`Transport::bell_receiver`](super::Transport::bell_receiver)), and
    /// notifies only the other listeners, one datagram each (see [`Bell`]).
    pub fn ringing(mut self, bell: Bell) -> Self {
        self.bell = Some(bell);
        self
    }

    /// Publishes a written sample and wakes the receivers; returns how many subscribers it
    /// reached.
    pub(crate) fn publish(&self, sample: SampleMut<Ipc, P, H>) -> Result<usize, TransportError> {
        let reached = sample
            .send()
            .map_err(|e| TransportError::ipc("send sample", self.name.as_str(), e))?;
        self.notify()?;
        Ok(reached)
    }

    /// Wakes the receivers without a sample: after a batch of
    /// [`send_silently`](Sender::send_silently)s, one wake-up for all of them (an agent
    /// process that hosts several robots sends their candidates so).
    pub fn notify(&self) -> Result<(), TransportError> {
        match &self.bell {
            None => self
                .notifier
                .notify()
                .map(drop)
                .map_err(|e| TransportError::ipc("notify", self.name.as_str(), e)),
            Some(bell) => self.ring_and_notify_the_others(bell),
        }
    }

    /// Notifies every listener that is not a [`BELL_LISTENER`], then rings `bell`: last, so
    /// that the woken agents do not preempt this loop on a busy machine.
    fn ring_and_notify_the_others(&self, bell: &Bell) -> Result<(), TransportError> {
        let mut failed = None;
        self.notifier.for_each_listener(|listener, details| {
            if details.listener_name != BELL_LISTENER {
                if let Err(e) = listener.notify() {
                    failed.get_or_insert(e);
                }
            }
            CallbackProgression::Continue
        });
        bell.ring()?;
        match failed {
            // A listener that left meanwhile is not an error of this send.
            None | Some(NotifierNotifyError::InvalidListenerKey) => Ok(()),
            Some(e) => Err(TransportError::ipc("notify", self.name.as_str(), e)),
        }
    }

    pub(crate) fn loan_error(&self, e: impl Debug) -> TransportError {
        TransportError::ipc("loan sample", self.name.as_str(), e)
    }

    /// Connects to subscribers that joined since the last send.
    pub fn update_connections(&self) -> Result<(), TransportError> {
        self.publisher
            .update_connections()
            .map_err(|e| TransportError::ipc("connect publisher", self.name.as_str(), e))
    }

    /// The underlying iceoryx2 publisher, for what this layer does not wrap.
    pub fn publisher(&self) -> &Publisher<Ipc, P, H> {
        &self.publisher
    }

    /// This sender's publisher, as its samples name it ([`Receiver::drain_pending_except`]).
    pub fn id(&self) -> PublisherId {
        PublisherId(self.publisher.id())
    }
}

impl<T: Debug + ZeroCopySend + 'static> Sender<T> {
    pub(crate) fn open(
        node: &Node<Ipc>,
        name: ServiceName,
        qos: Qos,
    ) -> Result<Self, TransportError> {
        let service = open_pubsub!(node, &name, qos, T)?;
        let publisher = service
            .publisher_builder()
            .backpressure_strategy(backpressure(&qos))
            .create()
            .map_err(|e| TransportError::ipc("create publisher", name.as_str(), e))?;
        Self::assemble(node, name, &qos, publisher)
    }

    /// Writes `value` into a loaned shared-memory chunk, publishes it and wakes the receivers.
    /// Returns how many subscribers received it.
    pub fn send(&self, value: T) -> Result<usize, TransportError> {
        let sample = self
            .publisher
            .loan_uninit()
            .map_err(|e| self.loan_error(e))?;
        self.publish(sample.write_payload(value))
    }

    /// [`Sender::send`] without waking the receivers: for state a reader takes at a deadline
    /// of its own (the heartbeat), where a wake-up per sample would only cost the reader.
    pub fn send_silently(&self, value: T) -> Result<usize, TransportError> {
        let sample = self
            .publisher
            .loan_uninit()
            .map_err(|e| self.loan_error(e))?;
        sample
            .write_payload(value)
            .send()
            .map_err(|e| TransportError::ipc("send sample", self.name.as_str(), e))
    }

    /// Loans a default-initialised chunk, lets `fill` write the payload in place (no copy of a
    /// large message through the stack), publishes it and wakes the receivers.
    pub fn send_in_place(&self, fill: impl FnOnce(&mut T)) -> Result<usize, TransportError>
    where
        T: Default,
    {
        let mut sample = self.publisher.loan().map_err(|e| self.loan_error(e))?;
        fill(sample.payload_mut());
        self.publish(sample)
    }

    /// [`Sender::send_in_place`] for a payload that may turn out invalid while it is written
    /// (bytes from another host): when `fill` fails the loan is returned unsent and its error
    /// comes back inside the `Ok`.
    pub fn try_send_in_place<E>(
        &self,
        fill: impl FnOnce(&mut T) -> Result<(), E>,
    ) -> Result<Result<usize, E>, TransportError>
    where
        T: Default,
    {
        let mut sample = self.publisher.loan().map_err(|e| self.loan_error(e))?;
        match fill(sample.payload_mut()) {
            Ok(()) => self.publish(sample).map(Ok),
            Err(e) => Ok(Err(e)),
        }
    }
}

/// The receiving half of a topic: a subscriber of `P` (fixed-size, or `[E]` for a slice topic,
/// see [`SliceReceiver`](super::SliceReceiver)) with user header `H`, plus a listener to block on.
///
/// Attach it to a [`Waiter`](super::Waiter); when the waiter returns
/// [`Wake::Data`](super::Wake::Data), call [`Receiver::drain_pending`] (or
/// [`Receiver::take_wakeup`] and then `receive` until nothing is left, in that order).
pub struct Receiver<P, H = ()>
where
    P: Debug + IceoryxSend + ?Sized + 'static,
    H: Debug + ZeroCopySend + 'static,
{
    name: ServiceName,
    subscriber: Subscriber<Ipc, P, H>,
    listener: Listener<Ipc>,
}

impl<P, H> Receiver<P, H>
where
    P: Debug + IceoryxSend + ?Sized + 'static,
    H: Debug + ZeroCopySend + 'static,
{
    /// Completes a receiver around a freshly created subscriber: its listener, and connections
    /// to the publishers that already exist.
    pub(crate) fn assemble(
        node: &Node<Ipc>,
        name: ServiceName,
        qos: &Qos,
        subscriber: Subscriber<Ipc, P, H>,
        listener_port: Option<&str>,
    ) -> Result<Self, TransportError> {
        let events = open_event(node, &name, qos)?;
        let listener = create_listener(&events, &name, listener_port)?;
        subscriber
            .update_connections()
            .map_err(|e| TransportError::ipc("connect subscriber", name.as_str(), e))?;
        Ok(Self {
            name,
            subscriber,
            listener,
        })
    }

    /// The full service name.
    pub fn name(&self) -> &str {
        self.name.as_str()
    }

    /// The listener behind the receiver (what a [`Waiter`](super::Waiter) attaches).
    pub(crate) fn listener(&self) -> &Listener<Ipc> {
        &self.listener
    }

    /// Consumes the pending wake-up events and reports what they were.
    pub fn take_wakeup(&self) -> Result<Wakeup, TransportError> {
        let mut wakeup = Wakeup::default();
        self.listener
            .try_wait(|activation| wakeup.record(activation.id))
            .map_err(|e| TransportError::ipc("drain listener", self.name.as_str(), e))?;
        Ok(wakeup)
    }

    pub(crate) fn receive_error(&self, e: impl Debug) -> TransportError {
        TransportError::ipc("receive", self.name.as_str(), e)
    }

    /// The underlying iceoryx2 subscriber, for what this layer does not wrap.
    pub fn subscriber(&self) -> &Subscriber<Ipc, P, H> {
        &self.subscriber
    }
}

impl<T: Debug + ZeroCopySend + 'static> Receiver<T> {
    /// Opens the receiver; its listener is named `listener_port` if given.
    pub(crate) fn open(
        node: &Node<Ipc>,
        name: ServiceName,
        qos: Qos,
        listener_port: Option<&str>,
    ) -> Result<Self, TransportError> {
        let service = open_pubsub!(node, &name, qos, T)?;
        let subscriber = service
            .subscriber_builder()
            .buffer_size(qos.buffer)
            .create()
            .map_err(|e| TransportError::ipc("create subscriber", name.as_str(), e))?;
        Self::assemble(node, name, &qos, subscriber, listener_port)
    }

    /// Takes the oldest unread sample, if any. The sample stays in shared memory (zero-copy)
    /// until it is dropped.
    pub fn receive(&self) -> Result<Option<Sample<Ipc, T, ()>>, TransportError> {
        self.subscriber.receive().map_err(|e| self.receive_error(e))
    }

    /// Hands every unread sample to `f` in publication order and returns how many there were.
    pub fn drain(&self, mut f: impl FnMut(&T)) -> Result<usize, TransportError> {
        let mut n = 0;
        while let Some(sample) = self.receive()? {
            f(sample.payload());
            n += 1;
        }
        Ok(n)
    }

    /// Consumes the listener's events, then hands every unread sample to `f`: the drain order
    /// a [`Waiter`](super::Waiter) wake-up needs, in one call.
    pub fn drain_pending(&self, f: impl FnMut(&T)) -> Result<Drained, TransportError> {
        self.drain_pending_except(&[], f)
    }

    /// [`Receiver::drain_pending`] that passes over the samples of the publishers in `skip`
    /// (taken and dropped, not handed to `f`); `samples` counts only those handed on.
    pub fn drain_pending_except(
        &self,
        skip: &[PublisherId],
        mut f: impl FnMut(&T),
    ) -> Result<Drained, TransportError> {
        let wakeup = self.take_wakeup()?;
        let mut samples = 0;
        while let Some(sample) = self.receive()? {
            if !skip.contains(&PublisherId(sample.header().publisher_id())) {
                f(sample.payload());
                samples += 1;
            }
        }
        Ok(Drained { wakeup, samples })
    }
}
