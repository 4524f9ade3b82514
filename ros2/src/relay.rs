//! The relay: the run's iceoryx2 topics in, ROS 2 messages out.
//!
//! It reads the run as an observer does (`hnav top`, the recorder): one subscriber on each of
//! `truth`, `estimate`, `commit`, `lifecycle`, and each robot's `wheels/<i>` and `map/<i>`,
//! all "latest" services without back-pressure, so it never holds a lockstep run up; it
//! publishes nothing there. Every commit goes out at once on `/hnav/decisions`; the state
//! (odometry, ground truth, plans, commands, `/tf`, markers) goes out at `rate_hz` of wall
//! clock, the latest of each; `/map` when it changes (its cache answers late joiners). It
//! ends on the supervisor's `Stop`, on SIGTERM/SIGINT or when its parent is gone, after a
//! last round of state, so a subscriber's last message is the run's end.

use std::time::{Duration, Instant};

use hnav_runtime::msg::{CommitView, Estimate, Lifecycle, LifecycleEvent, MapHeader, TruthView};
use hnav_runtime::scenario::{OdometrySource, Scenario};
use hnav_runtime::topics::{self, CommitReceiver, TruthReceiver, WheelsReceiver};
use hnav_runtime::transport::{Receiver, RunId, SliceReceiver, Transport, TransportError, Wake};
use zenoh::Session;

use crate::graph::Qos;
use crate::msgs::{MarkerArray, OccupancyGrid, Odometry, Path, Text, TfMessage};
use crate::node::{Node, NodeError, Publisher};
use crate::scene::Scene;
use crate::types;

/// What the relay is told.
#[derive(Debug, Clone)]
pub struct RelayOptions {
    /// `ROS_DOMAIN_ID`.
    pub domain: u32,
    /// Prefix of the robots' topics (`/fleet` → `/fleet/robot_0/odom`); empty for none.
    pub namespace: String,
    /// State messages per second of wall clock.
    pub rate_hz: f64,
}

/// Why the relay stopped early.
#[derive(Debug, thiserror::Error)]
pub enum RelayError {
    /// The run's topics.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// A ROS 2 declaration.
    #[error(transparent)]
    Node(#[from] NodeError),
}

/// What the relay did.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Counts {
    /// Messages put.
    pub sent: u64,
    /// Messages that failed to encode or put (each said once per topic in the log).
    pub failed: u64,
}

impl std::fmt::Display for Counts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "sent={} failed={}", self.sent, self.failed)
    }
}

/// One robot's publishers.
pub(crate) struct RobotTopics {
    /// `robot_<i>/odom`, made once.
    odom_frame: String,
    /// `None` when the robot outside HNAV publishes its own `odom` (and HNAV reads it).
    odom: Option<Publisher>,
    /// `None` when the robot is outside HNAV: its ground truth is the outside world's.
    ground_truth: Option<Publisher>,
    plan: Publisher,
    pub(crate) cmd_vel: Publisher,
}

/// The node and its publishers.
pub struct Topics {
    /// The node.
    pub node: Node,
    pub(crate) robots: Vec<RobotTopics>,
    /// Robots outside HNAV: `cmd_vel` is theirs to obey, sent only by `outside` (as commands
    /// come, and the stops), never repeated with the state.
    outside: bool,
    map: Publisher,
    tf: Publisher,
    markers: Publisher,
    decisions: Publisher,
}

