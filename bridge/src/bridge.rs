//! One host's end of a run's bridge: a node in the host's iceoryx2 domain, a Zenoh session,
//! a port per forwarded topic, and the loop that moves samples both ways.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use hnav_runtime::msg::Lifecycle;
use hnav_runtime::topics as run_topics;
use hnav_runtime::transport::{Bell, RunId, Sender, Transport, TransportError, Wake};
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::Subscriber;
use zenoh::qos::{CongestionControl, Priority};
use zenoh::sample::{Locality, Sample, SampleKind};
use zenoh::{Session, Wait};

use crate::delay::{Delay, DelayLine};
use crate::hosts::{self, HostsView, Peers};
use crate::outlet::Outlet;
use crate::port::{self, Counts, Port};
use crate::session::{self, Endpoints, SessionError};
use crate::topics::TopicSpec;

/// Samples from Zenoh waiting for the bridge's loop; past this they are dropped and counted
/// (a host that cannot keep up must not grow without bound).
const INBOX: usize = 4096;
/// Invalid samples named in the log one by one; after that only counted.
const LOGGED_DROPS: u64 = 20;

/// Why a bridge stopped or did not start.
#[derive(Debug, thiserror::Error)]
pub enum BridgeError {
    /// The host's iceoryx2 side failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// The Zenoh session did not open.
    #[error(transparent)]
    Session(#[from] SessionError),
    /// The test-only delay ([`crate::delay::DELAY_ENV`]) is malformed.
    #[error("{0}")]
    Delay(String),
    /// A Zenoh publisher or subscriber was not declared.
    #[error("zenoh: declare {what} on {key}: {why}")]
    Declare {
        /// `publisher` or `subscriber`.
        what: &'static str,
        /// The key expression.
        key: String,
        /// Zenoh's words.
        why: String,
    },
}

/// Ends a [`Bridge::run`] from another thread (a bridge inside a benchmark or a test).
#[derive(Clone)]
pub struct Stopper {
    flag: Arc<AtomicBool>,
    bell: Arc<Bell>,
}

impl Stopper {
    /// Asks the bridge to stop; its `run` returns after the pass under way.
    pub fn stop(&self) {
        self.flag.store(true, Ordering::Release);
        let _ = self.bell.ring();
    }
}

/// Where the Zenoh callbacks put a sample for the bridge's loop: its inbox, or the test-only
/// delay line in front of it.
#[derive(Clone)]
enum Entry {
    Direct(crossbeam_channel::Sender<(usize, Sample)>),
    Delayed(crossbeam_channel::Sender<(Instant, (usize, Sample))>),
}

impl Entry {
    /// Whether it was taken (else the queue is full).
    fn put(&self, item: (usize, Sample)) -> bool {
        match self {
            Entry::Direct(tx) => tx.try_send(item).is_ok(),
            Entry::Delayed(tx) => tx.try_send((Instant::now(), item)).is_ok(),
        }
    }
}

/// The other hosts of a placed run: this bridge's token, the subscriber to everyone's, and
/// what it publishes into its own host about them.
struct HostWatch {
    view: HostsView,
    events: crossbeam_channel::Receiver<(String, bool)>,
    ready: Sender<Lifecycle>,
    lifecycle: Sender<Lifecycle>,
    _subscriber: Subscriber<()>,
    _token: LivelinessToken,
}

/// One host's end of a run's bridge. See the [crate docs](crate).
pub struct Bridge {
    transport: Transport,
    ports: Vec<Box<dyn Port>>,
    publishers: Vec<Outlet>,
    _subscribers: Vec<Subscriber<()>>,
    hosts: Option<HostWatch>,
    // After the subscribers, whose callbacks feed it: it ends once they are gone.
    _delay: Option<DelayLine>,
    inbox: crossbeam_channel::Receiver<(usize, Sample)>,
    bell: hnav_runtime::transport::BellWatch,
    overflow: Arc<AtomicU64>,
    stopper: Stopper,
    counts: Counts,
    // Declared last: dropped after the publishers and subscribers that live in it.
    _session: Session,
}

impl Bridge {
    /// Joins `run` on this host (node `bridge`) and a Zenoh session on `endpoints`, and
    /// opens a port for each of `topics`. With `peers` (a placed run), it follows the other
    /// hosts (see [`crate::hosts`]).
    pub fn open(
        run: &RunId,
        topics: &[TopicSpec],
        endpoints: &Endpoints,
        peers: Option<Peers>,
    ) -> Result<Self, BridgeError> {
        // The session first: a client waits in it for its hub, and a bridge stopped while it
        // waits then leaves nothing in this host's shared memory.
        let session = session::open(endpoints)?;
        let transport = Transport::builder(run).node_name("bridge").create()?;
        let bell = Bell::create()?;
        let (inbox_tx, inbox) = crossbeam_channel::bounded(INBOX);
        let (delay, tx) = match Delay::from_env().map_err(BridgeError::Delay)? {
            None => (None, Entry::Direct(inbox_tx)),
            Some(d) => {
                tracing::warn!(?d, "test-only delay on every sample from another host");
                let ring = bell.try_clone()?;
                let (line, tx) = DelayLine::start(d, inbox_tx, move || {
                    let _ = ring.ring();
                });
                (Some(line), Entry::Delayed(tx))
            }
        };
        let overflow = Arc::new(AtomicU64::new(0));
        let mut ports = Vec::with_capacity(topics.len());
        let mut publishers = Vec::with_capacity(topics.len());
        let best_effort = topics.iter().any(|t| t.droppable);
        let mut subscribers = Vec::with_capacity(topics.len());
        for (i, spec) in topics.iter().enumerate() {
            ports.push(port::open(&transport, spec)?);
            let key = format!("hnav/{}/{}", run.as_str(), spec.topic);
            let declare = |what, e: zenoh::Error| BridgeError::Declare {
                what,
                key: key.clone(),
                why: e.to_string(),
            };
            // A droppable sample waits at most 100 µs for room in a full queue and goes in the
            // data queue; everything else waits (a lost decision could hold a lockstep round
            // for ever), in a queue ahead of the droppable ones when there are any.
            let (congestion, priority) = match (spec.droppable, best_effort) {
                (true, _) => (CongestionControl::Drop, Priority::Data),
                (false, true) => (CongestionControl::Block, Priority::InteractiveHigh),
                (false, false) => (CongestionControl::Block, Priority::Data),
            };
            let publisher = session
                .declare_publisher(key.clone())
                .congestion_control(congestion)
                .priority(priority)
                .express(true)
                .allowed_destination(Locality::Remote)
                .wait()
                .map_err(|e| declare("publisher", e))?;
            publishers.push(Outlet::new(publisher));
            let (tx, ring, overflow) = (tx.clone(), bell.try_clone()?, Arc::clone(&overflow));
            subscribers.push(
                session
                    .declare_subscriber(key.clone())
                    // Only other sessions: this bridge's own puts never come back.
                    .allowed_origin(Locality::Remote)
                    .callback(move |sample| {
                        if !tx.put((i, sample)) {
                            overflow.fetch_add(1, Ordering::Relaxed);
                        } else if matches!(tx, Entry::Direct(_)) {
                            // A delayed sample rings once it is released.
                            let _ = ring.ring();
                        }
                    })
                    .wait()
                    .map_err(|e| declare("subscriber", e))?,
            );
        }
        let hosts = match peers {
            None => None,
            Some(p) => Some(watch_hosts(
                &session, &transport, run, p, &bell, &mut ports, topics,
            )?),
        };
        let stopper = Stopper {
            flag: Arc::new(AtomicBool::new(false)),
            bell: Arc::new(bell.try_clone()?),
        };
        Ok(Bridge {
            transport,
            ports,
            publishers,
            _subscribers: subscribers,
            hosts,
            _delay: delay,
            inbox,
            bell: bell.into_watch()?,
            overflow,
            stopper,
            counts: Counts::default(),
            _session: session,
        })
    }

