//! The supervisor's half of the lifecycle protocol (the processes' half is
//! [`hnav_runtime::launch::LifecyclePorts`]): it hears each process's `Up` on `ready` and publishes
//! `Start`, `Down`, `Restarted` and `Stop` on `lifecycle`.
//!
//! [`SupervisorPorts::start`] is the start-up handshake, once for `hnav run` and for the
//! stand-in supervisor of `hnav-bench round`: wait (bounded) until every expected process has
//! announced itself, fail at once if one of them exits, then publish `Start`. It keeps the
//! last start-up phase each process reported ([`hnav_runtime::launch::LifecyclePorts::report_phase`])
//! so that a timeout names what every late process was doing.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use super::child::{Child, ExitInfo};
use hnav_runtime::msg::{Lifecycle, LifecycleEvent, Role, StartupPhase};
use hnav_runtime::topics;
use hnav_runtime::transport::{Receiver, Sender, Transport, TransportError, Wake};

/// Why the processes of a run did not all come up.
#[derive(Debug, thiserror::Error)]
pub enum StartupError {
    /// An expected process exited before it announced itself.
    #[error("{node} exited during start-up ({exit}); see {}", log.display())]
    Exited {
        /// Its node name.
        node: String,
        /// How it ended.
        exit: ExitInfo,
        /// Its log file.
        log: PathBuf,
    },
    /// Some processes had not announced themselves when the time was up.
    #[error(
        "not up within {:.1} s (run.startup_timeout_s): {}",
        timeout.as_secs_f64(),
        missing.iter().map(LateProcess::to_string).collect::<Vec<_>>().join("; ")
    )]
    NotUp {
        /// The bound.
        timeout: Duration,
        /// The processes still missing, with what each was doing.
        missing: Vec<LateProcess>,
    },
    /// The transport failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
}

/// A process that was not up when the start-up timeout passed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LateProcess {
    /// Its node name.
    pub node: String,
    /// The last start-up phase it reported and that phase's size, if it reported one.
    pub phase: Option<(StartupPhase, u32)>,
}

impl std::fmt::Display for LateProcess {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.phase {
            Some((phase, size)) => write!(f, "{} was {}", self.node, phase.describe(size)),
            None => write!(
                f,
                "{} reported nothing (still loading the scenario and map or opening its ports)",
                self.node
            ),
        }
    }
}

/// How the start-up handshake ended, when it did not fail.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Startup {
    /// Every process was up at `all_up`; `Start` has been published.
    Started {
        /// When the last `Up` was taken.
        all_up: Instant,
    },
    /// A termination signal came first; `Start` was not published.
    Interrupted,
}

/// The supervisor's ports of the lifecycle protocol.
pub struct SupervisorPorts {
    ready: Receiver<Lifecycle>,
    events: Sender<Lifecycle>,
}

impl SupervisorPorts {
    /// Opens `ready` and `lifecycle` for a run of `agents` agents. Open them before spawning
    /// anything: an `Up` sent before the subscriber exists is lost.
    pub fn open(transport: &Transport, agents: usize) -> Result<Self, TransportError> {
        let q = topics::lifecycle_qos(agents);
        Ok(Self {
            ready: transport.receiver(topics::READY, q)?,
            events: transport.sender(topics::LIFECYCLE, q)?,
        })
    }

    /// The `ready` topic, on which restarted processes announce themselves too.
    pub fn ready(&self) -> &Receiver<Lifecycle> {
        &self.ready
    }

    /// The publisher of this supervisor's `lifecycle` events, as its samples name it.
    pub fn events_id(&self) -> hnav_runtime::transport::PublisherId {
        self.events.id()
    }

    /// Publishes `event` on `lifecycle`. A process that already died has no subscriber left;
    /// the send still succeeds.
    pub fn publish(&self, event: Lifecycle) -> Result<(), TransportError> {
        self.events.send(event)?;
        Ok(())
    }

    /// The start-up handshake: waits until each of `children` has announced `Up` on `ready`
    /// (matched by its spec's role and index), then publishes `Start`. Fails when one of them
    /// exits first, or when `timeout` passes with some still missing.
    pub fn start(
        &self,
        transport: &Transport,
        children: &[&Child],
        timeout: Duration,
    ) -> Result<Startup, StartupError> {
        let mut roll = Roll::of(children);
        self.start_roll(transport, children, &mut roll, timeout)
    }

