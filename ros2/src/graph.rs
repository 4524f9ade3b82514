//! rmw_zenoh's names for a ROS 2 graph, as `rmw_zenoh_cpp` (`liveliness_utils.cpp`,
//! `attachment_helpers.cpp` and the design document of ros2/rmw_zenoh) writes them:
//!
//! - a topic's data key expression: `<domain>/<topic without its outer slashes>/<DDS type
//!   name>/<type hash>`, e.g. `0/robot_0/odom/nav_msgs::msg::dds_::Odometry_/RIHS01_…`;
//! - a liveliness token per entity under the hermetic chunk `@ros2_lv`:
//!   `@ros2_lv/<domain>/<zid>/<nid>/<eid>/<kind>/<enclave>/<namespace>/<node>` for a node
//!   (`eid` = `nid`, kind `NN`), and for a publisher (`MP`) or a subscription (`MS`) also
//!   `/<topic>/<DDS type name>/<type hash>/<qos>`; every name "mangled" (each `/` as `%`), so
//!   the default enclave and namespace `/` are `%`;
//! - the QoS in the token, each field empty where it equals rmw_zenoh's default (reliable,
//!   volatile, keep-last 42, infinite deadline, lifespan and lease, automatic liveliness):
//!   `<reliability>:<durability>:<history>,<depth>:<deadline s>,<ns>:<lifespan s>,<ns>:<liveliness>,<lease s>,<ns>`;
//! - an entity's GID: XXH3-128 of its liveliness key expression, the low 64 bits then the
//!   high 64, each little-endian;
//! - the attachment on every sample: the sequence number (`i64`), the source timestamp (ns
//!   since the Unix epoch, `i64`), both little-endian, then the GID as Zenoh's serializer
//!   writes a 16-byte array: its length as a LEB128 byte (16) and the bytes. 33 bytes.

use crate::types::TypeInfo;

/// The hermetic chunk every liveliness token starts with.
pub const ADMIN_SPACE: &str = "@ros2_lv";

/// Bytes of an entity's GID (`RMW_GID_STORAGE_SIZE`).
pub const GID_LEN: usize = 16;

/// Bytes of a sample's attachment.
pub const ATTACHMENT_LEN: usize = 8 + 8 + 1 + GID_LEN;

/// rmw_zenoh's default history depth: a QoS with it leaves the depth out of the token.
pub const DEFAULT_DEPTH: u32 = 42;

/// A name with each `/` as `%` (rmw_zenoh's `mangle_name`).
pub fn mangle(name: &str) -> String {
    name.replace('/', "%")
}

/// The QoS of a publisher, as far as HNAV's choose: reliable, keep-last `depth`, and volatile
/// or transient local.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Qos {
    /// Keep-last depth.
    pub depth: u32,
    /// Transient local (late joiners get the cache) rather than volatile.
    pub transient_local: bool,
}

impl Qos {
    /// Reliable, volatile, keep-last 10: rclcpp's default for a publisher.
    pub const DEFAULT: Qos = Qos {
        depth: 10,
        transient_local: false,
    };
    /// Reliable, transient local, keep-last 1: a map server's latched `/map`.
    pub const LATCHED: Qos = Qos {
        depth: 1,
        transient_local: true,
    };

    /// The QoS part of a liveliness token (rmw_zenoh's `qos_to_keyexpr`): durability
    /// transient local is `1` (rmw's enum), the depth is written unless it is 42.
    pub fn keyexpr(&self) -> String {
        let durability = if self.transient_local { "1" } else { "" };
        let depth = if self.depth == DEFAULT_DEPTH {
            String::new()
        } else {
            self.depth.to_string()
        };
        format!(":{durability}:,{depth}:,:,:,,")
    }
}

/// A ROS 2 node: where its tokens and topics live.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeName {
    /// `ROS_DOMAIN_ID`.
    pub domain: u32,
    /// The Zenoh session id, as Zenoh prints it (lowercase hex).
    pub zid: String,
    /// The node's id within its context.
    pub nid: u32,
    /// The node's namespace (`/` for none).
    pub namespace: String,
    /// The node's name.
    pub name: String,
}

impl NodeName {
    /// The node's liveliness token.
    pub fn token(&self) -> String {
        format!(
            "{ADMIN_SPACE}/{}/{}/{}/{}/NN/%/{}/{}",
            self.domain,
            self.zid,
            self.nid,
            self.nid,
            mangle(&self.namespace),
            mangle(&self.name)
        )
    }

    /// The liveliness token of its publisher `eid` of `topic` (a fully qualified name).
    pub fn publisher_token(&self, eid: u32, topic: &str, ty: &TypeInfo, qos: Qos) -> String {
        self.entity_token("MP", eid, topic, ty, qos)
    }

    /// The liveliness token of its subscription `eid` of `topic` (a fully qualified name).
    pub fn subscription_token(&self, eid: u32, topic: &str, ty: &TypeInfo, qos: Qos) -> String {
        self.entity_token("MS", eid, topic, ty, qos)
    }

