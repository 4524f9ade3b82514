//! HNAV's agent: the Hopfield "neural map" and the "path constructor" of the dissertation,
//! single-query planning on top of them, and the `hnav-agent` process that drives one robot
//! with them.
//!
//! A robot's agent builds a neural map of its workspace with the goal as the activation point:
//! one neuron per cell, a wave of activation spreading from the goal through the free cells.
//! It then climbs that map by gradient ascent, one cell at a time, and the coordinator may
//! refuse directions to keep robots apart. The [`process`] module wires one agent to the run:
//! odometry in, candidates and wheel commands out, commits applied; messages and transport
//! live in `hnav-runtime`.
//!
//! **Must not depend on**: any HNAV crate but `hnav-runtime` (the coordinator, the sim and the operator's side are reached only through its messages), nor on the operator's libraries (plotters, ratatui, mcap, indicatif).
//!
//! Modules, highest first (a module uses only those below it in this table; imports never run
//! back up):
//!
//! | module | what |
//! |---|---|
//! | [`process`] | the `hnav-agent` process: ports, the round loop in lockstep and realtime, map snapshots, the restart checkpoint |
//! | [`navigator`] | one agent's decision-round logic: its `shared_paths` row, candidates, what each verdict does, waypoints; its guide: the neural map climbed, or a [`route::RoutePlanner`]'s route followed (`planner = "pso"`, `"ga-fuzzy"`) |
//! | [`pso`] | seed 003's particle swarm with virtual obstacles at swarm-detected local minima, a [`route::RoutePlanner`] |
//! | [`controller`] | the wheel controller that drives the robot to the centre of the committed cell |
//! | [`ga_fuzzy`] | seed 004: the GA over time-indexed grids ([`ga_fuzzy::GaPlanner`], route planner `"ga-fuzzy"`) and the fuzzy controller |
//! | [`plan`] | [`plan_query`]: one start-goal query, answered with a JSON-ready [`PlanResult`](hnav_runtime::plan::PlanResult) |
//! | [`path_constructor`] | gradient ascent (eq. 3.5 ascent form, Fig. 3-7 corners, eq. 3.7 heading, seed 001's sign flip); [`Walker`] for step-by-step use with the coordinator's direction masks |
//! | [`route`] | [`route::RoutePlanner`]: the seeds' planners that answer with a whole route (PSO, GA) |
//! | [`neural_map`] | the network (eq. 3.2–3.4, §2.8–2.11): options, the `f32` fast path [`NeuralMap`], the `f64` [`ReferenceMap`], Table 2-2's weight matrix, §2.10 repair |
//! | [`odometry`] | §D.2 dead reckoning from Hall ticks: [`odometry::DeadReckoning`], a pure function of the tick stream |
//! | [`error`] | [`Error`]: bad cells and bad options, never a panic |
//!
//! ```
//! use hnav_agent::plan::{plan_query, PlanOptions};
//! use hnav_runtime::grid::{Cell, Grid};
//!
//! let grid = Grid::new(10, 10).unwrap();
//! let r = plan_query(&grid, Cell::new(0, 0), Cell::new(5, 5), &PlanOptions::default()).unwrap();
//! assert!(r.found);
//! assert_eq!(r.steps, 5);
//! ```

pub mod controller;
pub mod error;
pub mod ga_fuzzy;
pub mod navigator;
pub mod neural_map;
pub mod odometry;
pub mod path_constructor;
pub mod plan;
pub mod process;
pub mod pso;
pub mod route;

pub use error::{Error, Role};
pub use neural_map::{
    Activation, ActivationField, BuildReport, NeuralDynamics, NeuralMap, NeuralMapOptions,
    ReferenceMap, StopRule,
};
pub use path_constructor::{DirectionMask, Path, PathConstructor, PathOptions, Walker};
pub use plan::{plan_query, PlanOptions};
