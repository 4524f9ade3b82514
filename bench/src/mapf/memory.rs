//! Memory of a run's processes, sampled from `/proc` while the run goes on: each process's
//! peak resident set (`VmHWM` in `/proc/PID/status`) and proportional set size (`Pss` in
//! `/proc/PID/smaps_rollup`, where a page shared by k processes counts 1/k in each, so the
//! sum over a run is what the run really holds, shared memory counted once).

use std::collections::HashMap;
use std::path::Path;

use hnav_operator::supervisor::registry::RunRegistry;
use hnav_runtime::msg::Role;
use hnav_runtime::transport::RunId;
use serde::{Deserialize, Serialize};

/// What one role's processes took at most, in KiB.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RoleMemory {
    /// Processes of the role seen (restarts included).
    pub processes: u32,
    /// The largest peak RSS (`VmHWM`) of one of them.
    pub hwm_kib: u64,
    /// The largest PSS of one of them at a sample.
    pub pss_kib: u64,
}

/// The memory of a whole run, in KiB.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunMemory {
    /// The supervisor (`hnav run`).
    pub supervisor: RoleMemory,
    /// The sim.
    pub sim: RoleMemory,
    /// The coordinator.
    pub coordinator: RoleMemory,
    /// The agents (the largest of them).
    pub agent: RoleMemory,
    /// Sum of the peak RSS of every process: shared pages counted in each process that maps
    /// them, so an upper bound of what the run held.
    pub hwm_sum_kib: u64,
    /// The largest sum of PSS over the run's processes at one sample: what the run held.
    pub pss_sum_kib: u64,
    /// Samples taken.
    pub samples: u32,
}

/// Samples the processes of one run.
#[derive(Debug, Default)]
pub struct Sampler {
    /// Per pid: its role and the largest `VmHWM` and PSS seen.
    seen: HashMap<u32, (Option<Role>, u64, u64)>,
    pss_sum_kib: u64,
    samples: u32,
}

impl Sampler {
    /// Samples the supervisor `supervisor` and every process the run registry in
    /// `registry` lists for `run` (missing files and processes that exited meanwhile are
    /// skipped: a sample is best effort, and the peak of a process that exited between two
    /// samples is the last one read). Returns whether the registry listed the run's
    /// processes.
    pub fn sample(&mut self, supervisor: u32, registry: &Path, run: &RunId) -> bool {
        let mut pids = vec![(supervisor, None)];
        if let Ok(Some(record)) = RunRegistry::at(registry).find(run) {
            pids.extend(record.processes.iter().map(|p| (p.pid, Some(p.role))));
        }
        let listed = pids.len() > 1;
        let mut pss_sum = 0;
        for (pid, role) in one_per_process(pids) {
            let Some(hwm) = status_kib(pid, "VmHWM:") else {
                continue;
            };
            let pss = smaps_kib(pid, "Pss:").unwrap_or(0);
            pss_sum += pss;
            let entry = self.seen.entry(pid).or_insert((role, 0, 0));
            entry.1 = entry.1.max(hwm);
            entry.2 = entry.2.max(pss);
        }
        self.pss_sum_kib = self.pss_sum_kib.max(pss_sum);
        self.samples += 1;
        listed
    }

    /// What the samples showed.
    pub fn finish(&self) -> RunMemory {
        let mut m = RunMemory {
            pss_sum_kib: self.pss_sum_kib,
            samples: self.samples,
            ..RunMemory::default()
        };
        for &(role, hwm, pss) in self.seen.values() {
            let slot = match role {
                // A bridge is the supervisor's helper (MAPF runs on one host have none).
                None | Some(Role::Bridge) => &mut m.supervisor,
                Some(Role::Sim) => &mut m.sim,
                Some(Role::Coordinator) => &mut m.coordinator,
                Some(Role::Agent) => &mut m.agent,
            };
            slot.processes += 1;
            slot.hwm_kib = slot.hwm_kib.max(hwm);
            slot.pss_kib = slot.pss_kib.max(pss);
            m.hwm_sum_kib += hwm;
        }
        m
    }
}

/// `pids` with each process once: the registry lists every robot of an agent process that
/// hosts several (`agents_per_process`) under the process's pid, and a process counted once
/// per robot would multiply its PSS in the sum.
fn one_per_process(mut pids: Vec<(u32, Option<Role>)>) -> Vec<(u32, Option<Role>)> {
    let mut seen = std::collections::HashSet::new();
    pids.retain(|&(pid, _)| seen.insert(pid));
    pids
}

/// A `KEY value kB` line of `/proc/PID/status`.
fn status_kib(pid: u32, key: &str) -> Option<u64> {
    kib_field(
        &std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?,
        key,
    )
}

/// A `KEY value kB` line of `/proc/PID/smaps_rollup`.
fn smaps_kib(pid: u32, key: &str) -> Option<u64> {
    kib_field(
        &std::fs::read_to_string(format!("/proc/{pid}/smaps_rollup")).ok()?,
        key,
    )
}

fn kib_field(text: &str, key: &str) -> Option<u64> {
    text.lines()
        .find_map(|l| l.strip_prefix(key))
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|v| v.parse().ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_process_of_several_robots_is_sampled_once() {
        let a = Some(Role::Agent);
        let pids = vec![(1, None), (7, a), (7, a), (9, Some(Role::Sim)), (7, a)];
        assert_eq!(
            one_per_process(pids),
            [(1, None), (7, a), (9, Some(Role::Sim))]
        );
    }

    #[test]
    fn fields_are_read_in_kib() {
        let text = "Name:\thnav\nVmPeak:\t  9000 kB\nVmHWM:\t    1234 kB\nVmRSS:\t 1000 kB\n";
        assert_eq!(kib_field(text, "VmHWM:"), Some(1234));
        assert_eq!(kib_field(text, "Pss:"), None);
    }

    #[test]
    fn this_process_is_sampled_as_the_supervisor() {
        let dir = tempfile::tempdir().unwrap();
        let mut s = Sampler::default();
        let run = RunId::unique("mapf-memory");
        s.sample(std::process::id(), dir.path(), &run);
        let m = s.finish();
        assert_eq!((m.samples, m.supervisor.processes), (1, 1));
        assert!(m.supervisor.hwm_kib > 0 && m.hwm_sum_kib == m.supervisor.hwm_kib);
        assert!(m.pss_sum_kib > 0, "smaps_rollup gives this process a PSS");
        assert_eq!(m.agent, RoleMemory::default());
    }
}