    fn entity_token(&self, kind: &str, eid: u32, topic: &str, ty: &TypeInfo, qos: Qos) -> String {
        format!(
            "{ADMIN_SPACE}/{}/{}/{}/{eid}/{kind}/%/{}/{}/{}/{}/{}/{}",
            self.domain,
            self.zid,
            self.nid,
            mangle(&self.namespace),
            mangle(&self.name),
            mangle(topic),
            ty.dds,
            ty.hash,
            qos.keyexpr()
        )
    }

    /// The data key expression of `topic` (a fully qualified name).
    pub fn topic_key(&self, topic: &str, ty: &TypeInfo) -> String {
        format!(
            "{}/{}/{}/{}",
            self.domain,
            topic.trim_matches('/'),
            ty.dds,
            ty.hash
        )
    }
}

/// The GID of the entity whose liveliness token is `token`.
pub fn gid(token: &str) -> [u8; GID_LEN] {
    // xxhash-rust's u128 holds XXH128_hash_t's low64 in its low bits.
    xxhash_rust::xxh3::xxh3_128(token.as_bytes()).to_le_bytes()
}

/// A sample's attachment: `sequence`, `timestamp_ns` (since the Unix epoch), the publisher's
/// `gid`.
pub fn attachment(sequence: i64, timestamp_ns: i64, gid: &[u8; GID_LEN]) -> [u8; ATTACHMENT_LEN] {
    let mut out = [0u8; ATTACHMENT_LEN];
    out[..8].copy_from_slice(&sequence.to_le_bytes());
    out[8..16].copy_from_slice(&timestamp_ns.to_le_bytes());
    out[16] = GID_LEN as u8;
    out[17..].copy_from_slice(gid);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types;

    fn node() -> NodeName {
        NodeName {
            domain: 2,
            zid: "8b20917502ee955ac4476e0266340d5c".into(),
            nid: 0,
            namespace: "/".into(),
            name: "talker".into(),
        }
    }

    #[test]
    fn tokens_match_rmw_zenoh_design_examples() {
        // docs/design.md of ros2/rmw_zenoh: the talker's publisher on `chatter` (depth 7).
        let string = types::STRING;
        let pubq = Qos {
            depth: 7,
            transient_local: false,
        };
        assert_eq!(
            node().publisher_token(10, "/chatter", &string, pubq),
            "@ros2_lv/2/8b20917502ee955ac4476e0266340d5c/0/10/MP/%/%/talker/%chatter/std_msgs::msg::dds_::String_/RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18/::,7:,:,:,,"
        );
        assert_eq!(
            node().subscription_token(11, "/chatter", &string, pubq),
            "@ros2_lv/2/8b20917502ee955ac4476e0266340d5c/0/11/MS/%/%/talker/%chatter/std_msgs::msg::dds_::String_/RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18/::,7:,:,:,,"
        );
        let listener = NodeName {
            zid: "aac3178e146ba6f1fc6e6a4085e77f21".into(),
            name: "listener".into(),
            ..node()
        };
        assert_eq!(
            listener.token(),
            "@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/0/NN/%/%/listener"
        );
        assert_eq!(
            NodeName { domain: 0, ..node() }.topic_key("/robot1/chatter", &string),
            "0/robot1/chatter/std_msgs::msg::dds_::String_/RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
        );
    }

    #[test]
    fn qos_fields_are_empty_where_they_are_rmw_zenohs_default() {
        assert_eq!(Qos::DEFAULT.keyexpr(), "::,10:,:,:,,");
        assert_eq!(Qos::LATCHED.keyexpr(), ":1:,1:,:,:,,");
        let default = Qos {
            depth: DEFAULT_DEPTH,
            transient_local: false,
        };
        assert_eq!(default.keyexpr(), "::,:,:,:,,");
    }

    #[test]
    fn the_attachment_is_33_bytes_with_a_length_byte_before_the_gid() {
        let gid = gid("@ros2_lv/0/1/0/0/NN/%/%/n");
        let a = attachment(5, -2, &gid);
        assert_eq!(&a[..8], &5i64.to_le_bytes());
        assert_eq!(&a[8..16], &(-2i64).to_le_bytes());
        assert_eq!(a[16], 16);
        assert_eq!(&a[17..], &gid);
        // XXH3-128 of the empty input (the reference implementation's test vector):
        // 99aa06d3014798d86001c324468d497f, low 64 bits first.
        let empty = gid_of_empty();
        assert_eq!(
            u64::from_le_bytes(empty[..8].try_into().unwrap()),
            0x6001c324468d497f
        );
        assert_eq!(
            u64::from_le_bytes(empty[8..].try_into().unwrap()),
            0x99aa06d3014798d8
        );
    }

    fn gid_of_empty() -> [u8; GID_LEN] {
        gid("")
    }
}
