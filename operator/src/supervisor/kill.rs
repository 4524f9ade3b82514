//! `hnav kill RUN TARGET [--signal KILL|TERM|STOP|CONT]`: a signal to one process of a live
//! run, from outside its supervisor.
//!
//! The run is found in the registry `hnav ps` reads ([`super::registry`]); a run the registry
//! does not know, one whose supervisor is gone, and a target the run does not have (or that
//! is not running right now, between a death and its restart) are refused. The signal goes to
//! the current pid of the target only (not its process group), as a planned fault's does; the
//! supervisor then reacts as to any other death or freeze: it reaps and restarts a killed
//! process under its role's policy, and hang detection deals with one stopped too long.
//!
//! Where hosts of a run across hosts share this machine, the target is looked for in the part
//! of the host that runs it.
//!
//! In a run with coordinator replicas, `coordinator` names the replica that leads: the one
//! whose role file (`DIR/log/<id>/raft-role.json`, what `hnav ps` shows) says `leader` in the
//! highest term. `coordinator:ID` names one replica whatever its role.
//!
//! The signal is recorded in the run's journal `DIR/events.jsonl` as a `signalled` line with
//! no fault index, appended next to the supervisor's own lines ([`RunEvents::append`]) under
//! the journal's lock, held from just before the signal ([`RunEvents::hold`]), so that it
//! precedes the supervisor's `exited` line of the same death; its `round` is the last round
//! the run's consensus log holds just before the signal (a replicated run: the replica that
//! decided the most).

use std::path::{Path, PathBuf};

use nix::errno::Errno;
use nix::sys::signal::kill as send_signal;
use nix::unistd::Pid;

use super::child::Signal;
use super::events::{RunEvent, RunEvents};
use super::proc_stat::process_alive;
use super::registry::{LiveRunError, RunRecord, RunRegistry};
use hnav_runtime::consensus_log::{read_decided, ReplicaRole};
use hnav_runtime::msg::Role;
use hnav_runtime::scenario::fault_arg::target_arg;
use hnav_runtime::scenario::FaultTarget;

/// Why `hnav kill` sent nothing.
#[derive(Debug, thiserror::Error)]
pub enum KillError {
    /// The run is not a live one.
    #[error(transparent)]
    Live(#[from] LiveRunError),
    /// The run has no such process.
    #[error("run `{run}` has no {target} ({has})")]
    UnknownTarget {
        /// The run id.
        run: String,
        /// The target as written: `agent:9`.
        target: String,
        /// What the run has: `its agents are 0-7`.
        has: String,
    },
    /// `coordinator` of a run with replicas, none of which says it leads (an election is
    /// under way, or the majority is gone).
    #[error("no coordinator replica of run `{run}` leads right now (an election may be under way); name one: {has}")]
    NoLeader {
        /// The run id.
        run: String,
        /// The replicas: `coordinator:1-3`.
        has: String,
    },
    /// The target is between a death and its restart, or gone for good.
    #[error("{target} of run `{run}` is not running (pid {pid} has exited; it may be about to be restarted)")]
    NotRunning {
        /// The run id.
        run: String,
        /// The target as written.
        target: String,
        /// Its last recorded pid.
        pid: u32,
    },
    /// In a run across hosts, another host runs the target.
    #[error("{target} of run `{run}` runs on host {host}: run `hnav kill` there")]
    Remote {
        /// The run id.
        run: String,
        /// The target as written.
        target: String,
        /// The host that runs it.
        host: String,
    },
    /// `kill(2)` refused.
    #[error("cannot send {signal} to {target} (pid {pid}) of run `{run}`: {source}")]
    Signal {
        /// The run id.
        run: String,
        /// The target as written.
        target: String,
        /// Its pid.
        pid: u32,
        /// The signal.
        signal: Signal,
        /// Why.
        source: Errno,
    },
}

/// What `hnav kill` did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Killed {
    /// The target's node name, e.g. `agent-3`; for a robot of a shared agent process
    /// (`[run] agents_per_process`), the process's, named by its first robot.
    pub node: String,
    /// The robots of the agent process signalled, ascending (the target alone when it has
    /// a process of its own; empty for a sim or a coordinator).
    pub robots: Vec<u32>,
    /// The pid signalled.
    pub pid: u32,
    /// The signal sent.
    pub signal: Signal,
    /// The last round in the run's log when it was sent.
    pub round: u64,
    /// The run's journal it was recorded in.
    pub journal: PathBuf,
}

