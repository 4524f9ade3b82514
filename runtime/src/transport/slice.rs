//! Slice channels: variable-length arrays (the neural-map snapshot) written in place into
//! loaned shared memory, with a fixed-size user header beside them.

use core::fmt::Debug;
use core::mem::MaybeUninit;

use iceoryx2::node::Node;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::{AllocationStrategy, ServiceName, ZeroCopySend};
use iceoryx2::sample::Sample;
use iceoryx2::sample_mut_uninit::SampleMutUninit;

use super::channel::{
    backpressure, create_listener, create_notifier, open_event, open_pubsub, take_wakeup,
};
use super::{Ipc, Qos, TransportError, Wakeup};

/// The sending half of a slice topic: `[E]` payloads with a header `H`.
///
/// Memory is preallocated for `max_len` elements per sample (iceoryx2's `Static` strategy),
/// so publishing never reallocates shared memory and subscribers never remap it.
pub struct SliceSender<E: Debug + ZeroCopySend + 'static, H: Debug + ZeroCopySend + Default + 'static>
{
    name: ServiceName,
    publisher: Publisher<Ipc, [E], H>,
    notifier: Notifier<Ipc>,
    max_len: usize,
}

impl<E, H> SliceSender<E, H>
where
    E: Debug + ZeroCopySend + 'static,
    H: Debug + ZeroCopySend + Default + 'static,
{
    pub(crate) fn open(
        node: &Node<Ipc>,
        name: ServiceName,
        max_len: usize,
        qos: Qos,
    ) -> Result<Self, TransportError> {
        let service = open_pubsub!(node, &name, qos, [E], H)?;
        let publisher = service
            .publisher_builder()
            .initial_max_slice_len(max_len.max(1))
            .allocation_strategy(AllocationStrategy::Static)
            .backpressure_strategy(backpressure(&qos))
            .create()
            .map_err(|e| TransportError::ipc("create slice publisher", name.as_str(), e))?;
        let events = open_event(node, &name, &qos)?;
        let notifier = create_notifier(&events, &name)?;
        publisher
            .update_connections()
            .map_err(|e| TransportError::ipc("connect publisher", name.as_str(), e))?;
        Ok(Self {
            name,
            publisher,
            notifier,
            max_len: max_len.max(1),
        })
    }

    /// The full service name.
    pub fn name(&self) -> &str {
        self.name.as_str()
    }

    /// The largest slice one sample can carry.
    pub fn max_len(&self) -> usize {
        self.max_len
    }

    /// Loans `len` elements of shared memory to be written in place.
    pub fn loan(&self, len: usize) -> Result<SliceLoan<'_, E, H>, TransportError> {
        let sample = self
            .publisher
            .loan_slice_uninit(len)
            .map_err(|e| TransportError::ipc("loan slice", self.name.as_str(), e))?;
        Ok(SliceLoan {
            sender: self,
            sample,
        })
    }

    /// Loans `len` elements, fills element `i` with `f(i)` in place, publishes and notifies.
    pub fn send_from_fn(
        &self,
        header: H,
        len: usize,
        f: impl FnMut(usize) -> E,
    ) -> Result<usize, TransportError> {
        let mut loan = self.loan(len)?;
        *loan.header_mut() = header;
        loan.fill_and_send(f)
    }

    fn finish(
        &self,
        sample: iceoryx2::sample_mut::SampleMut<Ipc, [E], H>,
    ) -> Result<usize, TransportError> {
        let reached = sample
            .send()
            .map_err(|e| TransportError::ipc("send slice", self.name.as_str(), e))?;
        self.notifier
            .notify()
            .map_err(|e| TransportError::ipc("notify", self.name.as_str(), e))?;
        Ok(reached)
    }
}

/// A loaned, not yet published slice sample.
pub struct SliceLoan<'a, E, H>
where
    E: Debug + ZeroCopySend + 'static,
    H: Debug + ZeroCopySend + Default + 'static,
{
    sender: &'a SliceSender<E, H>,
    sample: SampleMutUninit<Ipc, [MaybeUninit<E>], H>,
}

impl<E, H> SliceLoan<'_, E, H>
where
    E: Debug + ZeroCopySend + 'static,
    H: Debug + ZeroCopySend + Default + 'static,
{
    /// The header, to be written before publishing.
    pub fn header_mut(&mut self) -> &mut H {
        self.sample.user_header_mut()
    }

    /// The loaned elements, not yet initialised.
    pub fn payload_mut(&mut self) -> &mut [MaybeUninit<E>] {
        self.sample.payload_mut()
    }

    /// Writes element `i` as `f(i)` straight into shared memory, then publishes and notifies.
    pub fn fill_and_send(self, f: impl FnMut(usize) -> E) -> Result<usize, TransportError> {
        let sample = self.sample.write_from_fn(f);
        self.sender.finish(sample)
    }

    /// Copies `src` (which must have the loaned length) into shared memory, then publishes.
    pub fn copy_and_send(self, src: &[E]) -> Result<usize, TransportError>
    where
        E: Copy,
    {
        let sample = self.sample.write_from_slice(src);
        self.sender.finish(sample)
    }

    /// Publishes what was written through [`SliceLoan::payload_mut`].
    ///
    /// # Safety
    ///
    /// Every element of the loaned slice must have been initialised.
    pub unsafe fn assume_init_and_send(self) -> Result<usize, TransportError> {
        // SAFETY: the caller guarantees every element was written.
        let sample = unsafe { self.sample.assume_init() };
        self.sender.finish(sample)
    }
}

/// The receiving half of a slice topic.
pub struct SliceReceiver<E: Debug + ZeroCopySend + 'static, H: Debug + ZeroCopySend + 'static> {
    name: ServiceName,
    subscriber: Subscriber<Ipc, [E], H>,
    listener: Listener<Ipc>,
}

impl<E, H> SliceReceiver<E, H>
where
    E: Debug + ZeroCopySend + 'static,
    H: Debug + ZeroCopySend + 'static,
{
    pub(crate) fn open(node: &Node<Ipc>, name: ServiceName, qos: Qos) -> Result<Self, TransportError> {
        let service = open_pubsub!(node, &name, qos, [E], H)?;
        let subscriber = service
            .subscriber_builder()
            .buffer_size(qos.buffer)
            .create()
            .map_err(|e| TransportError::ipc("create slice subscriber", name.as_str(), e))?;
        let events = open_event(node, &name, &qos)?;
        let listener = create_listener(&events, &name)?;
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

    /// The listener to attach to a WaitSet.
    pub fn listener(&self) -> &Listener<Ipc> {
        &self.listener
    }

    /// Consumes the pending wake-up events and reports what they were.
    pub fn take_wakeup(&self) -> Result<Wakeup, TransportError> {
        take_wakeup(&self.listener, &self.name)
    }

    /// Takes the oldest unread sample; `sample.user_header()` and `sample.payload()` read it in
    /// place in shared memory.
    pub fn receive(&self) -> Result<Option<Sample<Ipc, [E], H>>, TransportError> {
        self.subscriber
            .receive()
            .map_err(|e| TransportError::ipc("receive slice", self.name.as_str(), e))
    }
}