    /// [`start`](Self::start) for a `roll` that may name processes of other hosts too: their
    /// `Up` crosses the bridge.
    pub fn start_roll(
        &self,
        transport: &Transport,
        children: &[&Child],
        roll: &mut Roll,
        timeout: Duration,
    ) -> Result<Startup, StartupError> {
        match self.wait_up(transport, children, roll, None, Instant::now() + timeout)? {
            Some(all_up) => {
                self.publish(Lifecycle::start())?;
                Ok(Startup::Started { all_up })
            }
            None => Ok(Startup::Interrupted),
        }
    }

    /// Waits until every process of `roll` (of role `only`, if given) has announced `Up`;
    /// returns when the last was taken, `None` on a termination signal. Every `Up` of the
    /// roll is kept, also one not waited for yet (a host's bridge is waited for first, and
    /// other hosts' processes may already announce themselves meanwhile).
    pub fn wait_up(
        &self,
        transport: &Transport,
        children: &[&Child],
        roll: &mut Roll,
        only: Option<Role>,
        deadline: Instant,
    ) -> Result<Option<Instant>, StartupError> {
        let waiter = transport.waiter()?;
        let mut attached = vec![waiter.attach(&self.ready)?];
        for c in children {
            attached.push(c.watch(&waiter)?);
        }
        let wanted = |e: &Expected| only.is_none_or(|r| r == e.role);
        loop {
            self.take_ups(roll)?;
            if roll.entries.iter().filter(|e| wanted(e)).all(|e| e.up) {
                return Ok(Some(Instant::now()));
            }
            for c in children {
                if let Some(exit) = c.try_reap() {
                    let spec = c.spec();
                    return Err(StartupError::Exited {
                        node: spec.role.node_name(spec.index),
                        exit,
                        log: spec.log_file.clone(),
                    });
                }
            }
            if Instant::now() >= deadline {
                let missing = roll
                    .entries
                    .iter()
                    .filter(|e| wanted(e) && !e.up)
                    .map(|e| LateProcess {
                        node: match &e.host {
                            None => e.role.node_name(e.index),
                            Some(h) => format!("{} on host {h}", e.role.node_name(e.index)),
                        },
                        phase: e.phase,
                    })
                    .collect();
                let timeout = deadline.saturating_duration_since(roll.since);
                return Err(StartupError::NotUp { timeout, missing });
            }
            if waiter.wait(Some(deadline))? == Wake::Stop {
                return Ok(None);
            }
        }
    }

    /// Marks up every process of `roll` whose `Up` is pending on `ready`, and keeps the last
    /// start-up phase each reported.
    fn take_ups(&self, roll: &mut Roll) -> Result<(), TransportError> {
        self.ready.drain_pending(|l| {
            let (Some(role), Some(event)) =
                (Role::from_u8(l.role), LifecycleEvent::from_u8(l.event))
            else {
                return;
            };
            let found = roll
                .entries
                .iter_mut()
                .find(|e| e.role == role && e.index == l.index);
            let Some(e) = found else { return };
            match event {
                LifecycleEvent::Up => e.up = true,
                LifecycleEvent::Phase => {
                    if let Some(p) = StartupPhase::from_u8(l.reason) {
                        e.phase = Some((p, l.restarts));
                    }
                }
                _ => {}
            }
        })?;
        Ok(())
    }
}

/// The processes a start-up handshake waits for: the supervisor's children and, in a run
/// across hosts, the processes of the other hosts.
#[derive(Debug, Clone)]
pub struct Roll {
    entries: Vec<Expected>,
    since: Instant,
}

#[derive(Debug, Clone)]
struct Expected {
    role: Role,
    index: u32,
    /// The other host that runs it; `None`: a child of this supervisor.
    host: Option<String>,
    up: bool,
    phase: Option<(StartupPhase, u32)>,
}

impl Roll {
    /// A roll of `children`.
    pub fn of(children: &[&Child]) -> Self {
        let mut roll = Self {
            entries: Vec::with_capacity(children.len()),
            since: Instant::now(),
        };
        roll.add(children);
        roll
    }

    /// Adds each of `children` the roll does not have yet.
    pub fn add(&mut self, children: &[&Child]) {
        for c in children {
            let (role, index) = (c.spec().role, c.spec().index);
            if !self
                .entries
                .iter()
                .any(|e| e.role == role && e.index == index)
            {
                self.push(role, index, None);
            }
        }
    }

