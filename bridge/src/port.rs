//! One forwarded topic on one host: a receiver of what the host's processes publish (out to
//! Zenoh) and a sender of what other hosts published (in from Zenoh).

use std::cell::RefCell;
use std::io::Write;

use bytemuck::Zeroable;
use hnav_runtime::msg::{
    Candidate, CommitHeader, Lifecycle, MapHeader, OdometryHeader, Progress, TruthHeader,
    WheelsHeader, Wire, WireError, WireSlice,
};
use hnav_runtime::topics;
use hnav_runtime::transport::{
    Attachment, PublisherId, Qos, Receiver, Sender, SliceReceiver, SliceSender, Transport,
    TransportError, Waiter,
};
use zenoh::bytes::ZBytes;

use crate::outlet::Outlet;
use crate::topics::{Payload, TopicSpec};

/// What a bridge has moved so far.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Counts {
    /// Samples of this host's processes sent to Zenoh.
    pub out: u64,
    /// Samples of other hosts published into this host's iceoryx2.
    pub r#in: u64,
    /// Samples from Zenoh dropped as invalid (wrong type name, size or field range).
    pub dropped: u64,
    /// Samples from Zenoh dropped because the inbox was full.
    pub overflow: u64,
    /// Puts Zenoh refused.
    pub failed: u64,
}

impl Counts {
    /// Counts one put to Zenoh, sent or refused.
    pub(crate) fn put(&mut self, topic: &str, put: Result<(), String>) {
        match put {
            Ok(()) => self.out += 1,
            Err(e) => {
                self.failed += 1;
                tracing::debug!(topic, "zenoh put failed: {e}");
            }
        }
    }
}

impl core::fmt::Display for Counts {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "out={} in={} dropped={} overflow={} failed={}",
            self.out, self.r#in, self.dropped, self.overflow, self.failed
        )
    }
}

/// A topic's two directions, whatever its payload type.
pub(crate) trait Port {
    /// The topic, below `hnav/<run>/`.
    fn topic(&self) -> &str;
    /// Attaches the receiver to `waiter`.
    fn attach<'w>(&'w self, waiter: &'w Waiter) -> Result<Attachment<'w, 'w>, TransportError>;
    /// Never forwards what publisher `id` sends (one of the bridge's own, on this topic).
    fn skip(&mut self, id: PublisherId);
    /// Forwards what the host's processes published since the last call to `out`.
    fn send_out(&self, out: &Outlet, counts: &mut Counts) -> Result<(), TransportError>;
    /// Publishes `payload` from another host into iceoryx2 on `transport`, checked; `Err` is
    /// why it was dropped.
    fn bring_in(
        &self,
        transport: &Transport,
        payload: &ZBytes,
        type_name: Option<&str>,
    ) -> Result<Result<(), WireError>, TransportError>;
}

/// `Err` unless the sender named `T`.
fn expect_type<T: Wire>(type_name: Option<&str>) -> Result<(), WireError> {
    if type_name == Some(T::wire_name()) {
        Ok(())
    } else {
        Err(WireError::TypeName {
            expected: T::wire_name(),
            got: type_name.unwrap_or("(none)").to_string(),
        })
    }
}

/// The port of a topic of `T`.
struct Typed<T: Wire> {
    topic: String,
    rx: Receiver<T>,
    tx: Sender<T>,
    /// The bridge's own senders: what they published came from Zenoh (or from the bridge
    /// about this host), and must not go out.
    own: Vec<PublisherId>,
}

impl<T: Wire + Default> Port for Typed<T> {
    fn topic(&self) -> &str {
        &self.topic
    }

