//! The services of a run, in one place: every process opens a topic by the name and with the
//! QoS defined here, so creating and opening sides always agree.
//!
//! | topic | payload | publishers -> subscribers | QoS |
//! |---|---|---|---|
//! | `wheels/<first>` | [`WheelCommand`] slice + [`WheelsHeader`], the latest of each robot of the process | agent process -> sim | latest |
//! | `odom/<first>` | [`Odometry`] slice + [`OdometryHeader`], one per robot of the process | sim -> agent process | latest |
//! | `view/<first>` | [`View`] slice + [`ViewsHeader`], one per robot of the process | sim -> agent process (with `[sensing]`) | latest |
//! | `truth` | [`Pose`] slice + [`TruthHeader`], one pose per robot | sim -> supervisor, recorder, viewers | latest, deep buffer ([`truth_qos`]) |
//! | `estimate` | [`Estimate`](crate::msg::Estimate) | every agent -> recorder, `hnav-ros2`, viewers | latest, depth 1, not notified ([`estimate_qos`]) |
//! | `candidates` | [`Candidate`](crate::msg::Candidate) | agents -> coordinator | reliable |
//! | `commit` | [`Decision`] slice + [`CommitHeader`], one decision per agent | coordinator -> agents | latest, deep buffer |
//! | `map/<i>` | `[f32]` + [`MapHeader`](crate::msg::MapHeader) | agent i -> viewers (`hnav services` lists who) | latest |
//! | `progress` | [`Progress`](crate::msg::Progress) | coordinator -> supervisor | latest |
//! | `ready` | [`Lifecycle`](crate::msg::Lifecycle) (`Up`; the sim's `Hold`) | every process -> supervisor | latest, deep buffer |
//! | `lifecycle` | [`Lifecycle`](crate::msg::Lifecycle) | supervisor -> every process | latest, deep buffer |
//! | `heartbeat` | [`Heartbeat`](crate::msg::Heartbeat) | every process -> supervisor | latest, depth 1, not notified |
//! | `sightings` | [`Sighting`](crate::msg::Sighting) | agents -> coordinator (with `[sensing]`) | reliable |
//! | `world` | `[u32]` (addressee bits, then cells) + [`WorldHeader`](crate::msg::WorldHeader) | coordinator -> restarted agents (with `[sensing]`) | latest, shallow ([`world_qos`]) |
//! | `movers` | [`MoverPlace`](crate::msg::MoverPlace) slice + [`MoversHeader`](crate::msg::MoversHeader) | sim -> recorder, viewers (a run with movers) | latest, deep buffer ([`truth_qos`]) |
//! | `raft/<i>` | `[u8]`: a Raft message | every other coordinator replica -> replica i | latest ([`raft_qos`]) |
//!
//! Why "latest" (overwrite the oldest) for commits and lifecycle events, where every sample
//! counts: with backpressure a dead subscriber whose buffer is full would stall the publisher
//! until the supervisor cleans the dead node up, and a stalled coordinator stalls the swarm.
//! The buffers are sized so that a live reader never falls that far behind: an agent reads a
//! commit every round, and there is one round in flight at a time. History 1 hands a
//! restarted process the last commit (or lifecycle event) at once. The same history hands a
//! viewer that subscribes to `map/<i>` late the agent's last snapshot at once: iceoryx2
//! delivers history when the publisher updates its connections, and the agent does that on
//! every pass of its loop, not only when it publishes a rebuilt map.
//!
//! Observers (`hnav top`, a test, a benchmark's observer) take a subscriber slot of each
//! topic they read. Besides them, `truth` and `progress` have one subscriber (the
//! supervisor), `commit` one per agent and `lifecycle` one per agent plus the sim and the
//! coordinator, so every topic keeps a free slot with one viewer in
//! (`a_viewer_leaves_a_slot_for_one_more_observer`).
//!
//! `<first>` is the first robot of an agent process (`[run] agents_per_process`; with the
//! default of one robot a process, every robot's own index): the sim holds three ports per
//! process, not per robot ([`crate::msg::WheelsHeader`] says why).
//!
//! One `heartbeat` topic for every process rather than one per process: iceoryx2 keeps a
//! queue per publisher-subscriber connection, so a depth-1 "latest" buffer already holds each
//! process's own last beat, and the supervisor reads the whole swarm from one subscriber
//! without a service (and its shared memory) per process. Beats do not notify: the
//! supervisor reads them at its own deadline, so a beat costs a sample write and wakes nobody.

use crate::msg::{
    CommitHeader, Decision, Odometry, OdometryHeader, Pose, TruthHeader, View, ViewsHeader,
    WheelCommand, WheelsHeader,
};
use crate::transport::{Delivery, Qos, SliceReceiver, SliceSender};

