//! # hnav-coordinator
//!
//! The central compute block of an HNAV swarm: every decision round it collects the agents'
//! candidate steps, resolves their conflicts by priority, records the round durably in the
//! consensus log and only then commits it. When an agent is blocked for several rounds or
//! stuck at a local extremum of its neural map, it replans globally over the known map (other
//! robots as obstacles) and answers with a waypoint. This crate holds all of that, the global
//! planners, and the terrain-hazard model they can plan with, after seed 002 (a thesis on
//! Lazy Theta* for s-bots on rough terrain).
//!
//! **Must not depend on**: any HNAV crate but `hnav-runtime`: never on `hnav-operator`
//! (which starts this process) nor on another process crate (agent, sim, bridge); what they
//! share with it (messages, topics, the consensus log's format) is the runtime's. Nor on the
//! operator's libraries (plotters, ratatui, mcap, indicatif).
//!
//! Modules, highest first (a module uses only those below it in this table; imports never run
//! back up; no two files of the crate import each other, directly or through a ring):
//!
//! | module | concept |
//! |---|---|
//! | [`process`] | the `hnav-coordinator` process: `new`/`run`, its ports, its state (the open round, the roster, the end watch), the [`Waiter`](hnav_runtime::transport::Waiter) loop, round deadline, log-then-commit through its decision log (a [`LogWriter`](hnav_runtime::consensus_log::LogWriter), or a replica's [`RaftLog`](replication::RaftLog)), restart from the log |
//! | [`replication`] | the replicated consensus log: one replica's Raft peer ([`Replica`](replication::Replica), the `raft` crate), its journal, its link, and [`RaftLog`](replication::RaftLog), which proposes round records and hands out the committed ones |
//! | [`round`] | the decision round: [`Arbiter`](round::Arbiter) reads the candidates into rows, resolves them, answers each agent (replanning in hybrid mode) and tallies the decisions |
//! | [`conflict`] | one decision round of `shared_paths`: the conflict types (a)–(d), corners, reservations; the [`Resolver`](conflict::Resolver); [`Pibt`](conflict::Pibt), priority inheritance (`rules = "pibt"`); [`Lacam`](conflict::Lacam), PIBT made complete (`rules = "lacam"`) |
//! | [`planner`] | the [`Planner`](planner::Planner) trait; A*, Basic Theta*, Lazy Theta*; single queries for the bench |
//! | [`terrain`] | slope, roughness and relief from a height map; the hazard index `R`; route hazard `c = sum alpha R` |
//! | [`mod@line_of_sight`] | line of sight between cell centres and the exact cell walk behind it, which the planners and the route hazard share |
//! | [`error`] | [`PlanError`], every way a caller's input can be unusable |
//!
//! ```
//! use hnav_coordinator::planner::{LazyTheta, Planner, PlannerConfig};
//! use hnav_runtime::grid::{Cell, Grid};
//! let mut grid = Grid::new(10, 10).unwrap();
//! for y in 2..10 {
//!     grid.set_blocked(Cell::new(5, y), true);
//! }
//! let mut planner = LazyTheta::new(PlannerConfig::default());
//! let path = planner.plan(&grid, Cell::new(1, 8), Cell::new(8, 8)).unwrap().unwrap();
//! assert_eq!(path.cells.len(), 4); // start, two turns at the wall's ends, goal
//! ```

#![warn(missing_docs)]

pub mod conflict;
pub mod error;
pub mod line_of_sight;
pub mod planner;
pub mod process;
pub mod replication;
pub mod round;
pub mod terrain;

pub use error::PlanError;
