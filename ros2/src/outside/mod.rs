//! `hnav-ros2 --robots`: robots outside HNAV in the sim's place (`[sim] kind = "ros2"`).
//!
//! The process takes the sim's slot in the roster (role `sim`: the start-up handshake, the
//! heartbeat, restarts, the fault plan) and speaks to the run's agents as `hnav-sim` does,
//! over the same topics: each agent's wheel commands in (`wheels/<i>`), odometry out every
//! control period (`odometry/<i>`: cumulative Hall ticks, [`wheels`]) and the ground truth
//! (`truth`). On the ROS 2 side it is the relay's node `/hnav` (every topic of
//! `docs/reference/ros2.md` but `ground_truth`, which is the outside world's), sending
//! `/robot_<i>/cmd_vel` as soon as a wheel command comes and reading `/robot_<i>/joint_states`
//! (or `odom`) and `/robot_<i>/ground_truth`.
//!
//! Time is the wall clock's (realtime only): period `k` is due `k` control periods after the
//! run's start, whose instant is kept in `DIR/outside.origin`, so that a restarted process
//! goes on counting where its predecessor was (an agent ignores a period it has seen).
//!
//! What HNAV's side still does: the motor watchdog (a robot whose agent has not commanded
//! for `sim.watchdog_ms` is sent a stop), a dead or lost agent's robot is sent a stop, and a
//! robot not heard for `[ros2] silence_s` is **down**: said in the log once, sent a stop,
//! its agent given its last odometry (the robot still stands where it was, so its cell
//! stays taken); heard again, it is back. Collisions are the outside world's to report: the
//! truth's count stays 0. A message that does not decode, or lacks the wheel joints, is
//! counted and dropped (said once per topic).

pub mod origin;
pub mod robot;
pub mod wheels;

use std::ops::Range;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use hnav_runtime::grid::geometry::cell_centre_pose;
use hnav_runtime::health::Heartbeat;
use hnav_runtime::launch::{LifecyclePorts, StartOutcome};
use hnav_runtime::msg::{
    LifecycleEvent, Odometry as HallOdometry, OdometryHeader, Pose, Role, RosterState, TruthHeader,
    TruthView,
};
use hnav_runtime::scenario::{OdometrySource, Ros2Params, Scenario};
use hnav_runtime::topics::{self, OdometrySender, TruthSender};
use hnav_runtime::transport::{RunId, Transport, TransportError, Wake};

use crate::graph::Qos;
use crate::msgs::{JointState, Odometry, Twist};
use crate::node::{NodeError, Subscription};
use crate::relay::{publish_state, read, Counts, Inputs, Out, RelayOptions, Scratch, Topics};
use crate::scene::Scene;
use crate::types;
use origin::origin;
use robot::{Liveness, OutsideRobot};
use wheels::{ticks, wheel_positions, Malformed};

/// What the process is told.
#[derive(Debug, Clone)]
pub struct OutsideOptions {
    /// The node's topics and state rate.
    pub relay: RelayOptions,
    /// The scenario's `[ros2]` (odometry source, wheel joints, silence bound).
    pub ros2: Ros2Params,
    /// Restarted by the supervisor (`--resume`): announce, do not wait for `Start`.
    pub resume: bool,
    /// The run directory (for [`origin::ORIGIN_FILE`]).
    pub dir: Option<PathBuf>,
}

/// Why it stopped early.
#[derive(Debug, thiserror::Error)]
pub enum OutsideError {
    /// The run's topics.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// A ROS 2 declaration.
    #[error(transparent)]
    Node(#[from] NodeError),
    /// The run's start could not be kept.
    #[error(transparent)]
    Origin(#[from] origin::OriginError),
}

/// What it did.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct OutsideCounts {
    /// The ROS 2 messages sent.
    pub relay: Counts,
    /// Control periods published.
    pub periods: u64,
    /// Messages taken from outside.
    pub heard: u64,
    /// Messages from outside dropped as malformed.
    pub malformed: u64,
    /// Times a robot went down.
    pub down: u64,
    /// The process's CPU time (user + system) at the end, ms: a loop that sleeps as it
    /// should spends a small part of the run's wall time.
    pub cpu_ms: u64,
}

impl std::fmt::Display for OutsideCounts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} periods={} heard={} malformed={} down={} cpu_ms={}",
            self.relay, self.periods, self.heard, self.malformed, self.down, self.cpu_ms
        )
    }
}

impl OutsideCounts {
    /// The counts at the end: the relay's, and the CPU time spent.
    fn ended(mut self, relay: Counts) -> Self {
        use nix::sys::resource::{getrusage, UsageWho};
        use nix::sys::time::TimeValLike;
        self.relay = relay;
        if let Ok(u) = getrusage(UsageWho::RUSAGE_SELF) {
            let ms = u.user_time().num_milliseconds() + u.system_time().num_milliseconds();
            self.cpu_ms = u64::try_from(ms).unwrap_or(0);
        }
        self
    }
}

