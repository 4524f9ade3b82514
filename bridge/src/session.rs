//! The Zenoh session of a bridge: peer mode, the endpoints it listens on and connects to,
//! multicast scouting off (it would find every Zenoh process on the network; a run names its
//! peers).

use zenoh::{Config, Session, Wait};

/// Where a bridge's session listens and what it connects to: Zenoh endpoints such as
/// `tcp/10.0.0.2:7447` or `udp/10.0.0.2:7447`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Endpoints {
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
/// waits at most 100 µs for room in a full queue, a decision at most one lease.
pub fn config_json5(endpoints: &Endpoints) -> String {
    let quote = |v: &[String]| {
        v.iter()
            .map(|e| format!("{e:?}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    format!(
        r#"{{
  mode: "peer",
  listen: {{ endpoints: [{}] }},
  connect: {{
    endpoints: [{}],
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
        let ok = Endpoints {
            listen: vec!["tcp/127.0.0.1:7447".into()],
            connect: vec!["tcp/127.0.0.1:7448".into()],
        };
        Config::from_json5(&config_json5(&ok)).unwrap();
        let bad = Endpoints {
            listen: vec!["nonsense".into()],
            connect: Vec::new(),
        };
        assert!(matches!(
            open(&bad),
            Err(SessionError::Config(_) | SessionError::Open(_))
        ));
    }
}
