//! One ROS 2 node on Zenoh, declared as `rmw_zenoh_cpp` declares one: a liveliness token for
//! the node, per publisher a Zenoh advanced publisher on the topic's key expression and a
//! liveliness token, per subscription a Zenoh subscriber on it and a token. Each sample carries rmw_zenoh's attachment (sequence number from 1,
//! source time, the publisher's GID). A transient-local publisher keeps a cache of its last
//! `depth` samples that late subscribers query (rmw_zenoh's `AdvancedPublisher` options:
//! cache, publisher detection, sporadic heartbeat every 500 ms), which is how a
//! `ros2 topic echo` started after the map was sent still gets it.

use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde::Serialize;
use zenoh::bytes::ZBytes;
use zenoh::handlers::{RingChannel, RingChannelHandler};
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::Subscriber;
use zenoh::qos::{CongestionControl, Reliability};
use zenoh::sample::{Locality, Sample};
use zenoh::{Session, Wait};
use zenoh_ext::{AdvancedPublisher, AdvancedPublisherBuilderExt, CacheConfig, MissDetectionConfig};

use crate::graph::{self, NodeName, Qos, GID_LEN};
use crate::msgs;
use crate::types::TypeInfo;

/// The heartbeat period of a transient-local publisher (rmw_zenoh's
/// `SAMPLE_MISS_DETECTION_HEARTBEAT_PERIOD`).
const HEARTBEAT: Duration = Duration::from_millis(500);

/// Why a node or a publisher could not be declared, or a message not sent.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    /// Zenoh refused a declaration or a put.
    #[error("{what}: {source}")]
    Zenoh {
        /// What was being done.
        what: String,
        /// Zenoh's error.
        source: zenoh::Error,
    },
    /// A message did not encode (a string or sequence longer than CDR's `u32`).
    #[error("{topic}: CDR encoding: {source}")]
    Encode {
        /// The topic.
        topic: String,
        /// The encoder's error.
        source: cdr::Error,
    },
}

fn zenoh_err(what: impl Into<String>) -> impl FnOnce(zenoh::Error) -> NodeError {
    let what = what.into();
    move |source| NodeError::Zenoh { what, source }
}

/// A declared node.
pub struct Node {
    session: Session,
    name: NodeName,
    token: String,
    next_eid: u32,
    _token: LivelinessToken,
}

impl Node {
    /// Declares node `name` in `namespace` (`/` for none) of domain `domain` on `session`.
    pub fn declare(
        session: Session,
        domain: u32,
        namespace: &str,
        name: &str,
    ) -> Result<Node, NodeError> {
        let name = NodeName {
            domain,
            zid: session.zid().to_string(),
            nid: 0,
            namespace: namespace.to_string(),
            name: name.to_string(),
        };
        let token = name.token();
        let live = (session.liveliness().declare_token(&token).wait())
            .map_err(zenoh_err(format!("declare the node's token {token}")))?;
        Ok(Node {
            session,
            name,
            token,
            next_eid: 1,
            _token: live,
        })
    }

    /// The node's liveliness token.
    pub fn token(&self) -> &str {
        &self.token
    }

    /// The node's names (domain, session id, namespace).
    pub fn name(&self) -> &NodeName {
        &self.name
    }

    /// The next entity of the node on `topic`: its data key expression and its liveliness
    /// token, which `token` makes of the node's names and the entity's id.
    fn entity(
        &mut self,
        topic: &str,
        ty: &TypeInfo,
        token: impl FnOnce(&NodeName, u32) -> String,
    ) -> (String, String) {
        let eid = self.next_eid;
        self.next_eid += 1;
        (self.name.topic_key(topic, ty), token(&self.name, eid))
    }

