//! One forwarded topic on one host: a receiver of what the host's processes publish (out to
//! Zenoh) and a sender of what other hosts published (in from Zenoh).

use std::cell::RefCell;
use std::io::Write;

use hnav_runtime::msg::{
    Candidate, Commit, Lifecycle, MapHeader, Odometry, Progress, Truth, WheelCommand, Wire,
    WireError,
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

/// The port of a neural-map topic (`map/<i>`): `f32` activations with a [`MapHeader`],
/// on a link as the header's bytes followed by the activations'.
struct Map {
    topic: String,
    qos: Qos,
    rx: SliceReceiver<f32, MapHeader>,
    /// Opened with the first snapshot from another host, as long as it (a map keeps its
    /// size for a run); a longer one is dropped.
    tx: RefCell<Option<SliceSender<f32, MapHeader>>>,
    own: RefCell<Vec<PublisherId>>,
}

const HEADER: usize = core::mem::size_of::<MapHeader>();

impl Port for Map {
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
            // Copied once, into Zenoh's buffer: the header, then the activations.
            let written = w
                .write_all(h.bytes())
                .and_then(|()| w.write_all(bytemuck::cast_slice(values)));
            let put = written
                .map_err(|e| e.to_string())
                .and_then(|()| out.put(w.finish(), MapHeader::wire_name()));
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
        if let Err(e) = expect_type::<MapHeader>(type_name) {
            return Ok(Err(e));
        }
        let bytes = payload.to_bytes();
        let field = |what: String| WireError::Field {
            type_name: MapHeader::wire_name(),
            what,
        };
        if bytes.len() < HEADER || !(bytes.len() - HEADER).is_multiple_of(4) {
            return Ok(Err(field(format!(
                "{} bytes are no header and whole f32 activations",
                bytes.len()
            ))));
        }
        let mut header = MapHeader::default();
        if let Err(e) = header.assign(&bytes[..HEADER]) {
            return Ok(Err(e));
        }
        let values = &bytes[HEADER..];
        let len = values.len() / 4;
        let mut tx = self.tx.borrow_mut();
        if tx.is_none() {
            let sender = transport.slice_sender::<f32, MapHeader>(&self.topic, len, self.qos)?;
            self.own.borrow_mut().push(sender.id());
            *tx = Some(sender);
        }
        let tx = tx.as_ref().expect("opened above");
        if len > tx.max_len() {
            return Ok(Err(field(format!(
                "{len} activations, over the {} this host's map topic was opened for",
                tx.max_len()
            ))));
        }
        let mut loan = tx.loan(len)?;
        *loan.header_mut() = header;
        // Each element written once, straight from the link's bytes (no memset first).
        loan.fill_and_send(|i| {
            let b = &values[4 * i..4 * i + 4];
            f32::from_ne_bytes([b[0], b[1], b[2], b[3]])
        })?;
        Ok(Ok(()))
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
        Payload::Commit => typed::<Commit>(transport, spec),
        Payload::Lifecycle => typed::<Lifecycle>(transport, spec),
        Payload::Progress => typed::<Progress>(transport, spec),
        Payload::Truth => typed::<Truth>(transport, spec),
        Payload::Odometry => typed::<Odometry>(transport, spec),
        Payload::WheelCommand => typed::<WheelCommand>(transport, spec),
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
        Payload::Map => Ok(Box::new(Map {
            topic: spec.topic.clone(),
            qos: spec.qos,
            rx: transport.slice_receiver::<f32, MapHeader>(&spec.topic, spec.qos)?,
            tx: RefCell::new(None),
            own: RefCell::new(Vec::new()),
        })),
    }
}
