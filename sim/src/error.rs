//! Errors of the stepper: bad parameters and bad inputs, never a panic. The process around it
//! adds its own ([`crate::process::SimProcessError`]: transport, checkpoint), so the model
//! knows nothing of the process.

/// What went wrong building or driving a [`crate::World`].
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A robot or sim parameter is out of range.
    #[error("bad parameter {name} = {value}: {why}")]
    BadParam {
        /// Parameter name as in the scenario.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What the value must satisfy.
        why: &'static str,
    },
    /// An agent index that names no robot of the world.
    #[error("agent {agent} out of range (the world has {robots} robots)")]
    UnknownAgent {
        /// The index given.
        agent: u32,
        /// Robots in the world.
        robots: usize,
    },
    /// A wheel command with a NaN or infinite speed.
    #[error("agent {agent}: wheel command is not finite ({left}, {right})")]
    NonFiniteCommand {
        /// Agent index.
        agent: u32,
        /// Left set-point.
        left: f64,
        /// Right set-point.
        right: f64,
    },
    /// A start pose with a NaN or infinite coordinate.
    #[error("robot {robot}: start pose is not finite")]
    NonFinitePose {
        /// Robot index.
        robot: usize,
    },
}
