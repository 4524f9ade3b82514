//! The ROS 2 messages HNAV publishes, field for field as the Jazzy definitions
//! (`common_interfaces`, `geometry2`), encoded with the `cdr` crate: serde drives the
//! encoder, so a struct's field order here is its wire order.
//!
//! CDR aligns each primitive to its size, counted from the end of the 4-byte encapsulation
//! header; strings are a `u32` length (with the NUL) and the NUL-terminated bytes; a sequence
//! (`T[]`) is a `u32` count and the elements; a fixed array (`float64[36]`) its elements only.
//! The covariances are the one array longer than serde's 32, hence [`Cov`].
//!
//! What robots outside HNAV send (`[sim] kind = "ros2"`: [`JointState`], and [`Odometry`]
//! as `odom` or `ground_truth`) is decoded the same way ([`decode`]); a sample that does not
//! decode is an error, never a panic.

use serde::de::{Deserialize, Deserializer, SeqAccess, Visitor};
use serde::ser::{Serialize, SerializeTuple, Serializer};

/// `builtin_interfaces/msg/Time` (and `Duration`, the same two fields).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default, PartialEq)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds, in [0, 1e9).
    pub nanosec: u32,
}

impl Time {
    /// `ns` nanoseconds (sim time) as a ROS time.
    pub fn from_ns(ns: u64) -> Time {
        Time {
            sec: i32::try_from(ns / 1_000_000_000).unwrap_or(i32::MAX),
            nanosec: (ns % 1_000_000_000) as u32,
        }
    }
}

/// `std_msgs/msg/Header`.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Default, PartialEq)]
pub struct Header {
    /// When.
    pub stamp: Time,
    /// The frame the data is in.
    #[serde(deserialize_with = "string")]
    pub frame_id: String,
}