/// The `commit` topic's sending side: a slice of one decision per agent (its length, the
/// run's agents, fixed when the coordinator creates the service).
pub type CommitSender = SliceSender<Decision, CommitHeader>;
/// The `commit` topic's receiving side.
pub type CommitReceiver = SliceReceiver<Decision, CommitHeader>;
/// The `truth` topic's sending side: a slice of one pose per robot.
pub type TruthSender = SliceSender<Pose, TruthHeader>;
/// The `truth` topic's receiving side.
pub type TruthReceiver = SliceReceiver<Pose, TruthHeader>;

/// The `wheels/<first>` topic's sending side: the wheel commands of an agent process's
/// robots, one sample per process ([`crate::msg::WheelsHeader`] says why).
pub type WheelsSender = SliceSender<WheelCommand, WheelsHeader>;
/// The `wheels/<first>` topic's receiving side.
pub type WheelsReceiver = SliceReceiver<WheelCommand, WheelsHeader>;
/// The `odom/<first>` topic's sending side: one reading per robot of an agent process.
pub type OdometrySender = SliceSender<Odometry, OdometryHeader>;
/// The `odom/<first>` topic's receiving side.
pub type OdometryReceiver = SliceReceiver<Odometry, OdometryHeader>;
/// The `view/<first>` topic's sending side: one view per robot of an agent process.
pub type ViewsSender = SliceSender<View, ViewsHeader>;
/// The `view/<first>` topic's receiving side.
pub type ViewsReceiver = SliceReceiver<View, ViewsHeader>;

/// The wheel commands of the agent process whose first robot is `first`
/// ([`crate::scenario::params::RunParams::agent_processes`]).
pub fn wheels(first: usize) -> String {
    format!("wheels/{first}")
}

/// The odometry of the robots of the agent process whose first robot is `first`.
pub fn odometry(first: usize) -> String {
    format!("odom/{first}")
}

/// Cells the agents saw change, for the coordinator's map.
pub const SIGHTINGS: &str = "sightings";
/// The coordinator's map of a changing world, for agents that restarted.
pub const WORLD: &str = "world";
/// Where the moving obstacles are, from the sim (a run with movers).
pub const MOVERS: &str = "movers";

/// The sensor views of the robots of the agent process whose first robot is `first`.
pub fn view(first: usize) -> String {
    format!("view/{first}")
}

/// Agent `i`'s neural-map snapshots.
pub fn map(i: usize) -> String {
    format!("map/{i}")
}

/// Ground truth from the sim.
pub const TRUTH: &str = "truth";
/// Candidate steps from the agents.
pub const CANDIDATES: &str = "candidates";
/// Commits from the coordinator.
pub const COMMIT: &str = "commit";
/// The coordinator's running tally.
pub const PROGRESS: &str = "progress";
/// Processes announce they are up.
pub const READY: &str = "ready";
/// The supervisor's lifecycle events and requests.
pub const LIFECYCLE: &str = "lifecycle";

/// Every agent's dead-reckoned pose ([`estimate_qos`]).
pub const ESTIMATE: &str = "estimate";

/// Every process's heartbeat ([`heartbeat_qos`]).
pub const HEARTBEAT: &str = "heartbeat";

/// The Raft inbox of coordinator replica `id`: every other replica writes its messages to
/// it there (`coordinator::replication::link`), and a bridge carries them to another host.
pub fn raft(id: u64) -> String {
    format!("raft/{id}")
}

/// The largest Raft message a `raft/<i>` sample carries.
pub const RAFT_MAX_BYTES: usize = 64 * 1024;

/// QoS of the `raft/<i>` topics of `voters` replicas: Raft resends what is lost and a leader
/// must never wait for a dead follower, so a slow reader's oldest message is overwritten.
/// Publishers: every other replica, an observer and a bridge; subscribers: the replica, an
/// observer and a bridge.
pub fn raft_qos(voters: usize) -> Qos {
    Qos {
        max_publishers: voters + 2,
        max_subscribers: 3,
        buffer: 32,
        history: 0,
        delivery: Delivery::LatestOnly,
    }
}

/// QoS of the per-robot topics and of truth and progress: superseding state.
pub fn state_qos() -> Qos {
    Qos::latest()
}

/// QoS of the `progress` topic: superseding state like [`state_qos`], published by the
/// coordinator that leads (see [`COORDINATOR_PUBLISHERS`]).
pub fn progress_qos() -> Qos {
    Qos {
        max_publishers: COORDINATOR_PUBLISHERS,
        ..state_qos()
    }
}

