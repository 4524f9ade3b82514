//! `hnav-ros2`: a run as ROS 2 topics, on rmw_zenoh's wire contract.
//!
//! ROS 2 tools (`ros2 topic echo`, RViz, Foxglove) on a machine with
//! `RMW_IMPLEMENTATION=rmw_zenoh_cpp` see the run as a node `/hnav` publishing each robot's
//! `odom`, `ground_truth`, `plan` and `cmd_vel`, and `/map`, `/tf`, `/hnav/markers` and
//! `/hnav/decisions` (`docs/reference/ros2.md`). No ROS installation is needed on HNAV's
//! side: the messages are CDR-encoded by serde ([`msgs`]), the names, tokens and attachments
//! are rmw_zenoh's ([`graph`]), and Zenoh carries them.
//!
//! With `[sim] kind = "ros2"` the same node also drives robots outside HNAV, in the sim's
//! place ([`outside`]): wheel commands out as `cmd_vel`, `joint_states` (or `odom`) and
//! `ground_truth` in, decoded from CDR the same way.
//!
//! **Must not depend on**: any HNAV crate but `hnav-runtime` (the run is reached only through
//! its topics), nor on the operator's libraries.
//!
//! Modules, highest first (a module uses only those below it in this table; imports never run
//! back up):
//!
//! | module | what it holds |
//! |---|---|
//! | [`outside`] | `--robots`: robots outside HNAV in the sim's place (wheel commands out as `cmd_vel`, `joint_states` or `odom` in as odometry, their ground truth as the run's) |
//! | [`relay`] | the loop: the run's iceoryx2 topics in, ROS 2 messages out; the node's publishers |
//! | [`scene`] | what is known of the run, and the ROS 2 messages made of it (frames, plans, markers, decisions) |
//! | [`node`] | one ROS 2 node on Zenoh: liveliness tokens, publishers and subscriptions, attachments, transient local |
//! | [`session`] | the Zenoh session: a peer of the router, or the router itself |
//! | [`graph`] | rmw_zenoh's names: key expressions, liveliness tokens, QoS strings, GIDs, attachments |
//! | [`types`] | the message types: ROS and DDS names, RIHS01 hashes (Jazzy) |
//! | [`msgs`] | the messages as serde structs, and their CDR encoding and decoding |

pub mod graph;
pub mod msgs;
pub mod node;
pub mod outside;
pub mod relay;
pub mod scene;
pub mod session;
pub mod types;