impl Topics {
    /// Declares node `hnav` and its publishers for `agents` robots. Robots `outside` HNAV
    /// (`Some`: where their motion comes from) get no `ground_truth` publisher, theirs
    /// being the outside world's, nor an `odom` one when they publish their own.
    pub fn declare(
        session: Session,
        agents: usize,
        opts: &RelayOptions,
        outside: Option<OdometrySource>,
    ) -> Result<Topics, NodeError> {
        let mut node = Node::declare(session, opts.domain, "/", "hnav")?;
        let ns = opts.namespace.trim_end_matches('/');
        let mut robots = Vec::with_capacity(agents);
        for i in 0..agents {
            let name = |t: &str| format!("{ns}/robot_{i}/{t}");
            robots.push(RobotTopics {
                odom_frame: format!("robot_{i}/odom"),
                odom: (outside != Some(OdometrySource::Odom))
                    .then(|| node.publisher(&name("odom"), &types::ODOMETRY, Qos::DEFAULT))
                    .transpose()?,
                ground_truth: outside
                    .is_none()
                    .then(|| node.publisher(&name("ground_truth"), &types::ODOMETRY, Qos::DEFAULT))
                    .transpose()?,
                plan: node.publisher(&name("plan"), &types::PATH, Qos::DEFAULT)?,
                cmd_vel: node.publisher(&name("cmd_vel"), &types::TWIST, Qos::DEFAULT)?,
            });
        }
        let tf_qos = Qos {
            depth: 100,
            transient_local: false,
        };
        Ok(Topics {
            map: node.publisher("/map", &types::OCCUPANCY_GRID, Qos::LATCHED)?,
            tf: node.publisher("/tf", &types::TF_MESSAGE, tf_qos)?,
            markers: node.publisher("/hnav/markers", &types::MARKER_ARRAY, Qos::DEFAULT)?,
            decisions: node.publisher("/hnav/decisions", &types::STRING, Qos::DEFAULT)?,
            robots,
            outside: outside.is_some(),
            node,
        })
    }

    /// Every publisher.
    pub fn publishers(&self) -> impl Iterator<Item = &Publisher> {
        (self.robots.iter())
            .flat_map(|r| {
                [
                    r.odom.as_ref(),
                    r.ground_truth.as_ref(),
                    Some(&r.plan),
                    Some(&r.cmd_vel),
                ]
            })
            .flatten()
            .chain([&self.map, &self.tf, &self.markers, &self.decisions])
    }
}

/// The run's topics this relay reads.
pub(crate) struct Inputs {
    /// `None` when this process sends the ground truth itself (robots outside HNAV).
    truth: Option<TruthReceiver>,
    estimate: Receiver<Estimate>,
    commit: CommitReceiver,
    /// One per agent process: its robots' wheel commands.
    pub(crate) wheels: Vec<WheelsReceiver>,
    maps: Vec<SliceReceiver<f32, MapHeader>>,
}

impl Inputs {
    /// Opens the topics of a run of `scenario`; the ground truth's only for an `observer`
    /// (the relay beside the roster, not the sim's stand-in in it, which sends it).
    pub(crate) fn open(
        t: &Transport,
        scenario: &Scenario,
        observer: bool,
    ) -> Result<Inputs, TransportError> {
        let n = scenario.agents.len();
        Ok(Inputs {
            truth: observer
                .then(|| t.slice_receiver(topics::TRUTH, topics::truth_qos()))
                .transpose()?,
            estimate: t.receiver(topics::ESTIMATE, topics::estimate_qos(n))?,
            commit: t.slice_receiver(topics::COMMIT, topics::commit_qos(n))?,
            wheels: (scenario.run.agent_processes(n))
                .map(|(first, _)| {
                    t.slice_receiver(&topics::wheels(first as usize), topics::state_qos())
                })
                .collect::<Result<_, _>>()?,
            maps: (0..n)
                .map(|i| t.slice_receiver(&topics::map(i), topics::state_qos()))
                .collect::<Result<_, _>>()?,
        })
    }
}

/// Reusable messages: each is filled in place, so a tick allocates only what Zenoh copies.
#[derive(Default)]
pub(crate) struct Scratch {
    odom: Odometry,
    path: Path,
    grid: OccupancyGrid,
    tf: TfMessage,
    markers: MarkerArray,
    text: Text,
}

/// Relays run `run` of `scenario` onto `topics` until the run stops.
pub fn relay(
    run: &RunId,
    scenario: &Scenario,
    topics: &mut Topics,
    opts: &RelayOptions,
) -> Result<Counts, RelayError> {
    let n = scenario.agents.len();
    let transport = Transport::builder(run).node_name("ros2").create()?;
    let inputs = Inputs::open(&transport, scenario, true)?;
    let life: Receiver<Lifecycle> =
        transport.receiver(topics::LIFECYCLE, topics::lifecycle_qos(n))?;
    // The lifecycle is the one source the relay sleeps on; the rest is read at its rate.
    let waiter = transport.single_waiter(&life);
    let period = Duration::from_secs_f64(1.0 / opts.rate_hz.clamp(0.1, 1000.0));
    let parent = std::os::unix::process::parent_id();
    let mut out = Out::default();
    let mut scene = Scene::new(scenario);
    let mut s = Scratch::default();
    let mut next = Instant::now();
    loop {
        let wake = waiter.wait(Some(next))?;
        let mut stop = wake == Wake::Stop || std::os::unix::process::parent_id() != parent;
        // Consumes the listener's events too: an event left pending would end every later
        // wait at once.
        life.drain_pending(|l| stop |= l.event == LifecycleEvent::Stop as u8)?;
        read(&inputs, &mut scene, topics, &mut s, &mut out)?;
        if stop || Instant::now() >= next {
            publish_state(&mut scene, topics, &mut s, &mut out);
            next = Instant::now() + period;
        }
        if stop {
            return Ok(out.counts);
        }
    }
}