/// QoS of the `truth` topic: superseding state like [`state_qos`], with a subscriber buffer
/// deep enough for the supervisor's recorder, which samples truth by simulated time and so
/// needs every message near a sampling boundary. A lockstep run publishes a truth message per
/// control period at 10-20x real time (about 2000 a second on the demo), so 128 messages
/// bridge some 60 ms in which the recorder thread is not scheduled; gaps beyond that are
/// counted as missed, never waited for. One more subscriber than [`state_qos`]: the
/// recorder, beside the supervisor's own and a viewer's. Openers with [`state_qos`] still
/// fit (iceoryx2 only requires at least what they ask for); the supervisor creates the
/// service before any process starts.
pub fn truth_qos() -> Qos {
    Qos {
        max_subscribers: Qos::EXTRA_NODES + 1,
        ..state_qos().with_buffer(128)
    }
}

/// QoS of the `estimate` topic of a swarm of `agents`: like [`heartbeat_qos`], every agent
/// (twice, while a restarted one replaces a dead one) publishes and only each one's latest
/// pose matters; the recorder, `hnav-ros2`, a live view and one more viewer read at a pace
/// of their own.
pub fn estimate_qos(agents: usize) -> Qos {
    Qos {
        max_subscribers: 4,
        ..heartbeat_qos(agents)
    }
}

/// QoS of the candidate stream of a swarm of `agents`.
pub fn candidates_qos(agents: usize) -> Qos {
    Qos::reliable(agents)
}

/// Publishers a coordinator's topics (commit, progress) may have at once: a single
/// coordinator and the one restarted in its place, or every replica twice (replicas open them
/// when they come to lead, and a frozen deposed leader keeps its ports until it is continued).
pub const COORDINATOR_PUBLISHERS: usize = 2 * crate::msg::MAX_REPLICAS as usize;

/// QoS of the commit stream: one publisher at a time (see [`COORDINATOR_PUBLISHERS`] for why
/// more may be open), every agent and a few observers reading, a buffer no live reader
/// exhausts.
pub fn commit_qos(agents: usize) -> Qos {
    Qos {
        max_publishers: COORDINATOR_PUBLISHERS,
        max_subscribers: agents.max(1) + Qos::EXTRA_NODES,
        buffer: 64,
        history: 1,
        delivery: Delivery::LatestOnly,
    }
}

/// QoS of the `world` topic of a swarm of `agents`: like the commit stream (one coordinator
/// publishing at a time, every agent reading), but two samples deep: each sample is the whole
/// picture and answers every agent that restarted since the last, and a sample holds a cell
/// per changed cell of the map, which a deep buffer per reader would multiply.
pub fn world_qos(agents: usize) -> Qos {
    Qos {
        buffer: 2,
        ..commit_qos(agents)
    }
}

/// QoS of the `ready` and `lifecycle` topics of a swarm of `agents`. One subscriber more
/// than the run's nodes: in a run across hosts the supervisor listens on `lifecycle` too, for
/// another host's `Stop`.
pub fn lifecycle_qos(agents: usize) -> Qos {
    let n = agents.max(1) + Qos::EXTRA_NODES;
    Qos {
        max_publishers: 2 * n,
        max_subscribers: n + 1,
        buffer: 2 * n,
        history: 1,
        delivery: Delivery::LatestOnly,
    }
}

/// QoS of the `heartbeat` topic of a swarm of `agents`: every process (twice, while a
/// restarted one replaces a dead one whose connection is not cleaned up yet) publishes, the
/// supervisor and an observer read, and only each publisher's last beat matters.
pub fn heartbeat_qos(agents: usize) -> Qos {
    let n = agents.max(1) + Qos::EXTRA_NODES;
    Qos {
        max_publishers: 2 * n,
        max_subscribers: 2,
        buffer: 1,
        history: 0,
        delivery: Delivery::LatestOnly,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn per_robot_topics_are_distinct() {
        assert_ne!(wheels(1), wheels(2));
        assert_ne!(wheels(1), odometry(1));
        assert_ne!(map(3), odometry(3));
    }

    #[test]
    fn a_viewer_leaves_a_slot_for_one_more_observer() {
        let (viewer, another) = (1, 1);
        for agents in [1, 6, 64, 256] {
            assert!(state_qos().max_subscribers >= 1 + viewer + another);
            assert!(commit_qos(agents).max_subscribers >= agents + viewer + another);
            assert!(lifecycle_qos(agents).max_subscribers >= agents + 2 + viewer + another);
        }
    }

    #[test]
    fn lifecycle_admits_every_process_twice() {
        let q = lifecycle_qos(64);
        assert!(q.max_publishers >= 2 * (64 + 2));
        assert!(q.buffer >= 64 + 2);
    }
}