/// Sends `signal` to `target` of the live run `run` of `registry` and records it in the run's
/// journal. See the [module docs](self).
pub fn kill(
    registry: &RunRegistry,
    run: &str,
    target: FaultTarget,
    signal: Signal,
) -> Result<Killed, KillError> {
    let (_, record) = registry.find_live(run)?;
    let (role, index) = match target {
        FaultTarget::Agent(i) => (Role::Agent, u32::try_from(i).unwrap_or(u32::MAX)),
        FaultTarget::Coordinator => (Role::Coordinator, coordinator_index(run, &record)?),
        FaultTarget::Replica(id) => (Role::Coordinator, id),
        FaultTarget::Sim => (Role::Sim, 0),
    };
    let name = target_arg(target);
    let record = target_host_part(registry, run, record, role, index);
    let Some(p) = record
        .processes
        .iter()
        .find(|p| p.role == role && p.index == index)
    else {
        let agents = record
            .processes
            .iter()
            .filter(|p| p.role == Role::Agent)
            .count();
        let has = match agents {
            0 => "it has no agents yet".to_string(),
            1 => "its only agent is 0".to_string(),
            n => format!("its agents are 0-{}", n - 1),
        };
        return Err(KillError::UnknownTarget {
            run: run.into(),
            target: name,
            has,
        });
    };
    if let Some(host) = &p.host {
        return Err(KillError::Remote {
            run: run.into(),
            target: name,
            host: host.clone(),
        });
    }
    let not_running = || KillError::NotRunning {
        run: run.into(),
        target: name.clone(),
        pid: p.pid,
    };
    if !process_alive(p.pid, p.start_ticks) {
        return Err(not_running());
    }
    let pid = i32::try_from(p.pid).map_err(|_| not_running())?;
    let round = last_round(&record.dir.join("log"));
    let journal = RunEvents::append(&record.dir);
    // Held from before the signal until its line is written: the supervisor, woken by the
    // death at once, writes its `exited` line after this one.
    let held = journal.hold();
    match send_signal(Pid::from_raw(pid), signal) {
        Ok(()) => {}
        Err(Errno::ESRCH) => return Err(not_running()),
        Err(source) => {
            return Err(KillError::Signal {
                run: run.into(),
                target: name,
                pid: p.pid,
                signal,
                source,
            })
        }
    }
    // A robot of a shared process: the signal took the process, named by its first robot.
    let mut robots: Vec<u32> = match role {
        Role::Agent => (record.processes.iter())
            .filter(|q| q.role == Role::Agent && q.pid == p.pid)
            .map(|q| q.index)
            .collect(),
        _ => Vec::new(),
    };
    robots.sort_unstable();
    let node = role.node_name(robots.first().copied().unwrap_or(index));
    held.record(RunEvent::Signalled {
        node: node.clone(),
        pid: p.pid,
        signal: signal.to_string(),
        fault: None,
        round,
    });
    drop(held);
    Ok(Killed {
        node,
        robots,
        pid: p.pid,
        signal,
        round,
        journal: record.dir.join(super::events::EVENTS_FILE),
    })
}

/// The record of the part of run `run` that runs `role`/`index`: `record`, unless another
/// host runs it and that host's part runs on this machine too (hosts of a run across hosts
/// sharing a machine, each in its own domain).
fn target_host_part(
    registry: &RunRegistry,
    run: &str,
    record: RunRecord,
    role: Role,
    index: u32,
) -> RunRecord {
    let host = record
        .processes
        .iter()
        .find(|p| p.role == role && p.index == index)
        .and_then(|p| p.host.as_deref());
    host.and_then(|h| registry.live_host_part(run, h))
        .unwrap_or(record)
}

/// The index of the process `coordinator` names: 0 for a single coordinator, else the
/// replica that leads in the highest term its role file shows.
fn coordinator_index(run: &str, record: &RunRecord) -> Result<u32, KillError> {
    let replicas: Vec<u32> = record
        .processes
        .iter()
        .filter(|p| p.role == Role::Coordinator)
        .map(|p| p.index)
        .collect();
    if replicas.is_empty() || replicas.contains(&0) {
        return Ok(0);
    }
    let log = record.dir.join("log");
    replicas
        .iter()
        .filter_map(|&id| {
            let shown = ReplicaRole::read(&log.join(id.to_string()))?;
            (shown.role == "leader").then_some((shown.term, id))
        })
        .max()
        .map(|(_, id)| id)
        .ok_or_else(|| KillError::NoLeader {
            run: run.into(),
            has: format!(
                "coordinator:{}-{}",
                replicas.iter().min().unwrap_or(&1),
                replicas.iter().max().unwrap_or(&1)
            ),
        })
}

