//! `hnav services RUN`: a live run's topics with their publishers and subscribers, like
//! `ros2 topic list -v`.
//!
//! The run is found in the registry as `hnav kill` finds it ([`RunRegistry::find_live`]).
//! iceoryx2 lists a run's services from its config alone ([`Ipc::list`]: name, payload type,
//! QoS); who publishes and who subscribes is in each service's dynamic config, which only a
//! node that opens the service can read. So this joins the run with a node of its own
//! (`hnav-services`, which opens each service with its payload type and creates no port) and
//! names each port's node and process from the run's node list. That node never cleans up
//! dead nodes of the run: that is the supervisor's job, with the events it sends.
//!
//! Every data service has an event service of the same name beside it (its publishers'
//! notifiers and its subscribers' listeners); those are not listed.

use std::collections::HashMap;

use iceoryx2::node::{Node, NodeState, NodeView};
use iceoryx2::prelude::{
    CallbackProgression, NodeBuilder, NodeName, ServiceName, SignalHandlingMode, ZeroCopySend,
};
use iceoryx2::service::port_factory::PortFactory;
use iceoryx2::service::static_config::message_type_details::TypeVariant;
use iceoryx2::service::static_config::messaging_pattern::MessagingPattern;
use iceoryx2::service::Service as _;
use serde::Serialize;

use super::registry::{LiveRunError, RunRegistry};
use hnav_runtime::msg::{
    Candidate, CommitHeader, Decision, Estimate, Heartbeat, Lifecycle, MapHeader, MoverPlace,
    MoversHeader, Odometry, OdometryHeader, Pose, Progress, Sighting, TruthHeader, View,
    ViewsHeader, WheelCommand, WheelsHeader, WorldHeader,
};
use hnav_runtime::transport::{run_config, Ipc, TransportError};

/// Why `hnav services` listed nothing.
#[derive(Debug, thiserror::Error)]
pub enum ServicesError {
    /// The run is not a live one.
    #[error(transparent)]
    Live(#[from] LiveRunError),
    /// The run's services or nodes could not be read.
    #[error(transparent)]
    Transport(#[from] TransportError),
}

/// The node and process of one port.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Endpoint {
    /// The node's name (`agent-3`, `coordinator`, ...; empty if it has none).
    pub node: String,
    /// Its process id, if the node can be inspected.
    pub pid: Option<i32>,
}

/// One publish-subscribe service of the run.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct TopicStatus {
    /// The topic, below `hnav/<run-id>/`.
    pub topic: String,
    /// The full service name.
    pub service: String,
    /// The payload's type name (`[f32]` for a slice of `f32`).
    pub payload: String,
    /// The user header's type name, if it has one.
    pub user_header: Option<String>,
    /// Samples kept for late joiners.
    pub history: usize,
    /// A subscriber's buffer at most.
    pub buffer: usize,
    /// Whether a full buffer overwrites its oldest sample (else the publisher waits).
    pub overflow: bool,
    /// Publishers admitted.
    pub max_publishers: usize,
    /// Subscribers admitted.
    pub max_subscribers: usize,
    /// The publishers, in the order iceoryx2 lists them.
    pub publishers: Vec<Endpoint>,
    /// The subscribers.
    pub subscribers: Vec<Endpoint>,
}

/// What `hnav services RUN` reports.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ServicesReport {
    /// The run id.
    pub run_id: String,
    /// Every publish-subscribe service, in topic order (`map/2` before `map/10`).
    pub topics: Vec<TopicStatus>,
}

/// The name of the node that reads the services.
pub const NODE_NAME: &str = "hnav-services";