    /// Declares a publisher of `ty` on `topic` (a fully qualified name) with `qos`.
    pub fn publisher(
        &mut self,
        topic: &str,
        ty: &TypeInfo,
        qos: Qos,
    ) -> Result<Publisher, NodeError> {
        let (key, token) = self.entity(topic, ty, |n, eid| n.publisher_token(eid, topic, ty, qos));
        let builder = (self.session.declare_publisher(key.clone()))
            .reliability(Reliability::Reliable)
            .congestion_control(CongestionControl::Drop);
        let publisher = if qos.transient_local {
            builder
                .cache(CacheConfig::default().max_samples(qos.depth as usize))
                .publisher_detection()
                .sample_miss_detection(MissDetectionConfig::default().sporadic_heartbeat(HEARTBEAT))
                .wait()
        } else {
            builder.advanced().wait()
        }
        .map_err(zenoh_err(format!(
            "declare the publisher of {topic} on {key}"
        )))?;
        let live = (self.session.liveliness().declare_token(&token).wait())
            .map_err(zenoh_err(format!("declare the publisher's token {token}")))?;
        Ok(Publisher {
            topic: topic.to_string(),
            gid: graph::gid(&token),
            key,
            token,
            sequence: 1,
            buf: Vec::new(),
            publisher,
            _token: live,
        })
    }

    /// Declares a subscription of `ty` on `topic` (a fully qualified name) with `qos`.
    pub fn subscription(
        &mut self,
        topic: &str,
        ty: &TypeInfo,
        qos: Qos,
    ) -> Result<Subscription, NodeError> {
        let (key, token) = self.entity(topic, ty, |n, eid| {
            n.subscription_token(eid, topic, ty, qos)
        });
        // Only other sessions' samples: the node may publish on the same topic name (its
        // `odom`), and must not read its own.
        let subscriber = (self.session.declare_subscriber(key.clone()))
            .allowed_origin(Locality::Remote)
            .with(RingChannel::new(SUBSCRIPTION_RING))
            .wait()
            .map_err(zenoh_err(format!(
                "declare the subscription of {topic} on {key}"
            )))?;
        let live = (self.session.liveliness().declare_token(&token).wait()).map_err(zenoh_err(
            format!("declare the subscription's token {token}"),
        ))?;
        Ok(Subscription {
            topic: topic.to_string(),
            key,
            subscriber,
            _token: live,
        })
    }
}

/// The samples a subscription holds before the oldest is dropped: the loop takes them every
/// control period, so a robot's 10 ms of messages fit many times over.
const SUBSCRIPTION_RING: usize = 64;

/// One topic's subscription: Zenoh puts its samples into a ring (the oldest dropped when
/// full, so a flood from outside never blocks Zenoh's threads), and the loop takes them.
pub struct Subscription {
    topic: String,
    key: String,
    subscriber: Subscriber<RingChannelHandler<Sample>>,
    _token: LivelinessToken,
}

impl Subscription {
    /// The topic's fully qualified name.
    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// The data key expression.
    pub fn key(&self) -> &str {
        &self.key
    }

    /// Hands every payload received since the last call to `f`, oldest first.
    pub fn drain(&self, mut f: impl FnMut(&[u8])) {
        while let Ok(Some(sample)) = self.subscriber.handler().try_recv() {
            f(&sample.payload().to_bytes());
        }
    }
}

/// One topic's publisher.
pub struct Publisher {
    topic: String,
    key: String,
    token: String,
    gid: [u8; GID_LEN],
    sequence: i64,
    /// The last message's CDR bytes: the encoder writes into it without reallocating once it
    /// has grown to the topic's size.
    buf: Vec<u8>,
    publisher: AdvancedPublisher<'static>,
    _token: LivelinessToken,
}

impl Publisher {
    /// The topic's fully qualified name.
    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// The data key expression.
    pub fn key(&self) -> &str {
        &self.key
    }

    /// The liveliness token.
    pub fn token(&self) -> &str {
        &self.token
    }

    /// Encodes `msg` and puts it with its attachment.
    pub fn publish<T: Serialize>(&mut self, msg: &T) -> Result<(), NodeError> {
        msgs::encode(msg, &mut self.buf).map_err(|source| NodeError::Encode {
            topic: self.topic.clone(),
            source,
        })?;
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX));
        let attachment = graph::attachment(self.sequence, now, &self.gid);
        self.sequence += 1;
        (self.publisher.put(ZBytes::from(self.buf.as_slice())))
            .attachment(ZBytes::from(&attachment[..]))
            .wait()
            .map_err(zenoh_err(format!("put on {}", self.key)))
    }
}