    fn attach<'w>(&'w self, waiter: &'w Waiter) -> Result<Attachment<'w, 'w>, TransportError> {
        waiter.attach(&self.rx)
    }

    fn skip(&mut self, id: PublisherId) {
        self.own.push(id);
    }

    fn send_out(&self, out: &Outlet, counts: &mut Counts) -> Result<(), TransportError> {
        self.rx.drain_pending_except(&self.own, |v| {
            // The sample is read in place; its bytes are copied once, into Zenoh's buffer.
            counts.put(&self.topic, out.put(v.bytes(), T::wire_name()));
        })?;
        Ok(())
    }

    fn bring_in(
        &self,
        _: &Transport,
        payload: &ZBytes,
        type_name: Option<&str>,
    ) -> Result<Result<(), WireError>, TransportError> {
        if let Err(e) = expect_type::<T>(type_name) {
            return Ok(Err(e));
        }
        // Contiguous (one Zenoh slice, the usual case below the MTU): borrowed, no copy.
        let bytes = payload.to_bytes();
        Ok(self.tx.try_send_in_place(|v| v.assign(&bytes))?.map(|_| ()))
    }
}

/// The port of a slice topic: a neural map (`map/<i>`, `f32` activations with a
/// [`MapHeader`]), the commits (`[Decision]` with a `CommitHeader`) or the ground truth
/// (`[Pose]` with a `TruthHeader`); on a link as the header's bytes followed by the
/// elements' ([`WireSlice`]).
struct Sliced<H: WireSlice> {
    topic: String,
    qos: Qos,
    rx: SliceReceiver<H::Element, H>,
    /// Opened with the first sample from another host, as long as it (a topic's slices keep
    /// their length for a run: the map's cells, the run's agents); a longer one is dropped.
    tx: RefCell<Option<SliceSender<H::Element, H>>>,
    own: RefCell<Vec<PublisherId>>,
}

impl<H: WireSlice> Sliced<H> {
    fn open(transport: &Transport, spec: &TopicSpec) -> Result<Box<dyn Port>, TransportError> {
        Ok(Box::new(Self {
            topic: spec.topic.clone(),
            qos: spec.qos,
            rx: transport.slice_receiver::<H::Element, H>(&spec.topic, spec.qos)?,
            tx: RefCell::new(None),
            own: RefCell::new(Vec::new()),
        }))
    }
}

impl<H: WireSlice> Port for Sliced<H> {
    fn topic(&self) -> &str {
        &self.topic
    }

    fn attach<'w>(&'w self, waiter: &'w Waiter) -> Result<Attachment<'w, 'w>, TransportError> {
        waiter.attach(&self.rx)
    }

    fn skip(&mut self, id: PublisherId) {
        self.own.get_mut().push(id);
    }

    fn send_out(&self, out: &Outlet, counts: &mut Counts) -> Result<(), TransportError> {
        let own = self.own.borrow();
        self.rx.drain_pending_except(&own, |h, values| {
            let mut w = ZBytes::writer();
            // Copied once, into Zenoh's buffer: the header, then the elements.
            let written = w
                .write_all(h.bytes())
                .and_then(|()| w.write_all(bytemuck::cast_slice(values)));
            let put = written
                .map_err(|e| e.to_string())
                .and_then(|()| out.put(w.finish(), H::wire_name()));
            counts.put(&self.topic, put);
        })?;
        Ok(())
    }

    fn bring_in(
        &self,
        transport: &Transport,
        payload: &ZBytes,
        type_name: Option<&str>,
    ) -> Result<Result<(), WireError>, TransportError> {
        if let Err(e) = expect_type::<H>(type_name) {
            return Ok(Err(e));
        }
        let bytes = payload.to_bytes();
        let (header, elements) = match H::from_wire(&bytes) {
            Ok(read) => read,
            Err(e) => return Ok(Err(e)),
        };
        let len = elements.len() / core::mem::size_of::<H::Element>().max(1);
        let mut tx = self.tx.borrow_mut();
        if tx.is_none() {
            let sender = transport.slice_sender::<H::Element, H>(&self.topic, len, self.qos)?;
            self.own.borrow_mut().push(sender.id());
            *tx = Some(sender);
        }
        let tx = tx.as_ref().expect("opened above");
        if len > tx.max_len() {
            return Ok(Err(H::field(format!(
                "{len} elements, over the {} this host's topic was opened for",
                tx.max_len()
            ))));
        }
        let mut loan = tx.loan(len)?;
        *loan.header_mut() = header;
        // Each element written once, straight from the link's bytes, then checked in place;
        // a sample that fails the check is dropped unsent.
        let sent = loan.fill_with(H::Element::zeroed(), |out| {
            header
                .elements_from_wire(elements, out)
                .map_err(Refused::Wire)
        });
        match sent {
            Ok(_) => Ok(Ok(())),
            Err(Refused::Wire(e)) => Ok(Err(e)),
            Err(Refused::Transport(e)) => Err(e),
        }
    }
}

