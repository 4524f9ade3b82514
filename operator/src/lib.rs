//! # hnav-operator
//!
//! The operator's side of HNAV: what a person at the keyboard uses to start, watch, stop and
//! read back a run. The `hnav` binary (`src/bin/hnav/`) is a thin layer of command-line verbs
//! over these modules.
//!
//! **Must not depend on**: any HNAV crate but `hnav-runtime`: the supervisor starts the
//! process binaries by path and never links them. **Must not be depended on by a process
//! crate** (`hnav-agent`, `hnav-coordinator`, `hnav-sim`, `hnav-bridge`): they never link
//! plotters, ratatui, mcap, indicatif or the `foxglove` crate (and the tokio it brings). `hnav-bench` and `hnav-tests` may use it.
//!
//! Modules, highest first (a module uses only those below it in this table; imports never run
//! back up):
//!
//! | module | what it holds |
//! |---|---|
//! | [`viewer`] | the live Foxglove view: a run's feed served on the Foxglove WebSocket protocol (`hnav run --foxglove`, `hnav view`) |
//! | [`monitor`] | the live view behind `hnav top`: a feed of a run's updates, the view's state, its ratatui drawing |
//! | [`supervisor`] | starting, watching, restarting and stopping a run's processes; the registry behind `hnav ps` |
//! | [`export`] | `hnav log export`: a run's log and recording as an MCAP file for Foxglove Studio |
//! | [`channels`] | the Foxglove channels a run is shown on, live and exported: topics, schemas, the fold from the swarm's messages to the scene |
//! | [`report`] | the run report `DIR/report.svg` (plotters, SVG): map, committed cells, true trajectories, conflicts, replans, collisions, neural-map heatmaps |
//! | [`recording`] | a run's recording on disk: pose samples (truth and estimate) and neural-map snapshots, for the report, the MCAP export and replay |
//! | [`invocation`] | `DIR/invocation.json`: the scenario file and command-line overrides a run was started with, for replay and export |

pub mod channels;
pub mod export;
pub mod invocation;
pub mod monitor;
pub mod recording;
pub mod report;
pub mod supervisor;
pub mod viewer;