/// `geometry_msgs/msg/Point` and `Vector3` (the same three `float64`).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default, PartialEq)]
pub struct Vec3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion`.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Quaternion::yaw(0.0)
    }
}

impl Quaternion {
    /// The rotation about +z (yaw) of this orientation, radians in [-pi, pi]; a planar
    /// robot's heading.
    pub fn yaw_angle(&self) -> f64 {
        let (x, y, z, w) = (self.x, self.y, self.z, self.w);
        (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
    }

    /// A rotation by `theta` radians about +z.
    pub fn yaw(theta: f64) -> Quaternion {
        let (s, c) = (theta / 2.0).sin_cos();
        Quaternion {
            x: 0.0,
            y: 0.0,
            z: s,
            w: c,
        }
    }
}

/// `geometry_msgs/msg/Pose`.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default, PartialEq)]
pub struct Pose {
    /// Position (a `Point`).
    pub position: Vec3,
    /// Orientation.
    pub orientation: Quaternion,
}

/// A `float64[36]` covariance (row-major 6x6), zero: HNAV does not estimate one.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Cov;

impl Serialize for Cov {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut t = s.serialize_tuple(36)?;
        for _ in 0..36 {
            t.serialize_element(&0.0f64)?;
        }
        t.end()
    }
}

impl<'de> Deserialize<'de> for Cov {
    /// Reads the 36 values and keeps none: HNAV has no use for an outside covariance.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Skip36;
        impl<'de> Visitor<'de> for Skip36 {
            type Value = Cov;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("36 float64")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Cov, A::Error> {
                for i in 0..36 {
                    seq.next_element::<f64>()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
                }
                Ok(Cov)
            }
        }
        d.deserialize_tuple(36, Skip36)
    }
}

/// `geometry_msgs/msg/PoseWithCovariance`.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default, PartialEq)]
pub struct PoseWithCovariance {
    /// The pose.
    pub pose: Pose,
    /// Its covariance.
    pub covariance: Cov,
}

/// `geometry_msgs/msg/Twist`.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default, PartialEq)]
pub struct Twist {
    /// m/s (a `Vector3`).
    pub linear: Vec3,
    /// rad/s.
    pub angular: Vec3,
}

/// `geometry_msgs/msg/TwistWithCovariance`.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default, PartialEq)]
pub struct TwistWithCovariance {
    /// The twist.
    pub twist: Twist,
    /// Its covariance.
    pub covariance: Cov,
}

/// `nav_msgs/msg/Odometry`.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Default, PartialEq)]
pub struct Odometry {
    /// Stamp and the pose's frame.
    pub header: Header,
    /// The body frame.
    #[serde(deserialize_with = "string")]
    pub child_frame_id: String,
    /// Pose in `header.frame_id`.
    pub pose: PoseWithCovariance,
    /// Velocity in `child_frame_id`.
    pub twist: TwistWithCovariance,
}

impl Odometry {
    /// The pose as a planar robot's: x, y and yaw in `header.frame_id`; `None` if any is not a
    /// finite number (what came from outside is not trusted to be).
    pub fn planar(&self) -> Option<(f64, f64, f64)> {
        let p = &self.pose.pose;
        let v = (p.position.x, p.position.y, p.orientation.yaw_angle());
        (v.0.is_finite() && v.1.is_finite() && v.2.is_finite()).then_some(v)
    }
}

/// `geometry_msgs/msg/PoseStamped`.
#[derive(serde::Serialize, Debug, Clone, Default, PartialEq)]
pub struct PoseStamped {
    /// Stamp and frame.
    pub header: Header,
    /// The pose.
    pub pose: Pose,
}

/// `nav_msgs/msg/Path`.
#[derive(serde::Serialize, Debug, Clone, Default, PartialEq)]
pub struct Path {
    /// Stamp and frame.
    pub header: Header,
    /// The waypoints.
    pub poses: Vec<PoseStamped>,
}

/// `nav_msgs/msg/MapMetaData`.
#[derive(serde::Serialize, Debug, Clone, Copy, Default, PartialEq)]
pub struct MapMetaData {
    /// When the map was loaded.
    pub map_load_time: Time,
    /// Metres per cell (`float32`).
    pub resolution: f32,
    /// Cells.
    pub width: u32,
    /// Cells.
    pub height: u32,
    /// The pose of cell (0, 0)'s corner in the map frame.
    pub origin: Pose,
}

/// `nav_msgs/msg/OccupancyGrid`.
#[derive(serde::Serialize, Debug, Clone, Default, PartialEq)]
pub struct OccupancyGrid {
    /// Stamp and frame.
    pub header: Header,
    /// Size and placement.
    pub info: MapMetaData,
    /// Row-major from (0, 0), 0 free to 100 occupied, -1 unknown.
    pub data: Vec<i8>,
}

/// `geometry_msgs/msg/Transform`.
#[derive(serde::Serialize, Debug, Clone, Copy, Default, PartialEq)]
pub struct Transform {
    /// A `Vector3`.
    pub translation: Vec3,
    /// The rotation.
    pub rotation: Quaternion,
}

/// `geometry_msgs/msg/TransformStamped`.
#[derive(serde::Serialize, Debug, Clone, Default, PartialEq)]
pub struct TransformStamped {
    /// Stamp and parent frame.
    pub header: Header,
    /// The child frame.
    pub child_frame_id: String,
    /// Child in parent.
    pub transform: Transform,
}

/// `tf2_msgs/msg/TFMessage`.
#[derive(serde::Serialize, Debug, Clone, Default, PartialEq)]
pub struct TfMessage {
    /// The transforms.
    pub transforms: Vec<TransformStamped>,
}

/// `std_msgs/msg/ColorRGBA`.
#[derive(serde::Serialize, Debug, Clone, Copy, Default, PartialEq)]
pub struct Color {
    /// Red, in [0, 1].
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
    /// Alpha.
    pub a: f32,
}

/// `sensor_msgs/msg/CompressedImage` (a marker's texture; HNAV sends none).
#[derive(serde::Serialize, Debug, Clone, Default, PartialEq)]
pub struct CompressedImage {
    /// Stamp and frame.
    pub header: Header,
    /// `jpeg`, `png`.
    pub format: String,
    /// The image.
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/UVCoordinate`.
#[derive(serde::Serialize, Debug, Clone, Copy, Default, PartialEq)]
pub struct UvCoordinate {
    /// u.
    pub u: f32,
    /// v.
    pub v: f32,
}