/// Why a slice from another host was not published here.
enum Refused {
    /// Its elements failed their check.
    Wire(WireError),
    /// Shared memory refused it.
    Transport(TransportError),
}

impl From<TransportError> for Refused {
    fn from(e: TransportError) -> Self {
        Self::Transport(e)
    }
}

/// The name a Raft message crosses under (`raft/<i>`): its bytes are Raft's protobuf, which
/// the replica decodes and drops if it does not decode (`coordinator::replication::wire`).
pub const RAFT_WIRE_NAME: &str = "hnav::RaftMessage";

/// The port of a coordinator replica's Raft inbox (`raft/<i>`): bytes of any length up to
/// [`topics::RAFT_MAX_BYTES`], as they are.
struct Raft {
    topic: String,
    rx: SliceReceiver<u8, ()>,
    tx: SliceSender<u8, ()>,
    own: Vec<PublisherId>,
}

impl Port for Raft {
    fn topic(&self) -> &str {
        &self.topic
    }

    fn attach<'w>(&'w self, waiter: &'w Waiter) -> Result<Attachment<'w, 'w>, TransportError> {
        waiter.attach(&self.rx)
    }

    fn skip(&mut self, id: PublisherId) {
        self.own.push(id);
    }

    fn send_out(&self, out: &Outlet, counts: &mut Counts) -> Result<(), TransportError> {
        self.rx.drain_pending_except(&self.own, |(), bytes| {
            counts.put(&self.topic, out.put(bytes, RAFT_WIRE_NAME));
        })?;
        Ok(())
    }

    fn bring_in(
        &self,
        _: &Transport,
        payload: &ZBytes,
        type_name: Option<&str>,
    ) -> Result<Result<(), WireError>, TransportError> {
        if type_name != Some(RAFT_WIRE_NAME) {
            return Ok(Err(WireError::TypeName {
                expected: RAFT_WIRE_NAME,
                got: type_name.unwrap_or("(none)").to_string(),
            }));
        }
        let bytes = payload.to_bytes();
        if bytes.len() > self.tx.max_len() {
            return Ok(Err(WireError::Field {
                type_name: RAFT_WIRE_NAME,
                what: format!(
                    "{} bytes, over the topic's {}",
                    bytes.len(),
                    self.tx.max_len()
                ),
            }));
        }
        self.tx.loan(bytes.len())?.copy_and_send(&bytes)?;
        Ok(Ok(()))
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
            own: vec![tx.id()],
            rx,
            tx,
        }))
    }
    match spec.payload {
        Payload::Candidate => typed::<Candidate>(transport, spec),
        Payload::Commit => Sliced::<CommitHeader>::open(transport, spec),
        Payload::Lifecycle => typed::<Lifecycle>(transport, spec),
        Payload::Progress => typed::<Progress>(transport, spec),
        Payload::Truth => Sliced::<TruthHeader>::open(transport, spec),
        Payload::Odometry => Sliced::<OdometryHeader>::open(transport, spec),
        Payload::WheelCommand => Sliced::<WheelsHeader>::open(transport, spec),
        Payload::Raft => {
            let tx =
                transport.slice_sender::<u8, ()>(&spec.topic, topics::RAFT_MAX_BYTES, spec.qos)?;
            Ok(Box::new(Raft {
                topic: spec.topic.clone(),
                own: vec![tx.id()],
                rx: transport.slice_receiver::<u8, ()>(&spec.topic, spec.qos)?,
                tx,
            }))
        }
        Payload::Map => Sliced::<MapHeader>::open(transport, spec),
    }
}
