//! This host's part of a run across hosts (`hnav run --host NAME`): which of the run's
//! processes it starts, its bridge's command line, and which processes of other hosts its
//! start-up handshake waits for. Also the list of a run's processes ([`processes_of`]) that
//! both this host's slots and the other hosts' part are cut from.
//!
//! Every host's supervisor waits for the `Up` of every process of the run (those of other
//! hosts cross the bridges) and then publishes `Start`; a process takes the first `Start` and
//! ignores the others. Nothing but the bridge is spawned before the bridge is up, and a bridge
//! is up only once it hears every other host's bridge, so no `Up` is sent before the far
//! side can hear it.
//!
//! Each host's processes meet in an iceoryx2 domain named after the host ([`HostPart::run_id`];
//! `HNAV_DOMAIN`, if set, wins), and its supervisor's registry entry carries the domain: two
//! hosts of one run can share a machine (a trial before the robots' computers, a test) with
//! the same `--run`, and only their bridges link them, as between machines.

use std::path::{Path, PathBuf};

use crate::supervisor::child::ChildSpec;
use crate::supervisor::startup::Roll;
use hnav_runtime::msg::Role;
use hnav_runtime::placement::{Host, Placement, PlacementError};
use hnav_runtime::scenario::{ClockMode, FaultSpec, FaultTarget, Scenario};
use hnav_runtime::transport::{RunId, TransportError};

/// This host's part of a run across hosts.
#[derive(Debug, Clone)]
pub struct HostPart {
    file: PathBuf,
    placement: Placement,
    index: usize,
    /// The processes of the run that other hosts run.
    remote: Vec<(Role, u32, String)>,
}

impl HostPart {
    /// Host `name` of the placement in `file`, checked for a run of `scenario`.
    pub fn load(file: &Path, name: &str, scenario: &Scenario) -> Result<Self, PlacementError> {
        let placement =
            Placement::load(file, scenario.agents.len(), scenario.coordinator.replicas)?;
        check_processes(&placement, file, scenario)?;
        let index = placement.index_of(name)?;
        Ok(Self {
            file: file.to_path_buf(),
            remote: remote_of(&placement, index, scenario),
            placement,
            index,
        })
    }

    /// This host.
    pub fn this(&self) -> &Host {
        &self.placement.hosts()[self.index]
    }

    /// This host's place in the placement (its bridge's index).
    pub fn index(&self) -> usize {
        self.index
    }

    /// `run` as this host's processes name it: in the domain named after this host, unless
    /// `run` is in one already (`HNAV_DOMAIN`). Every host of the run may share one machine.
    pub fn run_id(&self, run: RunId) -> Result<RunId, TransportError> {
        match run.domain() {
            Some(_) => Ok(run),
            None => run.in_domain(&self.this().name),
        }
    }

    /// The host that runs the coordinator, or the first that runs one of its replicas: one
    /// with a log (with replicas apart, each replica's host has its replica's).
    pub fn coordinator_host(&self) -> &str {
        let hosts = self.placement.hosts();
        hosts
            .iter()
            .find(|h| !h.coordinator.is_empty())
            .unwrap_or(&hosts[self.index])
            .name
            .as_str()
    }

    /// `spec` (of `hnav-bridge`) with the arguments for run `run` of `scenario`: in
    /// realtime, samples other than lifecycle events that a link cannot take are dropped
    /// rather than waited for.
    pub(super) fn bridge_args(&self, spec: ChildSpec, run: &str, scenario: &Scenario) -> ChildSpec {
        let spec = spec
            .arg("--run")
            .arg(run)
            .arg("--agents")
            .arg(scenario.agents.len().to_string())
            .arg("--agents-per-process")
            .arg(scenario.run.agents_per_process.to_string())
            .arg("--replicas")
            .arg(scenario.coordinator.replicas.to_string())
            .arg("--hosts")
            .arg(&self.file)
            .arg("--host")
            .arg(&self.this().name);
        match scenario.sim.clock {
            ClockMode::Realtime => spec.arg("--best-effort"),
            ClockMode::Lockstep => spec,
        }
    }

    /// Whether this host runs the target of a planned fault: it carries the fault out (every
    /// host reads the same plan). `coordinator` (the leader when the fault fires) is any
    /// host with a replica; the one that runs the leader then finds it among its processes.
    pub fn runs_target(&self, target: &FaultTarget) -> bool {
        let me = self.this();
        match *target {
            FaultTarget::Agent(i) => me.runs(Role::Agent, i as u32),
            FaultTarget::Sim => me.sim,
            FaultTarget::Coordinator => !me.coordinator.is_empty(),
            FaultTarget::Replica(id) => me.runs(Role::Coordinator, id),
        }
    }

