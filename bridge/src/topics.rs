//! The topics a bridge forwards: the run's decision round, lifecycle and state, and each
//! agent process's wheels and odometry. Each with the payload type and QoS its processes open it with
//! (a different QoS would not open).
//!
//! The neural-map snapshots (`map/<i>`, up to megabytes each) only on request
//! ([`run_topics`]'s `maps`); the replicas' Raft inboxes (`raft/<i>`) only where the replicas
//! are on more than one host ([`raft_topics`]). Left out: heartbeats and estimates (each host's supervisor
//! watches its own processes).

use hnav_runtime::topics;
use hnav_runtime::transport::Qos;

/// A forwarded topic's payload type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Payload {
    /// `candidates`.
    Candidate,
    /// `commit`.
    Commit,
    /// `ready` and `lifecycle`.
    Lifecycle,
    /// `progress`.
    Progress,
    /// `truth`.
    Truth,
    /// `odom/<first>`: an agent process's robots' odometry.
    Odometry,
    /// `wheels/<first>`: an agent process's robots' wheel commands.
    WheelCommand,
    /// `map/<i>`: a neural-map snapshot (`f32` activations with a `MapHeader`).
    Map,
    /// `raft/<i>`: a Raft message to coordinator replica `i` (bytes, Raft's protobuf).
    Raft,
}

/// One forwarded topic.
#[derive(Debug, Clone, PartialEq)]
pub struct TopicSpec {
    /// The topic below `hnav/<run>/`.
    pub topic: String,
    /// Its payload type.
    pub payload: Payload,
    /// Its QoS, as the run's processes open it.
    pub qos: Qos,
    /// Whether a sample may be dropped when a link cannot take it (see [`best_effort`]);
    /// otherwise the bridge waits for room.
    pub droppable: bool,
}

impl TopicSpec {
    /// Whether a realtime run may lose its samples on a link that cannot take them: all but
    /// the lifecycle events. State (truth, progress, odometry, wheels, maps) is superseded
    /// by the next sample; a realtime agent resends an unanswered candidate, and the
    /// coordinator answers a candidate for a decided round with the last commit; Raft
    /// resends what a replica did not acknowledge.
    pub fn is_recoverable(&self) -> bool {
        self.payload != Payload::Lifecycle
    }
}

/// Makes the recoverable topics of `specs` droppable ([`TopicSpec::is_recoverable`]): for a
/// realtime run, where a link cut off must not hold the bridge (and every other host's
/// samples) while its queue is full. A lockstep run waits for every sample, so it keeps
/// them all reliable.
pub fn best_effort(specs: &mut [TopicSpec]) {
    for s in specs.iter_mut().filter(|s| s.is_recoverable()) {
        s.droppable = true;
    }
}

/// Every topic a run of `agents` agents, `per_process` to an agent process, forwards; with
/// `maps`, each agent's neural-map snapshots too.
pub fn run_topics(agents: usize, per_process: u32, maps: bool) -> Vec<TopicSpec> {
    let spec = |topic: &str, payload, qos| TopicSpec {
        topic: topic.to_string(),
        payload,
        qos,
        droppable: false,
    };
    let mut out = vec![
        spec(
            topics::CANDIDATES,
            Payload::Candidate,
            topics::candidates_qos(agents),
        ),
        spec(topics::COMMIT, Payload::Commit, topics::commit_qos(agents)),
        spec(
            topics::LIFECYCLE,
            Payload::Lifecycle,
            topics::lifecycle_qos(agents),
        ),
        spec(
            topics::READY,
            Payload::Lifecycle,
            topics::lifecycle_qos(agents),
        ),
        spec(topics::PROGRESS, Payload::Progress, topics::progress_qos()),
        spec(topics::TRUTH, Payload::Truth, topics::truth_qos()),
    ];
    let per_process = per_process.max(1) as usize;
    for first in (0..agents).step_by(per_process) {
        out.push(spec(
            &topics::odometry(first),
            Payload::Odometry,
            topics::state_qos(),
        ));
        out.push(spec(
            &topics::wheels(first),
            Payload::WheelCommand,
            topics::state_qos(),
        ));
    }
    if maps {
        for i in 0..agents {
            out.push(spec(&topics::map(i), Payload::Map, topics::state_qos()));
        }
    }
    out
}

/// The Raft inbox of every replica of a run of `replicas` (Raft ids 1 to `replicas`): for a
/// run whose replicas are on more than one host. Each keeps the replicas' QoS (a slow
/// reader's oldest message is overwritten: Raft resends).
pub fn raft_topics(replicas: u32) -> Vec<TopicSpec> {
    let voters = replicas as usize;
    (1..=u64::from(replicas))
        .map(|id| TopicSpec {
            topic: topics::raft(id),
            payload: Payload::Raft,
            qos: topics::raft_qos(voters),
            droppable: false,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_forwards_six_topics_and_two_per_agent_process() {
        let t = run_topics(3, 1, false);
        assert_eq!(t.len(), 6 + 2 * 3);
        let grouped = run_topics(10, 4, false);
        assert_eq!(grouped.len(), 6 + 2 * 3);
        assert!(grouped.iter().any(|s| s.topic == "odom/8"));
        assert!(!grouped.iter().any(|s| s.topic == "odom/9"));
        assert_eq!(t[0].topic, "candidates");
        assert!(t.iter().any(|s| s.topic == "wheels/2"));
        assert!(!t.iter().any(|s| s.topic.starts_with("map/")));
        let mut t = run_topics(3, 1, true);
        assert_eq!(t.iter().filter(|s| s.payload == Payload::Map).count(), 3);
        assert!(t.iter().all(|s| !s.droppable));
        best_effort(&mut t);
        let kept: Vec<&str> = (t.iter().filter(|s| !s.droppable))
            .map(|s| s.topic.as_str())
            .collect();
        assert_eq!(kept, ["lifecycle", "ready"]);
    }

    #[test]
    fn three_replicas_have_three_raft_inboxes_droppable_in_realtime() {
        let mut t = raft_topics(3);
        let names: Vec<&str> = t.iter().map(|s| s.topic.as_str()).collect();
        assert_eq!(names, ["raft/1", "raft/2", "raft/3"]);
        best_effort(&mut t);
        assert!(t.iter().all(|s| s.droppable && s.payload == Payload::Raft));
        assert!(raft_topics(1).len() == 1);
    }
}
