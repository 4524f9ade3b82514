//! # hnav-coordinator
//!
//! The central compute block of an HNAV swarm: conflict resolution between candidate steps,
//! global replanning for blocked agents and the durable consensus log. Its modules arrive with
//! the coordinator and end-to-end issues; until then the crate is an empty member of the
//! workspace so that its place in the dependency graph (`runtime` <- `coordinator`) is fixed.
