//! The transport's error type.

use thiserror::Error;

/// What went wrong in the transport.
#[derive(Debug, Error)]
pub enum TransportError {
    /// A run id that cannot be used in service names and file names.
    #[error("invalid run id {id:?}: {why}")]
    InvalidRunId {
        /// The id given.
        id: String,
        /// Why it is rejected.
        why: &'static str,
    },
    /// A topic or node name that iceoryx2 rejects (too long, empty, reserved).
    #[error("invalid name {name:?}: {why}")]
    InvalidName {
        /// The name given.
        name: String,
        /// Why it is rejected.
        why: String,
    },
    /// The directory where iceoryx2 keeps the user's node and service files
    /// ([`ipc_root`](super::ipc_root)) cannot be used by this process.
    #[error("cannot use the shared-memory directory {}: {problem}", dir.display())]
    IpcRoot {
        /// The directory.
        dir: std::path::PathBuf,
        /// What is wrong (permissions, owner, not a directory).
        problem: String,
    },
    /// An iceoryx2 operation failed.
    #[error("{op} on {service:?} failed: {detail}")]
    Iceoryx {
        /// What was being done (e.g. "open publish-subscribe service").
        op: &'static str,
        /// The service or node concerned.
        service: String,
        /// iceoryx2's error, formatted.
        detail: String,
    },
}

impl TransportError {
    pub(crate) fn ipc(op: &'static str, service: &str, e: impl core::fmt::Debug) -> Self {
        Self::Iceoryx {
            op,
            service: service.to_string(),
            detail: format!("{e:?}"),
        }
    }
}