    /// Checks that every fault of `faults` (the scenario's and the command line's) can be
    /// carried out across hosts. In realtime any can: each host fires those it runs the
    /// target of. In lockstep the sim holds at a fault's round until `Resume`, which the host
    /// that runs the round's targets sends once they are done: so the faults of one round
    /// must target one host's processes, and `coordinator` (whichever replica leads then)
    /// must not be spread over several hosts.
    pub fn check_faults(&self, faults: &[FaultSpec], scenario: &Scenario) -> Result<(), String> {
        if scenario.sim.clock != ClockMode::Lockstep {
            return Ok(());
        }
        let host_of = |t: &FaultTarget| -> Vec<&str> {
            let hosts = self.placement.hosts().iter();
            let part = |h: &&Host| match *t {
                FaultTarget::Agent(i) => h.runs(Role::Agent, i as u32),
                FaultTarget::Sim => h.sim,
                FaultTarget::Coordinator => !h.coordinator.is_empty(),
                FaultTarget::Replica(id) => h.runs(Role::Coordinator, id),
            };
            hosts.filter(part).map(|h| h.name.as_str()).collect()
        };
        let mut rounds: Vec<(u64, &str)> = Vec::new();
        for f in faults {
            let hosts = host_of(&f.target);
            if hosts.len() > 1 {
                return Err(format!(
                    "a lockstep fault at `coordinator` (the leader) with the replicas on hosts {}: name the replica (coordinator:ID) so that one host holds the run for it",
                    hosts.join(", ")
                ));
            }
            let (Some(host), round) = (hosts.first(), f.lockstep_round(&scenario.sim)) else {
                continue;
            };
            match rounds.iter().find(|(r, _)| *r == round) {
                Some((_, other)) if other != host => {
                    return Err(format!(
                        "lockstep faults at round {round} target processes of hosts {other} and {host}: the faults of one round must be one host's (it holds the run until they are done)"
                    ))
                }
                Some(_) => {}
                None => rounds.push((round, host)),
            }
        }
        Ok(())
    }

    /// Every process of the run that another host runs: role, index and that host.
    pub(super) fn remote(&self) -> impl Iterator<Item = (Role, u32, &str)> + '_ {
        self.remote.iter().map(|(r, i, h)| (*r, *i, h.as_str()))
    }

    /// Adds to `roll` every process of the run that another host runs.
    pub(super) fn add_remote(&self, roll: &mut Roll) {
        for (role, index, host) in self.remote() {
            roll.push(role, index, Some(host));
        }
    }
}

/// Checks that the robots of each agent process run on one host of `placement`.
fn check_processes(
    placement: &Placement,
    file: &Path,
    scenario: &Scenario,
) -> Result<(), PlacementError> {
    let run = &scenario.run;
    for (first, count) in run.agent_processes(scenario.agents.len()) {
        let host = |i| placement.host_of(Role::Agent, i).map(|h| h.name.as_str());
        let (a, host_a) = (first, host(first));
        if let Some(b) = (first + 1..first + count).find(|&b| host(b) != host_a) {
            return Err(PlacementError::SplitProcess {
                file: file.display().to_string(),
                per: run.agents_per_process,
                a,
                b,
                host_a: host_a.unwrap_or("none").to_string(),
                host_b: host(b).unwrap_or("none").to_string(),
            });
        }
    }
    Ok(())
}

/// Every process of a run of `scenario` that a host other than `me` of `placement` runs.
fn remote_of(placement: &Placement, me: usize, scenario: &Scenario) -> Vec<(Role, u32, String)> {
    let me = &placement.hosts()[me].name;
    processes_of(scenario)
        .filter_map(|(role, index, _)| {
            let host = &placement.host_of(role, index)?.name;
            (host != me).then(|| (role, index, host.clone()))
        })
        .collect()
}

/// Every process of a run of `scenario` but the bridges, in the order they start: the sim,
/// the coordinator (index 0) or its replicas (1 to n, their Raft ids), the agent processes
/// (each named by its first robot, with how many robots it hosts: `[run]
/// agents_per_process`). Each runs the binary `hnav-<role>`; the third field is the robots
/// a process hosts (1 but for agents).
pub(super) fn processes_of(scenario: &Scenario) -> impl Iterator<Item = (Role, u32, u32)> + '_ {
    let coordinators = match scenario.coordinator.replicas {
        1 => 0..=0,
        n => 1..=n,
    };
    let agents = scenario.run.agent_processes(scenario.agents.len());
    std::iter::once((Role::Sim, 0, 1))
        .chain(coordinators.map(|id| (Role::Coordinator, id, 1)))
        .chain(agents.map(|(first, count)| (Role::Agent, first, count)))
}
