//! The run's processes as `hnav top` shows them: pid, state and restarts as `hnav ps` finds
//! them (the registry and the run's iceoryx2 nodes), and the CPU share each used since the
//! last look, from the CPU time in `/proc/<pid>/stat`.

use std::collections::HashMap;
use std::time::Instant;

use crate::supervisor::proc_stat::process_cpu_ticks;
use crate::supervisor::ps::{ProcessState, RunStatus};
use crate::supervisor::registry::{RunEntry, RunRecord};
use hnav_runtime::msg::Role;

/// One process of the run.
#[derive(Debug, Clone, PartialEq)]
pub struct HealthRow {
    /// Its role.
    pub role: Role,
    /// Its agent index, else 0.
    pub index: u32,
    /// The pid of its current incarnation.
    pub pid: u32,
    /// Running, exited or dead, as `hnav ps` says.
    pub state: ProcessState,
    /// Restarts so far.
    pub restarts: u32,
    /// Percent of one core used since the previous sample; `None` on the first sample of a
    /// pid, or when `/proc` does not tell.
    pub cpu_percent: Option<f64>,
}

/// Turns successive registry records into [`HealthRow`]s, remembering each pid's CPU time
/// to tell the share used in between.
#[derive(Debug, Default)]
pub struct HealthSampler {
    last: HashMap<u32, (u64, Instant)>,
    ticks_per_s: f64,
}

impl HealthSampler {
    /// A sampler with no history.
    pub fn new() -> Self {
        Self {
            last: HashMap::new(),
            ticks_per_s: clock_ticks_per_s(),
        }
    }

    /// The rows of `record`'s processes now (`rows` is cleared first and refilled).
    pub fn sample(&mut self, record: &RunRecord, now: Instant, rows: &mut Vec<HealthRow>) {
        rows.clear();
        let status = RunStatus::of(RunEntry {
            record: record.clone(),
            stale: false,
        });
        let mut seen = HashMap::with_capacity(status.processes.len());
        for p in &status.processes {
            let ticks = process_cpu_ticks(p.pid);
            let cpu_percent = match (ticks, self.last.get(&p.pid)) {
                (Some(t), Some(&(t0, at))) => cpu_share(t0, t, self.ticks_per_s, now - at),
                _ => None,
            };
            if let Some(t) = ticks {
                seen.insert(p.pid, (t, now));
            }
            rows.push(HealthRow {
                role: p.role,
                index: p.index,
                pid: p.pid,
                state: p.state,
                restarts: p.restarts,
                cpu_percent,
            });
        }
        // Pids that are gone (restarted processes) are forgotten.
        self.last = seen;
    }
}

/// Percent of one core: `t1 - t0` clock ticks over `elapsed`.
fn cpu_share(t0: u64, t1: u64, ticks_per_s: f64, elapsed: std::time::Duration) -> Option<f64> {
    let secs = elapsed.as_secs_f64();
    (secs > 0.0 && ticks_per_s > 0.0 && t1 >= t0)
        .then(|| (t1 - t0) as f64 / ticks_per_s / secs * 100.0)
}

/// `sysconf(_SC_CLK_TCK)`: the unit of `/proc/<pid>/stat`'s CPU times (100 on Linux).
fn clock_ticks_per_s() -> f64 {
    // SAFETY: sysconf reads a constant of the C library and touches no memory of ours.
    let t = unsafe { libc::sysconf(libc::_SC_CLK_TCK) };
    if t > 0 {
        t as f64
    } else {
        100.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn the_share_is_ticks_over_wall_time() {
        let half = cpu_share(100, 150, 100.0, Duration::from_secs(1)).unwrap();
        assert!((half - 50.0).abs() < 1e-9, "{half}");
        let two_cores = cpu_share(0, 400, 100.0, Duration::from_secs(2)).unwrap();
        assert!((two_cores - 200.0).abs() < 1e-9, "{two_cores}");
        assert_eq!(cpu_share(5, 4, 100.0, Duration::from_secs(1)), None);
        assert_eq!(cpu_share(0, 4, 100.0, Duration::ZERO), None);
    }
}