/// The last round of the consensus log in `dir`, a single coordinator's or the replicas'
/// (0 if it has none or cannot be read: the signal is sent either way, and the journal's
/// stamp says when).
fn last_round(dir: &Path) -> u64 {
    read_decided(dir).map_or(0, |d| d.last_round())
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::transport::RunId;

    /// A registry in `tmp` holding one run `id` whose supervisor is this process, with a
    /// coordinator and two agents; agent 1 is `live` (a process that runs), the others have
    /// pids that exited.
    fn registry_with(tmp: &Path, id: &str, live: u32) -> RunRegistry {
        let registry = RunRegistry::at(tmp.join("runs"));
        let run = RunId::new(id).unwrap();
        let mut record = registry.new_record(&run, tmp.join("dir"));
        let gone = exited_pid();
        record.set_process(Role::Coordinator, 0, gone, 0);
        record.set_process(Role::Agent, 0, gone, 0);
        record.set_process(Role::Agent, 1, live, 0);
        record.write().unwrap();
        registry
    }

    /// A live process to signal: `sleep 30`.
    fn sleeper() -> std::process::Child {
        std::process::Command::new("sleep")
            .arg("30")
            .spawn()
            .unwrap()
    }

    /// The pid of a process that has exited and been reaped.
    fn exited_pid() -> u32 {
        let mut c = std::process::Command::new("true").spawn().unwrap();
        let pid = c.id();
        c.wait().unwrap();
        pid
    }

    #[test]
    fn a_live_target_is_signalled_and_the_journal_says_so() {
        let tmp = tempfile::tempdir().unwrap();
        let mut sleeper = sleeper();
        let registry = registry_with(tmp.path(), "kill-ok", sleeper.id());
        std::fs::create_dir_all(tmp.path().join("dir")).unwrap();
        let k = kill(&registry, "kill-ok", FaultTarget::Agent(1), Signal::SIGKILL).unwrap();
        assert_eq!(
            (k.node.as_str(), k.pid, k.round),
            ("agent-1", sleeper.id(), 0)
        );
        use std::os::unix::process::ExitStatusExt;
        assert_eq!(sleeper.wait().unwrap().signal(), Some(9));
        let text = std::fs::read_to_string(&k.journal).unwrap();
        let line: serde_json::Value = serde_json::from_str(text.trim()).unwrap();
        assert_eq!(line["event"], "signalled");
        assert_eq!(line["node"], "agent-1");
        assert_eq!(line["signal"], "SIGKILL");
        assert!(line["fault"].is_null());
    }

    /// `agent:N` of robots that share a process (`[run] agents_per_process`) signals that
    /// process, and the journal names it by its first robot, as the supervisor's lines do.
    #[test]
    fn a_robot_of_a_shared_process_takes_its_process_and_the_journal_names_it() {
        let tmp = tempfile::tempdir().unwrap();
        let mut sleeper = sleeper();
        let registry = RunRegistry::at(tmp.path().join("runs"));
        let run = RunId::new("kill-shared").unwrap();
        let mut record = registry.new_record(&run, tmp.path().join("dir"));
        let gone = exited_pid();
        for (i, pid) in [(0, gone), (1, gone), (2, sleeper.id()), (3, sleeper.id())] {
            record.set_process(Role::Agent, i, pid, 0);
        }
        record.write().unwrap();
        std::fs::create_dir_all(tmp.path().join("dir")).unwrap();
        let k = kill(
            &registry,
            "kill-shared",
            FaultTarget::Agent(3),
            Signal::SIGKILL,
        )
        .unwrap();
        assert_eq!(
            (k.node.as_str(), k.robots.as_slice()),
            ("agent-2", &[2, 3][..])
        );
        use std::os::unix::process::ExitStatusExt;
        assert_eq!(sleeper.wait().unwrap().signal(), Some(9));
        let text = std::fs::read_to_string(&k.journal).unwrap();
        let line: serde_json::Value = serde_json::from_str(text.trim()).unwrap();
        assert_eq!(line["node"], "agent-2");
    }

    #[test]
    fn coordinator_names_the_replica_that_leads_in_the_highest_term() {
        let tmp = tempfile::tempdir().unwrap();
        let mut sleeper = sleeper();
        let registry = RunRegistry::at(tmp.path().join("runs"));
        let run = RunId::new("kill-leader").unwrap();
        let dir = tmp.path().join("dir");
        let mut record = registry.new_record(&run, dir.clone());
        let gone = exited_pid();
        record.set_process(Role::Coordinator, 1, gone, 0);
        record.set_process(Role::Coordinator, 2, sleeper.id(), 0);
        record.set_process(Role::Coordinator, 3, gone, 0);
        record.write().unwrap();
        let show = |id: u32, role: &str, term: u64| {
            let d = dir.join("log").join(id.to_string());
            std::fs::create_dir_all(&d).unwrap();
            let role = role.to_string();
            ReplicaRole { role, term }.write(&d).unwrap();
        };
        show(1, "follower", 3);
        show(2, "candidate", 3);
        show(3, "follower", 3);
        let e = kill(
            &registry,
            "kill-leader",
            FaultTarget::Coordinator,
            Signal::SIGKILL,
        )
        .unwrap_err()
        .to_string();
        assert_eq!(
            e,
            "no coordinator replica of run `kill-leader` leads right now (an election may be \
             under way); name one: coordinator:1-3"
        );
        // A deposed leader that has not noticed yet shows an older term.
        show(1, "leader", 2);
        show(2, "leader", 3);
        let k = kill(
            &registry,
            "kill-leader",
            FaultTarget::Coordinator,
            Signal::SIGKILL,
        )
        .unwrap();
        assert_eq!((k.node.as_str(), k.pid), ("coordinator-2", sleeper.id()));
        use std::os::unix::process::ExitStatusExt;
        assert_eq!(sleeper.wait().unwrap().signal(), Some(9));
    }

    #[test]
    fn what_cannot_be_signalled_is_refused_with_its_reason() {
        let tmp = tempfile::tempdir().unwrap();
        let registry = registry_with(tmp.path(), "kill-no", exited_pid());
        let err = |run: &str, target| {
            kill(&registry, run, target, Signal::SIGKILL)
                .unwrap_err()
                .to_string()
        };
        assert_eq!(
            err("kill-other", FaultTarget::Agent(0)),
            format!(
                "no live run `kill-other` in the run registry {} (`hnav ps` lists the live runs)",
                registry.dir().display()
            )
        );
        assert_eq!(
            err("kill-no", FaultTarget::Agent(2)),
            "run `kill-no` has no agent:2 (its agents are 0-1)"
        );
        assert_eq!(
            err("kill-no", FaultTarget::Sim),
            "run `kill-no` has no sim (its agents are 0-1)"
        );
        let e = err("kill-no", FaultTarget::Agent(1));
        assert!(
            e.starts_with("agent:1 of run `kill-no` is not running (pid "),
            "{e}"
        );
        assert!(err("bad id!", FaultTarget::Sim).contains("bad id!"));

        // A run whose supervisor died.
        let run = RunId::new("kill-dead").unwrap();
        let mut record = registry.new_record(&run, tmp.path().join("dir"));
        record.supervisor_pid = exited_pid();
        record.supervisor_start_ticks = None;
        record.write().unwrap();
        assert_eq!(
            err("kill-dead", FaultTarget::Agent(0)),
            format!(
                "run `kill-dead` is dead: its supervisor (pid {}) is gone (`hnav clean kill-dead` removes what it left)",
                record.supervisor_pid
            )
        );
    }

    /// A log of `rounds` empty rounds in `dir`: long enough that reading its last round takes
    /// `hnav kill` a while.
    fn long_log(dir: &Path, rounds: u64) {
        use hnav_runtime::consensus_log::{LogWriter, Record, RoundRecord, RunHeader};
        let (mut w, _) = LogWriter::open(dir, hnav_runtime::scenario::FsyncPolicy::None).unwrap();
        w.append(&Record::Header(RunHeader {
            version: hnav_runtime::consensus_log::FORMAT_VERSION,
            scenario_hash: 1,
            seed: 1,
            clock: "lockstep".into(),
            width: 1,
            height: 1,
            agents: Vec::new(),
        }))
        .unwrap();
        for round in 1..=rounds {
            w.append(&Record::Round(RoundRecord::new(round, &[], &[])))
                .unwrap();
        }
        w.sync().unwrap();
    }

    #[test]
    fn the_signal_is_journalled_before_the_exit_it_causes() {
        let tmp = tempfile::tempdir().unwrap();
        let mut sleeper = sleeper();
        let registry = registry_with(tmp.path(), "kill-order", sleeper.id());
        let dir = tmp.path().join("dir");
        long_log(&dir.join("log"), 100_000);
        // The supervisor's part, as its watch does it: the death wakes it, it reaps the
        // child and journals the exit at once.
        let pid = sleeper.id();
        let journal_dir = dir.clone();
        let supervisor = std::thread::spawn(move || {
            let status = sleeper.wait().unwrap();
            RunEvents::append(&journal_dir).record(RunEvent::Exited {
                node: "agent-1".into(),
                pid,
                how: format!("{status}"),
            });
        });
        let k = kill(
            &registry,
            "kill-order",
            FaultTarget::Agent(1),
            Signal::SIGKILL,
        )
        .unwrap();
        supervisor.join().unwrap();
        assert_eq!(k.round, 100_000);
        let text = std::fs::read_to_string(&k.journal).unwrap();
        let events: Vec<serde_json::Value> = text
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        let names: Vec<&str> = events
            .iter()
            .map(|e| e["event"].as_str().unwrap())
            .collect();
        assert_eq!(
            names,
            ["signalled", "exited"],
            "the journal must read in the order things happened:\n{text}"
        );
        assert!(
            events[0]["t_ns"].as_u64() <= events[1]["t_ns"].as_u64(),
            "{text}"
        );
    }
}