/// The subscriptions to the robots outside.
struct Outside {
    /// Robot `i`'s `joint_states` or `odom`.
    motion: Vec<Subscription>,
    /// Robot `i`'s `ground_truth`.
    truth: Vec<Subscription>,
    robots: Vec<OutsideRobot>,
    /// The topics whose malformed samples were already said.
    said: Vec<String>,
}

impl Outside {
    fn declare(topics: &mut Topics, n: usize, o: &OutsideOptions) -> Result<Self, NodeError> {
        let ns = o.relay.namespace.trim_end_matches('/');
        let (name, ty) = match o.ros2.odometry {
            OdometrySource::JointStates => ("joint_states", &types::JOINT_STATE),
            // The node then publishes no `odom` of its own (`Topics::declare`).
            OdometrySource::Odom => ("odom", &types::ODOMETRY),
        };
        let mut motion = Vec::with_capacity(n);
        let mut truth = Vec::with_capacity(n);
        for i in 0..n {
            let topic = |t: &str| format!("{ns}/robot_{i}/{t}");
            motion.push(topics.node.subscription(&topic(name), ty, Qos::DEFAULT)?);
            truth.push(topics.node.subscription(
                &topic("ground_truth"),
                &types::ODOMETRY,
                Qos::DEFAULT,
            )?);
        }
        Ok(Outside {
            motion,
            truth,
            robots: vec![OutsideRobot::default(); n],
            said: Vec::new(),
        })
    }

    /// Counts a malformed sample of `topic`, saying so the first time.
    fn malformed(&mut self, counts: &mut OutsideCounts, topic: &str, why: &dyn std::fmt::Display) {
        counts.malformed += 1;
        if !self.said.iter().any(|t| t == topic) {
            tracing::warn!(
                "{topic}: a malformed sample dropped ({why}); further ones are only counted"
            );
            self.said.push(topic.to_string());
        }
    }
}

/// The run's ports that `hnav-sim` would have.
struct SimPorts {
    /// One per agent process: the robots it hosts and their odometry.
    odom: Vec<(Range<u32>, OdometrySender)>,
    truth: TruthSender,
    life: LifecyclePorts,
}

/// Stands in for the sim of run `run` of `scenario` with robots outside HNAV, until the
/// supervisor's `Stop` (or a signal); `topics` are the node's, declared without
/// `ground_truth` publishers.
pub fn drive(
    run: &RunId,
    scenario: &Scenario,
    topics: &mut Topics,
    opts: &OutsideOptions,
) -> Result<OutsideCounts, OutsideError> {
    let n = scenario.agents.len();
    let transport = Transport::builder(run)
        .node_name(&Role::Sim.node_name(0))
        .create()?;
    let inputs = Inputs::open(&transport, scenario, false)?;
    let q = topics::state_qos();
    let ports = SimPorts {
        odom: (scenario.run.agent_processes(n))
            .map(|(first, count)| {
                let tx =
                    transport.slice_sender(&topics::odometry(first as usize), count as usize, q)?;
                Ok((first..first + count, tx))
            })
            .collect::<Result<_, TransportError>>()?,
        truth: transport.slice_sender(topics::TRUTH, n, topics::truth_qos())?,
        life: LifecyclePorts::open(&transport, Role::Sim, 0, n)?,
    };
    let heart = Heartbeat::open(&transport, Role::Sim, 0, n, scenario.heartbeat())?;
    let mut outside = Outside::declare(topics, n, opts)?;
    let mut counts = OutsideCounts::default();
    let started = ports
        .life
        .handshake(&transport, opts.resume, scenario.startup_timeout())?;
    if started == StartOutcome::Stopped {
        return Ok(counts);
    }
    let origin = origin(opts.dir.as_deref(), opts.resume)?;
    let waiter = transport.waiter()?;
    let mut attached = Vec::with_capacity(n + 1);
    for rx in &inputs.wheels {
        attached.push(waiter.attach(rx)?);
    }
    attached.push(waiter.attach(ports.life.events())?);
    let mut st = Loop::new(scenario, opts, origin);
    if opts.resume {
        tracing::info!("resumed at period {} of the run's clock", st.k);
    }
    tracing::info!(
        robots = n,
        odometry = ?opts.ros2.odometry,
        period_ms = st.period.as_secs_f64() * 1e3,
        "driving robots outside HNAV"
    );
    let mut out = Out::default();
    let mut scene = Scene::new(scenario);
    let mut s = Scratch::default();
    loop {
        heart.beat()?;
        let stop = st.on_lifecycle(&ports.life, &mut outside)?;
        st.forward_commands(&inputs, topics, &mut scene, &mut outside, &mut out)?;
        read(&inputs, &mut scene, topics, &mut s, &mut out)?;
        let now = Instant::now();
        if now >= st.due() {
            st.take_outside(&mut outside, &mut counts, &opts.ros2, now);
            st.stop_where_due(topics, &mut outside, &mut out, now);
            st.publish_period(&ports, &outside, &mut scene)?;
            counts.periods += 1;
        }
        if stop || now >= st.next_state {
            publish_state(&mut scene, topics, &mut s, &mut out);
            st.next_state = now + st.state_period;
        }
        if stop {
            return Ok(counts.ended(out.counts));
        }
        let until = st.due().min(st.next_state);
        if waiter.wait(heart.until(Some(until))?)? == Wake::Stop {
            publish_state(&mut scene, topics, &mut s, &mut out);
            return Ok(counts.ended(out.counts));
        }
    }
}

