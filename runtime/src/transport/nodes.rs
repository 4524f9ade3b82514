//! A run's nodes and services as iceoryx2 lists them: who is alive, who died, and the
//! clean-up of what the dead left. Below both the process's own node ([`super::node`]) and
//! the clean-up of a finished run ([`super::purge_run`]), which need it alike.

use iceoryx2::config::Config;
use iceoryx2::node::{Node, NodeState, NodeView};
use iceoryx2::prelude::CallbackProgression;
use iceoryx2::service::Service as _;

use super::{Ipc, TransportError};

/// Whether a node's process still holds its liveness lock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeLiveness {
    /// The process is running.
    Alive,
    /// The process died without cleaning up (SIGKILL, crash).
    Dead,
    /// The node cannot be inspected (permissions) or is half created.
    Unknown,
}

/// A node seen in a run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeInfo {
    /// The node name (empty if the node has none).
    pub name: String,
    /// The process id, if known.
    pub pid: Option<i32>,
    /// Liveness.
    pub liveness: NodeLiveness,
}

/// The outcome of a dead-node cleanup.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct CleanupReport {
    /// Dead nodes whose resources were removed.
    pub removed: Vec<NodeInfo>,
    /// Dead nodes whose cleanup failed (another process was cleaning them, say).
    pub failed: Vec<NodeInfo>,
    /// Nodes found alive.
    pub alive: usize,
}

fn describe<V: NodeView>(view: &V, liveness: NodeLiveness) -> NodeInfo {
    let (name, pid) = view
        .details()
        .as_ref()
        .map(|d| (d.name().as_str().to_string(), Some(d.process_id().value())))
        .unwrap_or_default();
    NodeInfo {
        name,
        pid,
        liveness,
    }
}

pub(super) fn nodes_in(config: &Config) -> Result<Vec<NodeInfo>, TransportError> {
    let mut out = Vec::new();
    Node::<Ipc>::list(config, |state| {
        out.push(match &state {
            NodeState::Alive(v) => describe(v, NodeLiveness::Alive),
            NodeState::Dead(v) => describe(v, NodeLiveness::Dead),
            NodeState::Inaccessible(_) | NodeState::Undefined(_) => NodeInfo {
                name: String::new(),
                pid: None,
                liveness: NodeLiveness::Unknown,
            },
        });
        CallbackProgression::Continue
    })
    .map_err(|e| TransportError::ipc("list nodes", "", e))?;
    Ok(out)
}

pub(super) fn cleanup_dead_nodes_in(config: &Config) -> Result<CleanupReport, TransportError> {
    let mut report = CleanupReport::default();
    Node::<Ipc>::list(config, |state| {
        match state {
            NodeState::Alive(_) => report.alive += 1,
            NodeState::Dead(v) => {
                let info = describe(&v, NodeLiveness::Dead);
                match v.try_remove_stale_resources() {
                    Ok(()) => report.removed.push(info),
                    Err(e) => {
                        tracing::warn!(node = info.name, ?e, "dead node cleanup failed");
                        report.failed.push(info);
                    }
                }
            }
            NodeState::Inaccessible(_) | NodeState::Undefined(_) => {}
        }
        CallbackProgression::Continue
    })
    .map_err(|e| TransportError::ipc("list nodes", "", e))?;
    Ok(report)
}

pub(super) fn services_in(config: &Config) -> Result<Vec<String>, TransportError> {
    let mut out = Vec::new();
    Ipc::list(config, |service| {
        out.push(service.static_details.name().as_str().to_string());
        CallbackProgression::Continue
    })
    .map_err(|e| TransportError::ipc("list services", "", e))?;
    out.sort();
    out.dedup();
    Ok(out)
}
