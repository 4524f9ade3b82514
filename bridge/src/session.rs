//! The Zenoh session of a bridge: its mode, the endpoints it listens on and connects to,
//! multicast scouting off (it would find every Zenoh process on the network; a run names its
//! hosts).
//!
//! A placed run is a star: the hub (the placement's first host) is a Zenoh router and every
//! other host a client of it. Zenoh 1.10's peer-to-peer routing was tried first, as a full
//! mesh: with one of three peers cut off, the two others sometimes stopped hearing each other
//! until the third came back (about 1 run in 11 of the partition test under load), which
//! looks like eclipse-zenoh/zenoh#2581 (peers' routing stalled behind a link being torn
//! down). A client has one link, to the router, and the router's tables are its own.

use zenoh::{Config, Session, Wait};

/// How a bridge's session joins the others (Zenoh's modes).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Mode {
    /// A peer: links to the endpoints it is given and accepts links on its own (two bridges
    /// joined by `--listen`/`--connect`).
    #[default]
    Peer,
    /// The hub of a placed run: a router the other hosts connect to, which forwards between
    /// them.
    Router,
    /// Any other host of a placed run: a client of the hub, which waits for it at start and
    /// reconnects when its link is lost.
    Client,
}

impl Mode {
    fn name(self) -> &'static str {
        match self {
            Mode::Peer => "peer",
            Mode::Router => "router",
            Mode::Client => "client",
        }
    }
}

/// Where a bridge's session listens and what it connects to: Zenoh endpoints such as
/// `tcp/10.0.0.2:7447` or `udp/10.0.0.2:7447`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Endpoints {
    /// The session's mode.
    pub mode: Mode,
    /// Endpoints to listen on.
    pub listen: Vec<String>,
    /// Endpoints of other bridges to connect to.
    pub connect: Vec<String>,
}

/// Why a session did not open.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The configuration was refused (an endpoint that does not parse).
    #[error("zenoh configuration: {0}")]
    Config(String),
    /// The session did not open (an address in use, a peer unreachable).
    #[error("open the zenoh session: {0}")]
    Open(String),
}

/// How long a link may stay silent before Zenoh declares it dead, in ms (Zenoh's default is
/// 10 s): a host cut off is noticed within this, and its robots stand.
pub const LEASE_MS: u64 = 1000;

/// How long a reliable put may wait for room in a link's queue before Zenoh gives the link
/// up, in µs (Zenoh's default is 5 s): a link cut off fills its queue, and the bridge's loop
/// must not stand still for every host meanwhile.
const BLOCK_BEFORE_CLOSE_US: u64 = LEASE_MS * 1000;

/// The session's configuration as JSON5; everything not set is zenoh 1.10.2's default.
/// Besides the endpoints: the lease ([`LEASE_MS`], with 4 keep-alives in it); a lost
/// connection retried every 100 ms doubling to at most 500 ms, so that a healed link is used
/// again within about half a second; a state sample (droppable: the next one supersedes it)
/// waits at most 100 µs for room in a full queue, a decision at most one lease. A client
/// waits for its router however long it takes (Zenoh's default gives up at once): hosts start
/// in any order, and the supervisor bounds the wait.
pub fn config_json5(endpoints: &Endpoints) -> String {
    let quote = |v: &[String]| {
        v.iter()
            .map(|e| format!("{e:?}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    format!(
        r#"{{
  mode: "{}",
  listen: {{ endpoints: [{}] }},
  connect: {{
    endpoints: [{}],
    timeout_ms: {{ client: -1 }},
    exit_on_failure: {{ client: false }},
    retry: {{ period_init_ms: 100, period_max_ms: 500, period_increase_factor: 2 }},
  }},
  scouting: {{ multicast: {{ enabled: false }}, gossip: {{ enabled: false }} }},
  transport: {{ link: {{ tx: {{
    lease: {LEASE_MS},
    keep_alive: 4,
    queue: {{ congestion_control: {{
      drop: {{ wait_before_drop: 100 }},
      block: {{ wait_before_close: {BLOCK_BEFORE_CLOSE_US} }},
    }} }},
  }} }} }},
}}"#,
        endpoints.mode.name(),
        quote(&endpoints.listen),
        quote(&endpoints.connect)
    )
}

/// Opens a session for `endpoints`.
pub fn open(endpoints: &Endpoints) -> Result<Session, SessionError> {
    let json = config_json5(endpoints);
    let config = Config::from_json5(&json).map_err(|e| SessionError::Config(e.to_string()))?;
    zenoh::open(config)
        .wait()
        .map_err(|e| SessionError::Open(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_config_parses_and_a_bad_endpoint_is_refused() {
        for mode in [Mode::Peer, Mode::Router, Mode::Client] {
            let ok = Endpoints {
                mode,
                listen: vec!["tcp/127.0.0.1:7447".into()],
                connect: vec!["tcp/127.0.0.1:7448".into()],
            };
            Config::from_json5(&config_json5(&ok)).unwrap();
        }
        let bad = Endpoints {
            listen: vec!["nonsense".into()],
            ..Endpoints::default()
        };
        assert!(matches!(
            open(&bad),
            Err(SessionError::Config(_) | SessionError::Open(_))
        ));
    }
}
