//! Slice topics: variable-length arrays (the neural-map snapshot) written in place into
//! loaned shared memory, with a fixed-size user header beside them.
//!
//! A slice topic is a [`Sender`]/[`Receiver`] whose payload is `[E]`; this module adds what is
//! particular to slices: preallocated maximum length and in-place writing through a
//! [`SliceLoan`].

use core::fmt::Debug;
use core::mem::MaybeUninit;

use iceoryx2::node::Node;
use iceoryx2::prelude::{AllocationStrategy, ServiceName, ZeroCopySend};
use iceoryx2::sample::Sample;
use iceoryx2::sample_mut_uninit::SampleMutUninit;

use super::channel::{backpressure, open_pubsub};
use super::{Drained, Ipc, PublisherId, Qos, Receiver, Sender, TransportError};

/// The sending half of a slice topic: `[E]` payloads with a header `H`.
///
/// Memory is preallocated for `max_len` elements per sample (iceoryx2's `Static` strategy),
/// so publishing never reallocates shared memory and subscribers never remap it.
pub type SliceSender<E, H> = Sender<[E], H>;

/// The receiving half of a slice topic.
pub type SliceReceiver<E, H> = Receiver<[E], H>;

impl<E, H> Sender<[E], H>
where
    E: Debug + ZeroCopySend + 'static,
    H: Debug + ZeroCopySend + Default + 'static,
{
    pub(crate) fn open_slice(
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
        Self::assemble(node, name, &qos, publisher)
    }

    /// The largest slice one sample can carry.
    pub fn max_len(&self) -> usize {
        self.publisher().initial_max_slice_len()
    }

    /// Loans `len` elements of shared memory to be written in place.
    pub fn loan(&self, len: usize) -> Result<SliceLoan<'_, E, H>, TransportError> {
        let sample = self
            .publisher()
            .loan_slice_uninit(len)
            .map_err(|e| self.loan_error(e))?;
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
        self.sender.publish(self.sample.write_from_fn(f))
    }

    /// Copies `src` (which must have the loaned length) into shared memory, then publishes.
    pub fn copy_and_send(self, src: &[E]) -> Result<usize, TransportError>
    where
        E: Copy,
    {
        self.sender.publish(self.sample.write_from_slice(src))
    }

    /// Sets every loaned element to `init`, hands the now initialised slice to `write`, and
    /// publishes it unless `write` fails (the loan is then dropped unsent).
    ///
    /// For writers that fill a `&mut [E]` in place, such as a neural map writing its values
    /// straight into shared memory: the initial fill is what makes handing out `&mut [E]`
    /// sound, so no caller needs `unsafe`.
    pub fn fill_with<X>(
        mut self,
        init: E,
        write: impl FnOnce(&mut [E]) -> Result<(), X>,
    ) -> Result<usize, X>
    where
        E: Copy,
        X: From<TransportError>,
    {
        let out = self.sample.payload_mut();
        for v in out.iter_mut() {
            v.write(init);
        }
        // SAFETY: the loop above initialised every element, and `MaybeUninit<E>` has the size,
        // alignment and layout of `E`; the borrow of `out` ends with this slice's.
        let values: &mut [E] =
            unsafe { core::slice::from_raw_parts_mut(out.as_mut_ptr().cast::<E>(), out.len()) };
        write(values)?;
        // SAFETY: every element was initialised by the loop above; `write` could only store
        // initialised `E`s through `&mut [E]`.
        let sample = unsafe { self.sample.assume_init() };
        Ok(self.sender.publish(sample)?)
    }

    /// Publishes what was written through [`SliceLoan::payload_mut`].
    ///
    /// # Safety
    ///
    /// Every element of the loaned slice must have been initialised.
    pub unsafe fn assume_init_and_send(self) -> Result<usize, TransportError> {
        // SAFETY: the caller guarantees every element was written.
        let sample = unsafe { self.sample.assume_init() };
        self.sender.publish(sample)
    }
}

impl<E, H> Receiver<[E], H>
where
    E: Debug + ZeroCopySend + 'static,
    H: Debug + ZeroCopySend + 'static,
{
    /// Opens the receiver; its listener is named `listener_port` if given (see
    /// [`Receiver::open`]).
    pub(crate) fn open_slice(
        node: &Node<Ipc>,
        name: ServiceName,
        qos: Qos,
        listener_port: Option<&str>,
    ) -> Result<Self, TransportError> {
        let service = open_pubsub!(node, &name, qos, [E], H)?;
        let subscriber = service
            .subscriber_builder()
            .buffer_size(qos.buffer)
            .create()
            .map_err(|e| TransportError::ipc("create slice subscriber", name.as_str(), e))?;
        Self::assemble(node, name, &qos, subscriber, listener_port)
    }

    /// Takes the oldest unread sample; `sample.user_header()` and `sample.payload()` read it in
    /// place in shared memory.
    pub fn receive(&self) -> Result<Option<Sample<Ipc, [E], H>>, TransportError> {
        self.subscriber()
            .receive()
            .map_err(|e| self.receive_error(e))
    }

    /// Hands every unread sample's header and elements to `f`, read in place, in publication
    /// order, and returns how many there were.
    pub fn drain(&self, mut f: impl FnMut(&H, &[E])) -> Result<usize, TransportError> {
        let mut n = 0;
        while let Some(sample) = self.receive()? {
            f(sample.user_header(), sample.payload());
            n += 1;
        }
        Ok(n)
    }

    /// Consumes the listener's events and every unread sample, and returns the newest: for
    /// state topics whose latest sample supersedes the others (ground truth, views, the
    /// movers). One sample is held at a time, so a reader never holds more than its share of
    /// the publisher's samples.
    pub fn take_newest(&self) -> Result<Option<Sample<Ipc, [E], H>>, TransportError> {
        self.take_wakeup()?;
        let mut newest = None;
        while let Some(sample) = self.receive()? {
            newest = Some(sample);
        }
        Ok(newest)
    }

    /// Consumes the listener's events, then hands every unread sample's header and elements
    /// to `f`, read in place: the drain order a [`Waiter`](super::Waiter) wake-up needs.
    pub fn drain_pending(&self, f: impl FnMut(&H, &[E])) -> Result<Drained, TransportError> {
        self.drain_pending_except(&[], f)
    }

    /// [`drain_pending`](Self::drain_pending) that passes over the samples of the publishers
    /// in `skip` (see [`Receiver::drain_pending_except`]).
    pub fn drain_pending_except(
        &self,
        skip: &[PublisherId],
        mut f: impl FnMut(&H, &[E]),
    ) -> Result<Drained, TransportError> {
        let wakeup = self.take_wakeup()?;
        let mut samples = 0;
        while let Some(sample) = self.receive()? {
            if !skip.contains(&PublisherId(sample.header().publisher_id())) {
                f(sample.user_header(), sample.payload());
                samples += 1;
            }
        }
        Ok(Drained { wakeup, samples })
    }
}
