//! The dissertation's criteria (§2.1) that only a process of the run can measure, and the
//! files they reach the run summary by: the motor energy model the sim integrates and the
//! summary prices planned paths with, and the coordinator's candidate-to-commit latencies.
//! The rest of the criteria (path optimality, replans, false positives) the summary works
//! out from the consensus log and the scenario.
//!
//! | module | what it holds |
//! |---|---|
//! | [`files`] | `DIR/sim-criteria.json` and `DIR/consensus-latency.json`: what the sim and the coordinator leave for the summary |
//! | [`latency`] | [`Histogram`]: latencies in log-linear buckets, percentiles without keeping every value |
//! | [`energy`] | the motor model: power drawn per wheel step, the energy budget of a path |

pub mod files;
pub mod latency;

pub mod energy;

pub use files::{ConsensusLatency, CriteriaFileError, RobotCriteria, SimCriteria};
pub use latency::Histogram;