/// The loop's clock and what it carries from one pass to the next.
struct Loop {
    /// The run's start.
    origin: Instant,
    /// The control period.
    period: Duration,
    /// The next period to publish.
    k: u64,
    /// When the ROS 2 state goes out next, and how often.
    next_state: Instant,
    state_period: Duration,
    watchdog: Duration,
    silence: Duration,
    /// Robot `i`'s start pose (its truth until one is known).
    starts: Vec<Pose>,
    ticks_per_rev: f64,
    wheel_radius_m: f64,
    axle_m: f64,
}

impl Loop {
    fn new(scenario: &Scenario, opts: &OutsideOptions, origin: Instant) -> Loop {
        let period = Duration::from_secs_f64(scenario.sim.control_period_s());
        // A restarted process goes on from the period the clock is at.
        let k = (origin.elapsed().as_nanos() / period.as_nanos().max(1)) as u64 + 1;
        let cell = scenario.robot.cell_size_m;
        Loop {
            origin,
            period,
            k,
            next_state: Instant::now(),
            state_period: Duration::from_secs_f64(1.0 / opts.relay.rate_hz.clamp(0.1, 1000.0)),
            watchdog: Duration::from_millis(scenario.sim.watchdog_ms.into()),
            silence: Duration::from_secs_f64(opts.ros2.silence_s),
            starts: (scenario.agents.iter())
                .map(|a| cell_centre_pose(cell, a.start, a.start_heading_deg.to_radians()))
                .collect(),
            ticks_per_rev: scenario.robot.ticks_per_rev,
            wheel_radius_m: scenario.robot.wheel_radius_m,
            axle_m: scenario.robot.axle_track_m,
        }
    }

    /// When period `k` is due.
    fn due(&self) -> Instant {
        self.origin + self.period.mul_f64(self.k as f64)
    }

    /// The supervisor's news: an agent down or lost holds its robot; returns whether to stop.
    fn on_lifecycle(
        &self,
        life: &LifecyclePorts,
        outside: &mut Outside,
    ) -> Result<bool, TransportError> {
        let robots = &mut outside.robots;
        let stop = life.drain_samples(|role, ev, sample| {
            let Some(r) = robots.get_mut(sample.index as usize) else {
                return;
            };
            if role != Role::Agent {
                return;
            }
            match ev {
                LifecycleEvent::Down | LifecycleEvent::Lost => r.agent_down = true,
                LifecycleEvent::Up | LifecycleEvent::Restarted => r.agent_down = false,
                LifecycleEvent::Roster => {
                    r.agent_down = matches!(
                        RosterState::from_u8(sample.reason),
                        Some(RosterState::Down | RosterState::Lost)
                    );
                }
                _ => {}
            }
        })?;
        Ok(stop.is_some())
    }

    /// Each agent's newest wheel command goes out on its robot's `cmd_vel` at once (unless
    /// the robot is held).
    fn forward_commands(
        &self,
        inputs: &Inputs,
        topics: &mut Topics,
        scene: &mut Scene,
        outside: &mut Outside,
        out: &mut Out,
    ) -> Result<(), TransportError> {
        for rx in &inputs.wheels {
            // Consumes the listener's events too (the waiter is attached to it): a pending
            // event would end every later wait at once. The newest sample holds every robot
            // of the process's latest command.
            let newest = rx.take_newest()?;
            for c in newest.iter().flat_map(|s| s.payload()) {
                let i = c.agent as usize;
                let Some(r) = outside.robots.get_mut(i) else {
                    continue;
                };
                scene.robots[i].wheels = Some((c.left_rad_s, c.right_rad_s));
                r.commanded = Some(Instant::now());
                if !(r.down || r.agent_down) {
                    out.put(&mut topics.robots[i].cmd_vel, &scene.twist(i));
                    r.stopped = false;
                }
            }
        }
        Ok(())
    }