/// Lists the topics of the live run `run` of `registry`. See the [module docs](self).
pub fn services(registry: &RunRegistry, run: &str) -> Result<ServicesReport, ServicesError> {
    let (id, _) = registry.find_live(run)?;
    let mut config = run_config(&id);
    config.global.node.cleanup_dead_nodes_on_creation = false;
    config.global.node.cleanup_dead_nodes_on_destruction = false;
    config.global.service.cleanup_dead_nodes_on_open = false;
    let name =
        NodeName::new(NODE_NAME).map_err(|e| TransportError::ipc("name node", NODE_NAME, e))?;
    let node = NodeBuilder::new()
        .config(&config)
        .name(&name)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<Ipc>()
        .map_err(|e| TransportError::ipc("create node", NODE_NAME, e))?;
    let mut found = Vec::new();
    Ipc::list(&config, |s| {
        if matches!(
            s.static_details.messaging_pattern(),
            MessagingPattern::PublishSubscribe(_)
        ) {
            found.push(s.static_details);
        }
        CallbackProgression::Continue
    })
    .map_err(|e| TransportError::ipc("list services", "", e))?;
    let nodes = node_names(&node)?;
    let prefix = format!("hnav/{}/", id.as_str());
    let mut topics = Vec::new();
    for s in found {
        let service = s.name().as_str().to_string();
        let ps = s.publish_subscribe();
        let types = ps.message_type_details();
        let element = types.payload.type_name().to_string();
        let header = types.user_header.type_name().to_string();
        let slice = types.payload.variant() == TypeVariant::Dynamic;
        // A service that went away between the list and the open (the run ending) is left
        // out; one whose types HNAV does not know is listed without its ports.
        let ports = match open_ports(&node, s.name(), &element, slice, &header) {
            Some(Ok(p)) => p,
            Some(Err(_)) => continue,
            None => (Vec::new(), Vec::new()),
        };
        let named = |ids: Vec<u128>| -> Vec<Endpoint> {
            ids.into_iter()
                .map(|n| {
                    nodes.get(&n).cloned().unwrap_or(Endpoint {
                        node: String::new(),
                        pid: None,
                    })
                })
                .collect()
        };
        topics.push(TopicStatus {
            topic: service
                .strip_prefix(&prefix)
                .unwrap_or(&service)
                .to_string(),
            service,
            payload: if slice {
                format!("[{element}]")
            } else {
                element
            },
            user_header: (header != "()").then_some(header),
            history: ps.history_size(),
            buffer: ps.subscriber_max_buffer_size(),
            overflow: ps.has_safe_overflow(),
            max_publishers: ps.max_publishers(),
            max_subscribers: ps.max_subscribers(),
            publishers: named(ports.0),
            subscribers: named(ports.1),
        });
    }
    topics.sort_by(|a, b| natural_key(&a.topic).cmp(&natural_key(&b.topic)));
    Ok(ServicesReport {
        run_id: id.as_str().to_string(),
        topics,
    })
}

/// Every node of the run by id, with its name and pid.
fn node_names(node: &Node<Ipc>) -> Result<HashMap<u128, Endpoint>, TransportError> {
    let mut out = HashMap::new();
    Node::<Ipc>::list(node.config(), |state| {
        let entry = match &state {
            NodeState::Alive(v) => Some((v.id().value(), endpoint(v.details()))),
            NodeState::Dead(v) => Some((v.id().value(), endpoint(v.details()))),
            NodeState::Inaccessible(_) | NodeState::Undefined(_) => None,
        };
        if let Some((id, e)) = entry {
            out.insert(id, e);
        }
        CallbackProgression::Continue
    })
    .map_err(|e| TransportError::ipc("list nodes", "", e))?;
    Ok(out)
}

fn endpoint(details: &Option<iceoryx2::node::NodeDetails>) -> Endpoint {
    match details {
        Some(d) => Endpoint {
            node: d.name().as_str().to_string(),
            pid: Some(d.process_id().value()),
        },
        None => Endpoint {
            node: String::new(),
            pid: None,
        },
    }
}

/// Opens the service `name` with its types (a macro: iceoryx2's builder has separate `open`
/// impls for sized and slice payloads) and lists the node ids of its ports.
macro_rules! ports_of {
    ($node:expr, $name:expr, $payload:ty, $header:ty) => {
        $node
            .service_builder($name)
            .publish_subscribe::<$payload>()
            .user_header::<$header>()
            .open()
            .map_err(|e| TransportError::ipc("open publish-subscribe service", $name.as_str(), e))
            .map(|service| {
                let dynamic = service.dynamic_config();
                let (mut publishers, mut subscribers) = (Vec::new(), Vec::new());
                dynamic.list_publishers(|p| {
                    publishers.push(p.node_id.value());
                    CallbackProgression::Continue
                });
                dynamic.list_subscribers(|s| {
                    subscribers.push(s.node_id.value());
                    CallbackProgression::Continue
                });
                (publishers, subscribers)
            })
    };
}
/// The node ids of the publishers and subscribers of a service, opened with its payload
/// type (iceoryx2 opens a service only with the types it was created with); `None` for types
/// that are not HNAV's.
type Ports = (Vec<u128>, Vec<u128>);

