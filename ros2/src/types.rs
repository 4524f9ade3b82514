//! The ROS 2 message types HNAV publishes (and, from robots outside HNAV, reads), for ROS 2 Jazzy Jalisco: the name, the DDS type
//! name rmw_zenoh puts in key expressions and tokens, and the type hash (REP-2011's
//! `RIHS01_<sha256 of the type description>`).
//!
//! The hashes were computed per REP-2011 from Jazzy's message definitions by PyPI `rosbags`
//! 0.11.9 (`get_typestore(Stores.ROS2_JAZZY).hash_rihs01(name)`, the command in
//! `docs/reference/ros2.md`), and that computation checked against two hashes published
//! independently: `std_msgs/msg/String`'s in rmw_zenoh's design document and
//! `nav_msgs/msg/Odometry`'s in ZettaScale's ros-z (computed from Jazzy's generated type
//! descriptions). The Python test client decodes every topic with the same typestore, and
//! checks the hash in each key expression against it.

/// One message type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TypeInfo {
    /// `pkg/msg/Name`.
    pub name: &'static str,
    /// `pkg::msg::dds_::Name_`.
    pub dds: &'static str,
    /// `RIHS01_` and 64 hex digits.
    pub hash: &'static str,
}

/// `nav_msgs/msg/Odometry`.
pub const ODOMETRY: TypeInfo = TypeInfo {
    name: "nav_msgs/msg/Odometry",
    dds: "nav_msgs::msg::dds_::Odometry_",
    hash: "RIHS01_3cc97dc7fb7502f8714462c526d369e35b603cfc34d946e3f2eda2766dfec6e0",
};

/// `nav_msgs/msg/Path`.
pub const PATH: TypeInfo = TypeInfo {
    name: "nav_msgs/msg/Path",
    dds: "nav_msgs::msg::dds_::Path_",
    hash: "RIHS01_1957a5bb3cee5da65c4e52e52b65a93df227efce4c20f8458b36e73066ca334b",
};

/// `geometry_msgs/msg/Twist`.
pub const TWIST: TypeInfo = TypeInfo {
    name: "geometry_msgs/msg/Twist",
    dds: "geometry_msgs::msg::dds_::Twist_",
    hash: "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a",
};

/// `nav_msgs/msg/OccupancyGrid`.
pub const OCCUPANCY_GRID: TypeInfo = TypeInfo {
    name: "nav_msgs/msg/OccupancyGrid",
    dds: "nav_msgs::msg::dds_::OccupancyGrid_",
    hash: "RIHS01_8d348150c12913a31ee0ec170fbf25089e4745d17035792a1ba94d6f0bc0cfc7",
};

/// `tf2_msgs/msg/TFMessage`.
pub const TF_MESSAGE: TypeInfo = TypeInfo {
    name: "tf2_msgs/msg/TFMessage",
    dds: "tf2_msgs::msg::dds_::TFMessage_",
    hash: "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
};

/// `visualization_msgs/msg/MarkerArray`.
pub const MARKER_ARRAY: TypeInfo = TypeInfo {
    name: "visualization_msgs/msg/MarkerArray",
    dds: "visualization_msgs::msg::dds_::MarkerArray_",
    hash: "RIHS01_86cb8800b6fb05b5eff1abd7a56f62a5641d3ae9a1c29e78e67e704f1d067dcf",
};

/// `std_msgs/msg/String`: `/hnav/decisions` (one JSON object per commit).
pub const STRING: TypeInfo = TypeInfo {
    name: "std_msgs/msg/String",
    dds: "std_msgs::msg::dds_::String_",
    hash: "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18",
};

/// `sensor_msgs/msg/JointState`: what robots outside HNAV publish of their wheels.
pub const JOINT_STATE: TypeInfo = TypeInfo {
    name: "sensor_msgs/msg/JointState",
    dds: "sensor_msgs::msg::dds_::JointState_",
    hash: "RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e",
};

/// Every type above.
pub const ALL: [TypeInfo; 8] = [
    JOINT_STATE,
    ODOMETRY,
    PATH,
    TWIST,
    OCCUPANCY_GRID,
    TF_MESSAGE,
    MARKER_ARRAY,
    STRING,
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dds_names_and_hashes_are_well_formed() {
        for t in ALL {
            let (pkg, rest) = t.name.split_once("/msg/").unwrap();
            assert_eq!(t.dds, format!("{pkg}::msg::dds_::{rest}_"));
            let hex = t.hash.strip_prefix("RIHS01_").unwrap();
            assert_eq!(hex.len(), 64);
            assert!(hex
                .bytes()
                .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b)));
        }
    }
}
