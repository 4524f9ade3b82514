//! One forwarded topic on one host: a receiver of what the host's processes publish (out to
//! Zenoh) and a sender of what other hosts published (in from Zenoh).

use hnav_runtime::msg::{
    Candidate, Commit, Lifecycle, Odometry, Progress, Truth, WheelCommand, Wire, WireError,
};
use hnav_runtime::transport::{
    Attachment, PublisherId, Receiver, Sender, Transport, TransportError, Waiter,
};
use zenoh::bytes::ZBytes;
use zenoh::pubsub::Publisher;
use zenoh::Wait;

use crate::topics::{Payload, TopicSpec};

/// What one pass of a port did.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Moved {
    /// Samples sent to Zenoh.
    pub out: u64,
    /// Samples published into iceoryx2.
    pub r#in: u64,
    /// Samples from Zenoh dropped as invalid.
    pub dropped: u64,
    /// Puts Zenoh refused.
    pub failed: u64,
}

/// A topic's two directions, whatever its payload type.
pub(crate) trait Port {
    /// The topic, below `hnav/<run>/`.
    fn topic(&self) -> &str;
    /// Attaches the receiver to `waiter`.
    fn attach<'w>(&'w self, waiter: &'w Waiter) -> Result<Attachment<'w, 'w>, TransportError>;
    /// Forwards what the host's processes published since the last call to `out`.
    fn send_out(&self, out: &Publisher<'static>, moved: &mut Moved) -> Result<(), TransportError>;
    /// Publishes `payload` from another host into iceoryx2, checked; `Err` is why it was
    /// dropped.
    fn bring_in(
        &self,
        payload: &ZBytes,
        type_name: Option<&str>,
    ) -> Result<Result<(), WireError>, TransportError>;
}

/// The port of a topic of `T`.
struct Typed<T: Wire> {
    topic: String,
    rx: Receiver<T>,
    tx: Sender<T>,
    /// The bridge's own sender: what it published came from Zenoh, and must not go back.
    own: [PublisherId; 1],
}

impl<T: Wire + Default> Port for Typed<T> {
    fn topic(&self) -> &str {
        &self.topic
    }

    fn attach<'w>(&'w self, waiter: &'w Waiter) -> Result<Attachment<'w, 'w>, TransportError> {
        waiter.attach(&self.rx)
    }

    fn send_out(&self, out: &Publisher<'static>, moved: &mut Moved) -> Result<(), TransportError> {
        self.rx.drain_pending_except(&self.own, |v| {
            // The sample is read in place; its bytes are copied once, into Zenoh's buffer.
            match out.put(v.bytes()).attachment(T::wire_name()).wait() {
                Ok(()) => moved.out += 1,
                Err(e) => {
                    moved.failed += 1;
                    tracing::debug!(topic = %self.topic, "zenoh put failed: {e}");
                }
            }
        })?;
        Ok(())
    }

    fn bring_in(
        &self,
        payload: &ZBytes,
        type_name: Option<&str>,
    ) -> Result<Result<(), WireError>, TransportError> {
        if type_name != Some(T::wire_name()) {
            return Ok(Err(WireError::TypeName {
                expected: T::wire_name(),
                got: type_name.unwrap_or("(none)").to_string(),
            }));
        }
        // Contiguous (one Zenoh slice, the usual case below the MTU): borrowed, no copy.
        let bytes = payload.to_bytes();
        Ok(self.tx.try_send_in_place(|v| v.assign(&bytes))?.map(|_| ()))
    }
}

/// Opens the port of `spec` on `transport`.
pub(crate) fn open(
    transport: &Transport,
    spec: &TopicSpec,
) -> Result<Box<dyn Port>, TransportError> {
    fn typed<T: Wire + Default>(
        transport: &Transport,
        spec: &TopicSpec,
    ) -> Result<Box<dyn Port>, TransportError> {
        let tx = transport.sender::<T>(&spec.topic, spec.qos)?;
        let rx = transport.receiver::<T>(&spec.topic, spec.qos)?;
        Ok(Box::new(Typed {
            topic: spec.topic.clone(),
            own: [tx.id()],
            rx,
            tx,
        }))
    }
    match spec.payload {
        Payload::Candidate => typed::<Candidate>(transport, spec),
        Payload::Commit => typed::<Commit>(transport, spec),
        Payload::Lifecycle => typed::<Lifecycle>(transport, spec),
        Payload::Progress => typed::<Progress>(transport, spec),
        Payload::Truth => typed::<Truth>(transport, spec),
        Payload::Odometry => typed::<Odometry>(transport, spec),
        Payload::WheelCommand => typed::<WheelCommand>(transport, spec),
    }
}