fn open_ports(
    node: &Node<Ipc>,
    name: &ServiceName,
    element: &str,
    slice: bool,
    header: &str,
) -> Option<Result<Ports, TransportError>> {
    macro_rules! fixed {
        ($($t:ty),*) => {
            $(if !slice && header == "()" && element == type_name::<$t>() {
                return Some(ports_of!(node, name, $t, ()));
            })*
        };
    }
    macro_rules! sliced {
        ($(($e:ty, $h:ty)),*) => {
            $(if slice && element == type_name::<$e>() && header == type_name::<$h>() {
                return Some(ports_of!(node, name, [$e], $h));
            })*
        };
    }
    fixed!(Candidate, Progress, Lifecycle, Heartbeat, Estimate, Sighting);
    sliced!(
        (Decision, CommitHeader),
        (Pose, TruthHeader),
        (f32, MapHeader),
        (u32, WorldHeader),
        (MoverPlace, MoversHeader),
        (WheelCommand, WheelsHeader),
        (Odometry, OdometryHeader),
        (View, ViewsHeader),
        (u8, ())
    );
    None
}

fn type_name<T: ZeroCopySend + ?Sized>() -> &'static str {
    // SAFETY: `type_name` only returns a constant string.
    unsafe { <T as ZeroCopySend>::type_name() }
}

/// Sorts `map/10` after `map/2`: text, then the trailing number.
fn natural_key(topic: &str) -> (&str, u64) {
    match topic.rsplit_once('/') {
        Some((head, n)) if n.bytes().all(|b| b.is_ascii_digit()) && !n.is_empty() => {
            (head, n.parse().unwrap_or(u64::MAX))
        }
        _ => (topic, 0),
    }
}

impl ServicesReport {
    /// The report as JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// The report as text: per topic its types and QoS, then its publishers and subscribers
    /// (`agent-3 (pid 1234)`).
    pub fn render(&self) -> String {
        let mut out = format!("run {}: {} topics\n", self.run_id, self.topics.len());
        for t in &self.topics {
            let header = t
                .user_header
                .as_deref()
                .map(|h| format!(", header {h}"))
                .unwrap_or_default();
            out += &format!(
                "{}  [{}{header}]  history {}, buffer {}, {}\n",
                t.service,
                t.payload,
                t.history,
                t.buffer,
                if t.overflow { "latest" } else { "reliable" }
            );
            for (what, ports, max) in [
                ("publishers", &t.publishers, t.max_publishers),
                ("subscribers", &t.subscribers, t.max_subscribers),
            ] {
                let names: Vec<String> = ports.iter().map(describe).collect();
                out += &format!("  {what} {}/{max}: {}\n", ports.len(), names.join(", "));
            }
        }
        out
    }
}

fn describe(e: &Endpoint) -> String {
    let name = if e.node.is_empty() {
        "(unnamed)"
    } else {
        &e.node
    };
    match e.pid {
        Some(pid) => format!("{name} (pid {pid})"),
        None => name.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn topics_sort_by_their_trailing_number() {
        let mut t = vec!["map/10", "map/2", "commit", "odom/1", "map/1"];
        t.sort_by(|a, b| natural_key(a).cmp(&natural_key(b)));
        assert_eq!(t, ["commit", "map/1", "map/2", "map/10", "odom/1"]);
    }

    #[test]
    fn an_unknown_run_is_named() {
        let tmp = tempfile::tempdir().unwrap();
        let e = services(&RunRegistry::at(tmp.path()), "no-such-run").unwrap_err();
        assert!(
            e.to_string().starts_with("no live run `no-such-run`"),
            "{e}"
        );
    }

    #[test]
    fn a_bad_run_id_is_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let e = services(&RunRegistry::at(tmp.path()), "a/b").unwrap_err();
        assert!(e.to_string().contains("a/b"), "{e}");
    }

    #[test]
    fn the_text_names_every_port() {
        let r = ServicesReport {
            run_id: "r".into(),
            topics: vec![TopicStatus {
                topic: "commit".into(),
                service: "hnav/r/commit".into(),
                payload: "[hnav::Decision]".into(),
                user_header: Some("hnav::CommitHeader".into()),
                history: 1,
                buffer: 64,
                overflow: true,
                max_publishers: 2,
                max_subscribers: 6,
                publishers: vec![Endpoint {
                    node: "coordinator".into(),
                    pid: Some(7),
                }],
                subscribers: vec![Endpoint {
                    node: "agent-0".into(),
                    pid: Some(8),
                }],
            }],
        };
        let text = r.render();
        assert!(
            text.contains(
                "hnav/r/commit  [[hnav::Decision], header hnav::CommitHeader]  history 1, buffer 64, latest"
            ),
            "{text}"
        );
        assert!(
            text.contains("publishers 1/2: coordinator (pid 7)"),
            "{text}"
        );
        assert!(text.contains("subscribers 1/6: agent-0 (pid 8)"), "{text}");
    }
}
