//! The Zenoh session of `hnav-ros2`: a peer of the ROS 2 graph's router, as every
//! `rmw_zenoh_cpp` context is (`DEFAULT_RMW_ZENOH_SESSION_CONFIG.json5`: peer mode, the
//! router at `tcp/localhost:7447`, multicast scouting off, gossip on so that peers find each
//! other through the router), or, when asked ([`Role::Router`]), the router itself.

use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::Duration;

use zenoh::{Config, Session, Wait};

/// rmw_zenoh's default router endpoint.
pub const DEFAULT_ROUTER: &str = "tcp/localhost:7447";

/// Where a router HNAV starts itself listens: the default's port, on loopback only.
pub const OWN_ROUTER_LISTEN: &str = "tcp/127.0.0.1:7447";

/// How the session joins the graph.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Role {
    /// A peer connected to the router at this endpoint (retried in the background while it
    /// does not answer).
    Peer(String),
    /// The router itself, listening at this endpoint.
    Router(String),
}

/// Why the session did not open.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The configuration was refused (an endpoint that does not parse).
    #[error("zenoh configuration: {0}")]
    Config(String),
    /// The session did not open (the router's address in use, ...).
    #[error("open the zenoh session: {0}")]
    Open(String),
}

/// The session's configuration as JSON5; what is not set is Zenoh 1.10.2's default. A peer
/// waits up to a second for its router at start and then goes on retrying in the
/// background, so that a router started after the run is joined when it comes.
pub fn config_json5(role: &Role) -> String {
    match role {
        Role::Peer(router) => format!(
            r#"{{
  mode: "peer",
  connect: {{
    endpoints: [{router:?}],
    timeout_ms: {{ peer: 1000 }},
    exit_on_failure: {{ peer: false }},
    retry: {{ period_init_ms: 200, period_max_ms: 2000, period_increase_factor: 2 }},
  }},
  listen: {{ endpoints: ["tcp/localhost:0"] }},
  scouting: {{ multicast: {{ enabled: false }}, gossip: {{ enabled: true }} }},
}}"#
        ),
        Role::Router(listen) => format!(
            r#"{{
  mode: "router",
  listen: {{ endpoints: [{listen:?}] }},
  scouting: {{ multicast: {{ enabled: false }}, gossip: {{ enabled: true }} }},
}}"#
        ),
    }
}

/// Opens the session.
pub fn open(role: &Role) -> Result<Session, SessionError> {
    let config =
        Config::from_json5(&config_json5(role)).map_err(|e| SessionError::Config(e.to_string()))?;
    zenoh::open(config)
        .wait()
        .map_err(|e| SessionError::Open(e.to_string()))
}

/// Whether something accepts TCP connections at the Zenoh endpoint `endpoint`
/// (`tcp/HOST:PORT`) within `timeout`. Any other protocol is taken to answer: only TCP is
/// probed.
pub fn answers(endpoint: &str, timeout: Duration) -> bool {
    let Some(addr) = endpoint.strip_prefix("tcp/") else {
        return true;
    };
    // Zenoh endpoints may carry `#config` or `?metadata` after the address.
    let addr = addr.split(['#', '?']).next().unwrap_or(addr);
    let addrs: Vec<SocketAddr> = match addr.to_socket_addrs() {
        Ok(a) => a.collect(),
        Err(_) => return false,
    };
    addrs
        .iter()
        .any(|a| TcpStream::connect_timeout(a, timeout).is_ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_configurations_parse() {
        for role in [
            Role::Peer(DEFAULT_ROUTER.into()),
            Role::Router(OWN_ROUTER_LISTEN.into()),
        ] {
            Config::from_json5(&config_json5(&role)).unwrap();
        }
    }

    #[test]
    fn a_closed_port_does_not_answer_and_a_listener_does() {
        let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let port = l.local_addr().unwrap().port();
        assert!(answers(
            &format!("tcp/127.0.0.1:{port}"),
            Duration::from_secs(1)
        ));
        drop(l);
        assert!(!answers(
            &format!("tcp/127.0.0.1:{port}"),
            Duration::from_millis(200)
        ));
        assert!(!answers(
            "tcp/no-such-host.invalid:1",
            Duration::from_millis(200)
        ));
    }
}