    /// Takes what the robots outside sent since the last period, and applies the silence
    /// rule.
    fn take_outside(
        &self,
        outside: &mut Outside,
        counts: &mut OutsideCounts,
        ros2: &Ros2Params,
        now: Instant,
    ) {
        let (radius, axle) = (self.wheel_radius_m, self.axle_m);
        for i in 0..outside.robots.len() {
            let mut bad: Option<String> = None;
            let (motion, robots) = (&outside.motion[i], &mut outside.robots);
            let r = &mut robots[i];
            motion.drain(|payload| {
                let angles = match ros2.odometry {
                    OdometrySource::JointStates => crate::msgs::decode::<JointState>(payload)
                        .map_err(|e| e.to_string())
                        .and_then(|js| {
                            wheel_positions(&js, &ros2.wheel_joints).map_err(|e| e.to_string())
                        }),
                    OdometrySource::Odom => crate::msgs::decode::<Odometry>(payload)
                        .map_err(|e| e.to_string())
                        .and_then(|o| {
                            r.odom
                                .take(&o, radius, axle)
                                .map_err(|e: Malformed| e.to_string())
                        }),
                };
                match angles {
                    Ok(a) => {
                        r.angles = a;
                        r.hear(now);
                        counts.heard += 1;
                    }
                    Err(e) => bad = Some(e),
                }
            });
            outside.truth[i].drain(|payload| match crate::msgs::decode::<Odometry>(payload) {
                Ok(o) => {
                    if let Some((x_m, y_m, theta_rad)) = o.planar() {
                        r.truth = Some(Pose {
                            x_m,
                            y_m,
                            theta_rad,
                        });
                        counts.heard += 1;
                    }
                }
                Err(e) => bad = Some(format!("ground truth: {e}")),
            });
            if let Some(why) = bad {
                let topic = outside.motion[i].topic().to_string();
                outside.malformed(counts, &topic, &why);
            }
            let topic = outside.motion[i].topic();
            match outside.robots[i].check(now, self.origin, self.silence) {
                Liveness::WentDown => {
                    counts.down += 1;
                    tracing::warn!(
                        robot = i,
                        "robot {i} down: nothing on {topic} for {:.1} s; its wheels are sent a stop and the run goes on",
                        self.silence.as_secs_f64()
                    );
                }
                Liveness::Back => tracing::info!(robot = i, "robot {i} back: {topic} heard again"),
                Liveness::Same => {}
            }
        }
    }

    /// Sends a stop to every robot that must stop and has not been sent one.
    fn stop_where_due(
        &self,
        topics: &mut Topics,
        outside: &mut Outside,
        out: &mut Out,
        now: Instant,
    ) {
        for (i, r) in outside.robots.iter_mut().enumerate() {
            if r.must_stop(now, self.watchdog) && !r.stopped {
                out.put(&mut topics.robots[i].cmd_vel, &Twist::default());
                r.stopped = true;
            }
        }
    }

    /// Publishes period `k`'s odometry to every agent and the ground truth, and moves on.
    fn publish_period(
        &mut self,
        ports: &SimPorts,
        outside: &Outside,
        scene: &mut Scene,
    ) -> Result<(), TransportError> {
        let sim_time_ns = u64::try_from(self.period.as_nanos()).unwrap_or(u64::MAX) * self.k;
        for (robots, tx) in &ports.odom {
            let header = OdometryHeader {
                first: robots.start,
                count: robots.len() as u32,
            };
            tx.send_from_fn(header, robots.len(), |k| {
                let i = robots.start + k as u32;
                let angles = outside
                    .robots
                    .get(i as usize)
                    .map_or((0.0, 0.0), |r| r.angles);
                HallOdometry {
                    sim_time_ns,
                    period: self.k,
                    agent: i,
                    flags: 0,
                    ticks_left: ticks(angles.0, self.ticks_per_rev),
                    ticks_right: ticks(angles.1, self.ticks_per_rev),
                    fix: Pose::default(),
                }
            })?;
        }
        let (k, starts) = (self.k, &self.starts);
        let n = outside.robots.len();
        let header = TruthHeader {
            sim_time_ns,
            period: k,
            robots: n as u32,
            collisions: 0,
        };
        let mut loan = ports.truth.loan(n)?;
        *loan.header_mut() = header;
        loan.fill_with(Pose::default(), |poses| {
            for (i, (p, r)) in poses.iter_mut().zip(&outside.robots).enumerate() {
                // Without a ground truth from outside, the agent's own estimate stands for it.
                let estimate = scene.robots[i].estimate.map(|e| e.1);
                *p = r.truth.or(estimate).unwrap_or(starts[i]);
            }
            scene.truth(TruthView::new(&header, poses));
            Ok::<(), TransportError>(())
        })?;
        self.k += 1;
        Ok(())
    }
}
