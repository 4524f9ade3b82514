//! The live Foxglove view: a run served on the Foxglove WebSocket protocol (the `foxglove`
//! crate's server), for Foxglove to connect to (`hnav run --foxglove [ADDR]`,
//! `hnav view RUN --foxglove [ADDR]`).
//!
//! The crate negotiates the protocol under the subprotocol name `foxglove.sdk.v1` (or
//! `foxglove.sdk.v1.1`), Foxglove's current name for the protocol first published as
//! `foxglove.websocket.v1`, with the same messages and binary frames; a client that offers
//! only the old name is refused with HTTP 400 (Foxglove's own app offers the new one).
//!
//! ```text
//!   a Feed (live: the run's topics; playback: a run directory) ── Update ──> SceneFold ──> Server ──> clients
//! ```
//!
//! The data comes from a [`Feed`], the same as `hnav top`'s: [`LiveFeed`](crate::monitor::live::LiveFeed)
//! reads a live run's topics without back-pressure, [`PlaybackFeed`](crate::monitor::playback::PlaybackFeed)
//! plays a finished run's recording back. [`SceneFold`] turns its updates into the messages of
//! [`channels::shown`], the channels the MCAP export writes too, and [`Server`] sends them to
//! whoever subscribed.
//!
//! [`show`] pumps the feed every [`DRAIN`] and folds only the newest ground truth of each pump
//! (the scene at most 50 times a second, however fast a lockstep run goes); every commit and
//! process event it saw goes to `/log`. A client that subscribes gets the map and the scene at
//! once, not at the next change. The server's work runs on the `foxglove` crate's own tokio
//! threads, the pumping on the caller's: in `hnav run` a thread of its own ([`live`]), so the
//! supervisor never waits for a viewer. A slow or vanished client loses messages, nothing
//! else.
//!
//! | module | what it holds |
//! |---|---|
//! | [`live`] | the view of the run this process supervises, on a thread of its own |

pub mod live;

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use ::foxglove::websocket::{ChannelView, Client, ServerListener};
use ::foxglove::{
    ChannelBuilder, Context, PartialMetadata, RawChannel, Schema, WebSocketServer,
    WebSocketServerHandle,
};

use iceoryx2_bb_posix::signal::SignalHandler;

use crate::channels::scene::{Picture, SceneFold};
use crate::channels::{self, Message};
use crate::monitor::feed::{Feed, FeedError, RunEnd, Update, Waited};
use crate::recording::world::apply_due;
use hnav_runtime::msg::Truth;

/// Where the view listens without an address given.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8765";
/// The longest [`show`] sleeps in the feed between two pumps.
pub const DRAIN: Duration = Duration::from_millis(20);

/// Why the view could not start.
#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    /// `--foxglove` was given something that is not `HOST:PORT` with a numeric host.
    #[error("--foxglove {given}: not an address to listen on ({problem}); give IP:PORT, e.g. {DEFAULT_ADDR}")]
    Address {
        /// What was given.
        given: String,
        /// Why it does not parse.
        problem: String,
    },
    /// The address cannot be listened on (in use, not this machine's, a privileged port).
    #[error("--foxglove {addr}: cannot listen there: {problem}")]
    Listen {
        /// The address.
        addr: SocketAddr,
        /// Why.
        problem: String,
    },
}

/// Parses `--foxglove`'s value.
pub fn parse_addr(given: &str) -> Result<SocketAddr, ViewerError> {
    given
        .parse()
        .map_err(|e: std::net::AddrParseError| ViewerError::Address {
            given: given.to_string(),
            problem: e.to_string(),
        })
}

/// Set by a client's subscription: the map and the scene are due again.
#[derive(Default)]
struct Subscribed(AtomicBool);

impl ServerListener for Subscribed {
    fn on_subscribe(&self, _client: Client, _channel: ChannelView) {
        self.0.store(true, Ordering::Relaxed);
    }
}

/// The WebSocket server and its channels.
pub struct Server {
    context: Arc<Context>,
    handle: Option<WebSocketServerHandle>,
    addr: SocketAddr,
    subscribed: Arc<Subscribed>,
    channels: BTreeMap<String, Arc<RawChannel>>,
}

impl Server {
    /// Listens on `addr` (port 0: any free port, [`Server::addr`] says which).
    pub fn bind(addr: SocketAddr) -> Result<Server, ViewerError> {
        // The crate's server does not report a port in use on every path; a plain listener
        // does, and is closed again before the server binds.
        let probe = std::net::TcpListener::bind(addr).map_err(|e| ViewerError::Listen {
            addr,
            problem: e.to_string(),
        })?;
        let free = probe.local_addr().unwrap_or(addr);
        drop(probe);
        let context = Context::new();
        let subscribed = Arc::new(Subscribed::default());
        let handle = WebSocketServer::new()
            .name(concat!("hnav ", env!("CARGO_PKG_VERSION")))
            .bind(free.ip().to_string(), free.port())
            .context(&context)
            .listener(subscribed.clone())
            .start_blocking()
            .map_err(|e| ViewerError::Listen {
                addr,
                problem: e.to_string(),
            })?;
        let addr = SocketAddr::new(free.ip(), handle.port());
        Ok(Server {
            context,
            handle: Some(handle),
            addr,
            subscribed,
            channels: BTreeMap::new(),
        })
    }

