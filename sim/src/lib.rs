//! # hnav-sim
//!
//! The physics stepper of an HNAV run: differential-drive robots, Hall-sensor odometry and
//! collision checks on ground truth. Its modules arrive with the sim issue; until then the
//! crate is an empty member of the workspace so that its place in the dependency graph
//! (`runtime` <- `sim`) is fixed.