/// Takes in what the run's topics hold; each commit goes out on `/hnav/decisions` at once.
pub(crate) fn read(
    inputs: &Inputs,
    scene: &mut Scene,
    topics: &mut Topics,
    s: &mut Scratch,
    out: &mut Out,
) -> Result<(), TransportError> {
    if let Some(truth) = &inputs.truth {
        truth.drain(|h, p| scene.truth(TruthView::new(h, p)))?;
    }
    inputs.estimate.drain(|e| {
        if let Some(r) = scene.robots.get_mut(e.agent as usize) {
            r.estimate = Some((e.sim_time_ns, e.pose));
        }
    })?;
    inputs.commit.drain(|h, d| {
        let c = CommitView::new(h, d);
        scene.commit(c);
        scene.decisions_json(c, &mut s.text.data);
        out.put(&mut topics.decisions, &s.text);
    })?;
    for w in &inputs.wheels {
        w.drain(|_, commands| {
            for c in commands {
                if let Some(r) = scene.robots.get_mut(c.agent as usize) {
                    r.wheels = Some((c.left_rad_s, c.right_rad_s));
                }
            }
        })?;
    }
    for (i, m) in inputs.maps.iter().enumerate() {
        m.drain_pending(|h, values| {
            let slot = scene.robots[i].map.get_or_insert_with(Default::default);
            slot.0 = *h;
            slot.1.clear();
            slot.1.extend_from_slice(values);
        })?;
    }
    Ok(())
}

/// Sends the state: per robot its odometry, ground truth, plan and command, then `/tf`,
/// the markers, and `/map` if it changed.
pub(crate) fn publish_state(
    scene: &mut Scene,
    topics: &mut Topics,
    s: &mut Scratch,
    out: &mut Out,
) {
    let outside = topics.outside;
    for (i, t) in topics.robots.iter_mut().enumerate() {
        if let (Some((ns, pose)), Some(odom)) = (scene.robots[i].estimate, &mut t.odom) {
            scene.odometry(i, ns, &pose, &t.odom_frame, &mut s.odom);
            out.put(odom, &s.odom);
        }
        if let Some(pose) = scene.true_pose(i) {
            if let Some(gt) = &mut t.ground_truth {
                scene.odometry(i, scene.now_ns(), &pose, "map", &mut s.odom);
                out.put(gt, &s.odom);
            }
            scene.plan(i, &mut s.path);
            out.put(&mut t.plan, &s.path);
        }
        if scene.robots[i].wheels.is_some() && !outside {
            out.put(&mut t.cmd_vel, &scene.twist(i));
        }
    }
    scene.tf(&mut s.tf);
    if !s.tf.transforms.is_empty() {
        out.put(&mut topics.tf, &s.tf);
    }
    scene.markers(&mut s.markers);
    out.put(&mut topics.markers, &s.markers);
    if scene.map_dirty {
        scene.occupancy(&mut s.grid);
        if out.put(&mut topics.map, &s.grid) {
            scene.map_dirty = false;
        }
    }
}

/// The counts, and the topics whose failure was already said.
#[derive(Default)]
pub(crate) struct Out {
    pub(crate) counts: Counts,
    said: Vec<String>,
}

impl Out {
    /// Publishes `msg` on `p`; a failure is counted, and logged the first time per topic.
    pub(crate) fn put<T: serde::Serialize>(&mut self, p: &mut Publisher, msg: &T) -> bool {
        match p.publish(msg) {
            Ok(()) => {
                self.counts.sent += 1;
                true
            }
            Err(e) => {
                self.counts.failed += 1;
                if !self.said.iter().any(|t| t == p.topic()) {
                    tracing::warn!("{e} (further failures on this topic are only counted)");
                    self.said.push(p.topic().to_string());
                }
                false
            }
        }
    }
}