    /// A handle that ends [`run`](Self::run) from another thread.
    pub fn stopper(&self) -> Stopper {
        self.stopper.clone()
    }

    /// Waits until each of its Zenoh publishers has a subscriber on another host (their
    /// bridges are connected), for at most `timeout`; returns whether they all have. A put
    /// before that reaches nobody.
    pub fn wait_connected(&self, timeout: Duration) -> bool {
        let deadline = Instant::now() + timeout;
        self.publishers.iter().map(Outlet::publisher).all(|p| {
            // Listen first, then look: a match announced in between is not missed.
            let Ok(listener) = p.matching_listener().wait() else {
                return false;
            };
            if p.matching_status().wait().is_ok_and(|s| s.matching()) {
                return true;
            }
            // Zenoh announces a peer's subscribers on its own threads; block until it does.
            loop {
                let left = deadline.saturating_duration_since(Instant::now());
                match listener.recv_timeout(left) {
                    Ok(Some(status)) if status.matching() => return true,
                    Ok(Some(_)) if !left.is_zero() => continue,
                    _ => return false,
                }
            }
        })
    }

    /// What it has moved so far.
    pub fn counts(&self) -> Counts {
        Counts {
            overflow: self.overflow.load(Ordering::Relaxed),
            ..self.counts
        }
    }