    /// Adds process `role`/`index`, run by another host `host` (`None`: a child).
    pub fn push(&mut self, role: Role, index: u32, host: Option<&str>) {
        self.entries.push(Expected {
            role,
            index,
            host: host.map(str::to_string),
            up: false,
            phase: None,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::supervisor::child::{ChildSpec, Signal};
    use hnav_runtime::transport::{purge_run, RunId};

    /// A supervisor's transport and ports on a fresh run, a stand-in child (`sh -c SCRIPT`),
    /// and a sender on `ready` that plays the child's side of the handshake.
    fn with_run(
        script: &str,
        f: impl FnOnce(&Transport, &SupervisorPorts, &Child, &Sender<Lifecycle>),
    ) {
        let dir = tempfile::tempdir().unwrap();
        let run = RunId::unique("startup");
        {
            let transport = Transport::builder(&run)
                .node_name("supervisor")
                .create()
                .unwrap();
            let ports = SupervisorPorts::open(&transport, 1).unwrap();
            let ready = transport
                .sender(topics::READY, topics::lifecycle_qos(1))
                .unwrap();
            let spec = ChildSpec::new(Role::Agent, 0, "/bin/sh", dir.path().join("agent-0.log"))
                .arg("-c")
                .arg(script);
            let child = Child::spawn(&spec).unwrap();
            f(&transport, &ports, &child, &ready);
            child.signal_group(Signal::SIGKILL).unwrap();
            child.wait(Some(Duration::from_secs(10))).unwrap();
        }
        purge_run(&run).unwrap();
    }

    #[test]
    fn start_is_published_once_every_child_is_up() {
        with_run("sleep 30", |transport, ports, child, ready| {
            let events = transport
                .receiver::<Lifecycle>(topics::LIFECYCLE, topics::lifecycle_qos(1))
                .unwrap();
            ready.send(Lifecycle::up(Role::Sim, 0)).unwrap();
            ready.send(Lifecycle::up(Role::Agent, 0)).unwrap();
            let out = ports
                .start(transport, &[child], Duration::from_secs(10))
                .unwrap();
            assert!(matches!(out, Startup::Started { .. }), "{out:?}");
            let mut got = Vec::new();
            events.drain(|l| got.push(l.event)).unwrap();
            assert_eq!(got, [LifecycleEvent::Start as u8]);
        });
    }

    #[test]
    fn a_child_that_exits_fails_the_start_up() {
        with_run("exit 3", |transport, ports, child, _| {
            let err = ports
                .start(transport, &[child], Duration::from_secs(10))
                .unwrap_err();
            assert!(
                matches!(&err, StartupError::Exited { node, exit, .. }
                    if node == "agent-0" && *exit == ExitInfo::Exited(3)),
                "{err}"
            );
            assert!(err.to_string().contains("agent-0.log"), "{err}");
        });
    }

    #[test]
    fn a_child_that_never_announces_itself_times_out() {
        with_run("sleep 30", |transport, ports, child, ready| {
            ready.send(Lifecycle::down(Role::Agent, 0, 0)).unwrap();
            let err = ports
                .start(transport, &[child], Duration::from_millis(300))
                .unwrap_err();
            let late = LateProcess {
                node: "agent-0".into(),
                phase: None,
            };
            assert!(
                matches!(&err, StartupError::NotUp { missing, .. } if missing == &[late]),
                "{err}"
            );
            assert!(
                err.to_string().contains("agent-0 reported nothing"),
                "{err}"
            );
        });
    }

    #[test]
    fn a_timeout_names_the_last_phase_each_late_child_reported() {
        with_run("sleep 30", |transport, ports, child, ready| {
            let phase =
                |mib| Lifecycle::phase(Role::Agent, 0, StartupPhase::BuildingNeuralMap, mib);
            ready.send(phase(12)).unwrap();
            ready.send(phase(430)).unwrap();
            let err = ports
                .start(transport, &[child], Duration::from_millis(300))
                .unwrap_err();
            assert_eq!(
                err.to_string(),
                "not up within 0.3 s (run.startup_timeout_s): \
                 agent-0 was building its neural map, 430 MiB"
            );
        });
    }
}
