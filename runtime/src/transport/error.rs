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
        /// iceoryx2's error in words (`InsufficientPermissions` becomes "insufficient permissions").
        detail: String,
    },
    /// The commit bell ([`Bell`](super::Bell)) could not be created, inherited or rung.
    #[error("commit bell: {op}: {source}")]
    Bell {
        /// What was being done ("create", "inherit", "ring", "watch").
        op: &'static str,
        /// The system's error.
        source: std::io::Error,
    },
}

impl TransportError {
    /// An iceoryx2 call `op` on `service` that failed with `e` (also for the operator's
    /// direct iceoryx2 calls: `hnav services` lists nodes and services).
    pub fn ipc(op: &'static str, service: &str, e: impl core::fmt::Debug) -> Self {
        Self::Iceoryx {
            op,
            service: service.to_string(),
            detail: in_words(&format!("{e:?}")),
        }
    }
}

/// An iceoryx2 error's `Debug` text in words: `InsufficientPermissions` becomes
/// "insufficient permissions", `Outer(Inner)` "outer: inner", and `Some(..)`, `Ok(..)` and
/// `Err(..)` wrappers go. iceoryx2's errors are plain
/// enums whose `Display` is their Rust path (`NodeCreationFailure::InternalError`), which
/// means nothing to a user; their variant names do say what happened.
pub(crate) fn in_words(debug: &str) -> String {
    let mut text = debug.to_string();
    for wrapper in ["Some(", "Ok(", "Err("] {
        // Only a whole word: `HandleSome(` stays.
        while let Some(i) = text.match_indices(wrapper).map(|(i, _)| i).find(|&i| {
            !text[..i]
                .chars()
                .next_back()
                .is_some_and(char::is_alphanumeric)
        }) {
            text.replace_range(i..i + wrapper.len(), "");
        }
    }
    let mut out = String::new();
    let mut prev: Option<char> = None;
    for c in text.chars() {
        match c {
            '(' | '{' => out.push_str(": "),
            ')' | '}' => {}
            c if c.is_alphanumeric() => {
                let boundary = c.is_uppercase()
                    && prev.is_some_and(|p| p.is_lowercase() || p.is_ascii_digit());
                if boundary {
                    out.push(' ');
                }
                out.extend(c.to_lowercase());
            }
            '"' => out.push('"'),
            _ => {
                if !out.ends_with(' ') && !out.is_empty() {
                    out.push(' ');
                }
            }
        }
        prev = Some(c);
    }
    out.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use iceoryx2::node::NodeCreationFailure;

    #[test]
    fn iceoryx2_errors_read_as_words_not_rust_names() {
        let e = TransportError::ipc(
            "create node",
            "supervisor",
            NodeCreationFailure::InsufficientPermissions,
        );
        assert_eq!(
            e.to_string(),
            "create node on \"supervisor\" failed: insufficient permissions"
        );
        let e = TransportError::ipc(
            "create node",
            "supervisor",
            NodeCreationFailure::InternalError,
        );
        assert!(e.to_string().ends_with("failed: internal error"), "{e}");
        assert_eq!(
            in_words("ServiceInCorruptedState(UnableToOpenStaticConfig)"),
            "service in corrupted state: unable to open static config"
        );
        assert_eq!(
            in_words("Err(Some(ExceedsMaxSupportedSubscribers))"),
            "exceeds max supported subscribers"
        );
        assert_eq!(in_words("HandleSome(X)"), "handle some: x");
    }
}
