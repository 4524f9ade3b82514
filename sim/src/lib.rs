//! # hnav-sim
//!
//! The physics stepper of an HNAV run: differential-drive robots (the s-bot-like robots of
//! §3.1: two motors, one Hall sensor per wheel), Hall-sensor odometry and collision checks on
//! ground truth. Every parameter comes from the scenario's `[robot]` and `[sim]` sections
//! ([`hnav_runtime::scenario::params`]) and its agents' start cells and headings
//! ([`World::from_scenario`]). Poses and geometry use nalgebra (`Point2`, `UnitComplex`,
//! `Isometry2`); see [`world`] for why the inner loop needs no separate scalar form.
//!
//! **Must not depend on**: any HNAV crate but `hnav-runtime` (the agents and the coordinator are reached only through its messages), nor on the operator's libraries (plotters, ratatui, mcap, indicatif) (`hnav-agent` only as a dev-dependency, for the odometry tests).
//!
//! Modules, highest first (a module uses only those below it in this table; imports never run
//! back up):
//!
//! | module | what |
//! |---|---|
//! | [`process`] | the `hnav-sim` process: [`process::SimProcess`] (`new`, `run`), its ports and state, lockstep and realtime; [`process::SimOutcome`]; [`process::SimProcessError`]: the model's errors, transport and checkpoint failures |
//! | [`world`] | [`World`]: N robots, struct-of-arrays, fixed step, odometry and Truth |
//! | [`localiser`] | the emulated map-based localisation fix carried by odometry readings: truth plus seeded noise |
//! | [`robot`] | [`RobotModel`]: validated parameters; motor lag, speed and acceleration limits, braking |
//! | [`kinematics`] | §D.2 wheel increments and the exact-arc pose update as a rigid motion (nalgebra `Isometry2`, `UnitComplex` headings) |
//! | [`hall`] | tick quantisation and seeded wheel-slip noise (ChaCha) |
//! | [`collision`] | disc–disc and disc–blocked-cell contacts (`Point2` geometry), recorded when they begin with time, robots or cell, and positions |
//! | [`watchdog`] | stale commands are replaced by braking |
//! | [`error`] | [`SimError`]: bad parameters and inputs, never a panic |
//!
//! ```
//! use hnav_runtime::grid::geometry::cell_centre_pose;
//! use hnav_runtime::grid::{Cell, Grid};
//! use hnav_runtime::scenario::params::{RobotParams, SimParams};
//! use hnav_sim::World;
//!
//! let robot = RobotParams::default();
//! let start = cell_centre_pose(robot.cell_size_m, Cell::new(2, 2), 0.0);
//! let mut w = World::new(&robot, &SimParams::default(), Grid::new(20, 5).unwrap(), &[start]).unwrap();
//! w.apply_command(0, 0, 10.0, 10.0, 0).unwrap();
//! for _ in 0..100 {
//!     w.step();
//! }
//! assert!(w.pose(0).unwrap().x_m > start.x_m);
//! ```

pub mod collision;
pub mod error;
pub mod hall;
pub mod kinematics;
pub mod localiser;
pub mod process;
pub mod robot;
pub mod watchdog;
pub mod world;

pub use collision::{Collision, Hit};
pub use error::SimError;
pub use robot::RobotModel;
pub use world::World;