    /// The address it listens on.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Advertises `set` to every client, now and later (channels already there stay).
    pub fn advertise(&mut self, set: &[channels::Channel]) {
        for c in set {
            if self.channels.contains_key(&c.topic) {
                continue;
            }
            let built = ChannelBuilder::new(c.topic.clone())
                .context(&self.context)
                .message_encoding(channels::MESSAGE_ENCODING)
                .schema(Schema::new(
                    c.schema,
                    channels::SCHEMA_ENCODING,
                    channels::schemas::schema(c.schema),
                ))
                .build_raw();
            match built {
                Ok(ch) => {
                    self.channels.insert(c.topic.clone(), ch);
                }
                Err(e) => tracing::warn!("foxglove channel {}: {e}", c.topic),
            }
        }
    }

    /// Sends `m` to the clients subscribed to its channel (none: dropped at once).
    pub fn publish(&self, m: &Message) {
        let Some(ch) = self.channels.get(&m.topic) else {
            return;
        };
        if !ch.has_sinks() {
            return;
        }
        match serde_json::to_vec(&m.body) {
            Ok(bytes) => ch.log_with_meta(&bytes, PartialMetadata::with_log_time(m.t_ns)),
            Err(e) => tracing::warn!("foxglove {}: {e}", m.topic),
        }
    }

    /// Whether a client subscribed since the last call.
    fn take_subscribed(&self) -> bool {
        self.subscribed.0.swap(false, Ordering::Relaxed)
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        if let Some(h) = self.handle.take() {
            h.stop().wait_blocking();
        }
    }
}

impl std::fmt::Debug for Server {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Server")
            .field("addr", &self.addr)
            .field("channels", &self.channels.len())
            .finish_non_exhaustive()
    }
}

/// How [`show`] ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shown {
    /// The run ended (and the caller asked to stop then).
    RunEnded(RunEnd),
    /// SIGINT or SIGTERM.
    Signal,
    /// `stop` was set.
    Stopped,
}

/// Serves what `feed` yields on `server` until the run ends (with `exit_on_end`), a signal,
/// or `stop`. See the [module docs](self).
pub fn show(
    feed: &mut dyn Feed,
    server: &mut Server,
    exit_on_end: bool,
    stop: &AtomicBool,
) -> Result<Shown, FeedError> {
    let info = feed.info().clone();
    let mut fold = SceneFold::new(Picture {
        grid: info.grid.clone(),
        goals: info.goals.clone(),
        cell_m: info.cell_size_m,
    });
    let robots = info.goals.len();
    server.advertise(&channels::shown(robots));
    let mut world = info.grid.clone();
    let mut applied = 0;
    let mut latest = Truth::default();
    let mut now_ns = 0;
    let mut ended = None;
    loop {
        if stop.load(Ordering::Relaxed) {
            return Ok(Shown::Stopped);
        }
        if ended.is_some() {
            // A feed that has ended does not wait any more: keep serving, without spinning.
            std::thread::sleep(DRAIN);
            if SignalHandler::termination_requested() {
                return Ok(Shown::Signal);
            }
        } else if feed.wait(Instant::now() + DRAIN)? == Waited::Stop {
            return Ok(Shown::Signal);
        }
        let mut fresh = false;
        let mut out: Vec<Message> = Vec::new();
        feed.pump(&mut |u| match u {
            Update::Truth(t) => {
                latest.set(t);
                now_ns = now_ns.max(t.sim_time_ns());
                fresh = true;
            }
            Update::Commit(c) => out.extend(fold.commit(now_ns, c)),
            Update::Lifecycle(l) => out.extend(fold.lifecycle(now_ns, l.role, l.index, l.event)),
            Update::Movers(m) => fold.movers(m),
            Update::Ended(why) => ended = Some(why),
            _ => {}
        })?;
        let changed = apply_due(&mut world, &info.changes, &mut applied, now_ns);
        let map_due = server.take_subscribed() | changed;
        if map_due {
            server.publish(&fold.map(&world, now_ns));
            if !fresh {
                server.publish(&fold.scene(now_ns));
            }
        }
        if fresh {
            for m in fold.truth(latest.view()) {
                server.publish(&m);
            }
            for i in 0..latest.poses().len().min(robots) {
                server.publish(&SceneFold::pose_in_frame(latest.view(), i));
            }
        }
        for m in &out {
            server.publish(m);
        }
        if let Some(why) = ended.filter(|_| exit_on_end) {
            return Ok(Shown::RunEnded(why));
        }
    }
}