/// `visualization_msgs/msg/MeshFile` (HNAV sends none).
#[derive(serde::Serialize, Debug, Clone, Default, PartialEq)]
pub struct MeshFile {
    /// The file's name.
    pub filename: String,
    /// Its bytes.
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/Marker`, Jazzy's (with the texture and mesh-file fields).
#[derive(serde::Serialize, Debug, Clone, Default, PartialEq)]
pub struct Marker {
    /// Stamp and frame.
    pub header: Header,
    /// Namespace of the id.
    pub ns: String,
    /// Id within `ns`.
    pub id: i32,
    /// Shape: [`Marker::CYLINDER`], [`Marker::CUBE`], ...
    pub r#type: i32,
    /// `ADD` (0) or `DELETEALL` (3).
    pub action: i32,
    /// Where.
    pub pose: Pose,
    /// Size, m.
    pub scale: Vec3,
    /// Colour.
    pub color: Color,
    /// How long it stays (zero: until replaced).
    pub lifetime: Time,
    /// Whether it moves with its frame.
    pub frame_locked: bool,
    /// Points of a list type.
    pub points: Vec<Vec3>,
    /// Per-point colours.
    pub colors: Vec<Color>,
    /// Texture URI.
    pub texture_resource: String,
    /// Texture.
    pub texture: CompressedImage,
    /// Texture coordinates.
    pub uv_coordinates: Vec<UvCoordinate>,
    /// Text of a text marker.
    pub text: String,
    /// Mesh URI.
    pub mesh_resource: String,
    /// Mesh.
    pub mesh_file: MeshFile,
    /// Whether the mesh's own materials are used.
    pub mesh_use_embedded_materials: bool,
}

impl Marker {
    /// `type` CUBE.
    pub const CUBE: i32 = 1;
    /// `type` SPHERE.
    pub const SPHERE: i32 = 2;
    /// `type` CYLINDER.
    pub const CYLINDER: i32 = 3;
    /// `action` ADD (add or modify).
    pub const ADD: i32 = 0;
    /// `action` DELETEALL.
    pub const DELETEALL: i32 = 3;
}

/// `visualization_msgs/msg/MarkerArray`.
#[derive(serde::Serialize, Debug, Clone, Default, PartialEq)]
pub struct MarkerArray {
    /// The markers.
    pub markers: Vec<Marker>,
}

/// `sensor_msgs/msg/JointState`: what a robot outside HNAV says of its wheels.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Default, PartialEq)]
pub struct JointState {
    /// Stamp and frame (unused).
    pub header: Header,
    /// The joints' names.
    #[serde(deserialize_with = "strings")]
    pub name: Vec<String>,
    /// Positions, rad for a wheel (as many as `name`, or none).
    pub position: Vec<f64>,
    /// Velocities, rad/s (as many as `name`, or none).
    pub velocity: Vec<f64>,
    /// Efforts (as many as `name`, or none).
    pub effort: Vec<f64>,
}

/// `std_msgs/msg/String`.
#[derive(serde::Serialize, Debug, Clone, Default, PartialEq)]
pub struct Text {
    /// The text.
    pub data: String,
}

/// Encodes `msg` as a little-endian CDR payload (header `00 01 00 00`) into `out`, which is
/// cleared first and keeps its capacity from one message to the next.
pub fn encode<T: Serialize>(msg: &T, out: &mut Vec<u8>) -> Result<(), cdr::Error> {
    out.clear();
    cdr::serialize_into::<_, _, _, cdr::CdrLe>(&mut *out, msg, cdr::Infinite)
}

/// A CDR string read as what it is on the wire, a `u32` count and that many bytes (the last
/// a NUL), one byte at a time: the `cdr` crate's own string reader allocates the count it
/// reads before it checks the payload holds it, so a malformed sample could ask for 4 GiB.
/// Here a count beyond the payload ends in an error once the payload runs out.
fn string<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    struct Bytes;
    impl<'de> Visitor<'de> for Bytes {
        type Value = String;
        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("a NUL-terminated UTF-8 string")
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<String, A::Error> {
            let mut v = Vec::new();
            while let Some(b) = seq.next_element::<u8>()? {
                v.push(b);
            }
            if v.pop() != Some(0) {
                return Err(serde::de::Error::custom("a string without its NUL"));
            }
            String::from_utf8(v).map_err(serde::de::Error::custom)
        }
    }
    d.deserialize_seq(Bytes)
}

/// A `string[]` whose strings are read as [`string`] reads one.
fn strings<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<String>, D::Error> {
    struct One(String);
    impl<'de> Deserialize<'de> for One {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            string(d).map(One)
        }
    }
    struct Many;
    impl<'de> Visitor<'de> for Many {
        type Value = Vec<String>;
        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("a sequence of strings")
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<String>, A::Error> {
            let mut v = Vec::new();
            while let Some(One(s)) = seq.next_element()? {
                v.push(s);
            }
            Ok(v)
        }
    }
    d.deserialize_seq(Many)
}

/// Decodes a CDR payload (either byte order, as its encapsulation header says) into `T`.
pub fn decode<T: serde::de::DeserializeOwned>(payload: &[u8]) -> Result<T, cdr::Error> {
    cdr::deserialize::<T>(payload)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_header_is_the_encapsulation_then_aligned_fields() {
        let mut out = Vec::new();
        let h = Header {
            stamp: Time { sec: 1, nanosec: 2 },
            frame_id: "map".into(),
        };
        encode(&h, &mut out).unwrap();
        assert_eq!(
            out,
            [0, 1, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 4, 0, 0, 0, b'm', b'a', b'p', 0]
        );
        // A float64 after a 3-byte string (+NUL, length word) is aligned to 8 from the
        // start of the data, not of the buffer.
        let odom = Odometry {
            header: Header {
                stamp: Time::default(),
                frame_id: "ab".into(),
            },
            ..Odometry::default()
        };
        encode(&odom, &mut out).unwrap();
        // After the 4-byte header: time 8, "ab" 4 + 3 = 15, child_frame_id aligned to 16
        // (length 1: "") = 21, the pose's first float64 aligned to 24.
        assert_eq!(&out[4 + 16..4 + 21], &[1, 0, 0, 0, 0]);
        assert_eq!(&out[4 + 21..4 + 24], &[0, 0, 0]);
        assert_eq!(out.len(), 4 + 24 + (7 + 36) * 8 + (6 + 36) * 8);
    }

    #[test]
    fn what_is_encoded_decodes_and_garbage_is_an_error() {
        let mut out = Vec::new();
        let js = JointState {
            name: vec!["left_wheel_joint".into(), "right_wheel_joint".into()],
            position: vec![1.5, -2.25],
            ..JointState::default()
        };
        encode(&js, &mut out).unwrap();
        assert_eq!(decode::<JointState>(&out).unwrap(), js);
        let odom = Odometry {
            child_frame_id: "base_link".into(),
            ..Odometry::default()
        };
        encode(&odom, &mut out).unwrap();
        assert_eq!(decode::<Odometry>(&out).unwrap(), odom);
        // Cut short, a wrong header, a sequence longer than the payload.
        assert!(decode::<Odometry>(&out[..out.len() - 3]).is_err());
        assert!(decode::<JointState>(&[0xde, 0xad, 0xbe, 0xef, 1, 2, 3]).is_err());
        let mut long = vec![0, 1, 0, 0];
        long.extend_from_slice(&[0; 8]);
        long.extend_from_slice(&[1, 0, 0, 0]);
        long.extend_from_slice(&0xffff_fff0u32.to_le_bytes());
        assert!(decode::<JointState>(&long).is_err());
        // A frame id that claims 4 GiB: an error once the payload runs out, not an
        // allocation of the claim.
        let mut huge = vec![0, 1, 0, 0];
        huge.extend_from_slice(&[0; 8]);
        huge.extend_from_slice(&0xffff_fff0u32.to_le_bytes());
        huge.extend_from_slice(b"map\0");
        assert!(decode::<Odometry>(&huge).is_err());
        assert!(decode::<JointState>(&huge).is_err());
    }

    #[test]
    fn time_splits_nanoseconds() {
        assert_eq!(
            Time::from_ns(2_500_000_001),
            Time {
                sec: 2,
                nanosec: 500_000_001
            }
        );
    }
}