    /// Forwards until a termination signal or `until`; returns the counts.
    pub fn run(&mut self, until: Option<Instant>) -> Result<Counts, BridgeError> {
        let waiter = self.transport.waiter()?;
        let mut attached = Vec::with_capacity(self.ports.len() + 1);
        for p in &self.ports {
            attached.push(p.attach(&waiter)?);
        }
        attached.push(waiter.attach_bell(&self.bell)?);
        loop {
            let counts = &mut self.counts;
            for (p, out) in self.ports.iter().zip(&self.publishers) {
                p.send_out(out, counts)?;
            }
            // Take the edge before draining: a sample queued after the drain rings again.
            self.bell.take();
            if let Some(h) = &mut self.hosts {
                h.pass()?;
            }
            while let Ok((i, sample)) = self.inbox.try_recv() {
                let name = sample.attachment().and_then(|a| a.try_to_string().ok());
                let port = &self.ports[i];
                match port.bring_in(&self.transport, sample.payload(), name.as_deref())? {
                    Ok(()) => {
                        counts.r#in += 1;
                        // The bridge's own receiver of the topic holds what it just
                        // published (skipped, never forwarded); on a reliable topic a full
                        // buffer of its own would hold its next publish for ever.
                        port.send_out(&self.publishers[i], counts)?;
                    }
                    Err(why) => {
                        counts.dropped += 1;
                        if counts.dropped <= LOGGED_DROPS {
                            let topic = port.topic();
                            tracing::warn!(topic, "dropped a sample from another host: {why}");
                        }
                    }
                }
            }
            let stop = || self.stopper.flag.load(Ordering::Acquire);
            if stop() || until.is_some_and(|u| Instant::now() >= u) {
                break;
            }
            if waiter.wait(until)? == Wake::Stop || stop() {
                break;
            }
        }
        drop(attached);
        Ok(self.counts())
    }
}

/// Declares this host's token and follows every host's (see [`crate::hosts`]); opens the
/// senders it tells its own host with, which the ports of `ready` and `lifecycle` then
/// never forward.
fn watch_hosts(
    session: &Session,
    transport: &Transport,
    run: &RunId,
    peers: Peers,
    bell: &Bell,
    ports: &mut [Box<dyn Port>],
    topics: &[TopicSpec],
) -> Result<HostWatch, BridgeError> {
    let mut sender = |topic: &str| -> Result<Sender<Lifecycle>, BridgeError> {
        let at = topics.iter().position(|t| t.topic == topic);
        let qos = at.map_or_else(|| run_topics::lifecycle_qos(1), |i| topics[i].qos);
        let tx = transport.sender::<Lifecycle>(topic, qos)?;
        if let Some(i) = at {
            ports[i].skip(tx.id());
        }
        Ok(tx)
    };
    let ready = sender(run_topics::READY)?;
    let lifecycle = sender(run_topics::LIFECYCLE)?;
    let declare = |what, key: &str, e: zenoh::Error| BridgeError::Declare {
        what,
        key: key.to_string(),
        why: e.to_string(),
    };
    let (tx, events) = crossbeam_channel::unbounded();
    let ring = bell.try_clone()?;
    let all = hosts::all_tokens(run.as_str());
    let prefix = hosts::token_key(run.as_str(), "");
    let subscriber = session
        .liveliness()
        .declare_subscriber(all.clone())
        .history(true)
        .callback(move |s: Sample| {
            if let Some(name) = s.key_expr().as_str().strip_prefix(&prefix) {
                let alive = s.kind() == SampleKind::Put;
                if tx.send((name.to_string(), alive)).is_ok() {
                    let _ = ring.ring();
                }
            }
        })
        .wait()
        .map_err(|e| declare("liveliness subscriber", &all, e))?;
    // Declared after every data subscriber: a host that sees this token can be heard.
    let key = hosts::token_key(run.as_str(), &peers.me);
    let token = session
        .liveliness()
        .declare_token(key.clone())
        .wait()
        .map_err(|e| declare("liveliness token", &key, e))?;
    Ok(HostWatch {
        view: HostsView::new(peers),
        events,
        ready,
        lifecycle,
        _subscriber: subscriber,
        _token: token,
    })
}

impl HostWatch {
    /// Takes in what changed among the other hosts and tells this host.
    fn pass(&mut self) -> Result<(), TransportError> {
        let mut heard = false;
        while let Ok((name, alive)) = self.events.try_recv() {
            heard = true;
            for event in self.view.on_token(&name, alive) {
                self.lifecycle.send(event)?;
            }
        }
        if let Some(up) = self.view.take_up() {
            tracing::info!("every other host heard: bridge up");
            self.ready.send(up)?;
        } else if heard && !self.view.is_up() {
            tracing::info!(waiting = ?self.view.unheard(), "hosts not heard yet");
        }
        Ok(())
    }
}
