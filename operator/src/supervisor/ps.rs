//! What `hnav ps` shows: every registered run with the current state of its processes.
//!
//! The state combines two sources. [`process_alive`] says whether the pid exists and is
//! still the process the run started (its start time is recorded). The run's iceoryx2 node list says whether the process died without leaving the
//! run: its node is then `Dead`, and its shared memory remains until somebody cleans up.
//! A dead node takes precedence: its pid may already be a zombie or be reused.
//!
//! A run whose supervisor is gone is *dead* (`stale` in JSON): the table marks it and names
//! the command that removes what it left, `hnav clean RUN` ([`super::clean`]).

use std::path::PathBuf;

use serde::Serialize;

use super::registry::{process_alive, RunEntry, RunRegistry};
use hnav_runtime::consensus_log::ReplicaRole;
use hnav_runtime::msg::Role;
use hnav_runtime::transport::{NodeLiveness, Transport};

/// A process's state as `hnav ps` shows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ProcessState {
    /// The pid is alive.
    Running,
    /// The pid is gone (or a zombie waiting to be reaped).
    Exited,
    /// iceoryx2 lists the process's node as dead: it died without leaving the run.
    Dead,
    /// Another host runs it (a run across hosts): its supervisor watches it.
    Remote,
}

impl ProcessState {
    /// `running`, `exited` or `dead`.
    pub fn as_str(&self) -> &'static str {
        match self {
            ProcessState::Running => "running",
            ProcessState::Exited => "exited",
            ProcessState::Dead => "dead",
            ProcessState::Remote => "remote",
        }
    }
}

/// One process in `hnav ps`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ProcessStatus {
    /// Its role ([`Role::name`] in JSON).
    pub role: Role,
    /// Its index.
    pub index: u32,
    /// Its pid.
    pub pid: u32,
    /// Its state.
    pub state: ProcessState,
    /// Restarts so far.
    pub restarts: u32,
    /// A coordinator replica's Raft role and term, as it last wrote them (absent for a
    /// single coordinator and for other roles).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub raft: Option<ReplicaRole>,
    /// The other host that runs it, in a run across hosts.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub host: Option<String>,
}

/// A dead iceoryx2 node of a run that no recorded process accounts for (an earlier
/// incarnation killed before the restart, say).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct DeadNode {
    /// The node name.
    pub name: String,
    /// Its pid, if known.
    pub pid: Option<i32>,
}

/// One run in `hnav ps`. The JSON field order is part of the interface: `run_id`, `dir`,
/// `processes` first.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct RunStatus {
    /// The run id.
    pub run_id: String,
    /// Its output directory.
    pub dir: PathBuf,
    /// Its processes.
    pub processes: Vec<ProcessStatus>,
    /// The supervisor is gone.
    pub stale: bool,
    /// The supervisor's pid.
    pub supervisor_pid: u32,
    /// Start time, milliseconds since the Unix epoch.
    pub started_unix_ms: u64,
    /// Dead nodes not matched to a recorded process.
    pub dead_nodes: Vec<DeadNode>,
}

impl RunStatus {
    /// Looks up the state of every process of `entry`.
    pub fn of(entry: RunEntry) -> RunStatus {
        let record = entry.record;
        let mut dead: Vec<DeadNode> = match record.run() {
            Ok(run) => match Transport::nodes_of(&run) {
                Ok(nodes) => nodes
                    .into_iter()
                    .filter(|n| n.liveness == NodeLiveness::Dead)
                    .map(|n| DeadNode {
                        name: n.name,
                        pid: n.pid,
                    })
                    .collect(),
                Err(e) => {
                    tracing::warn!(run = record.run_id, error = %e, "cannot list the run's nodes");
                    Vec::new()
                }
            },
            Err(e) => {
                tracing::warn!(error = %e, "run record with an invalid run id");
                Vec::new()
            }
        };
        let processes = record
            .processes
            .iter()
            .map(|p| {
                let found = dead
                    .iter()
                    .position(|d| d.pid.and_then(|x| u32::try_from(x).ok()) == Some(p.pid));
                let state = if p.host.is_some() {
                    ProcessState::Remote
                } else if let Some(i) = found {
                    dead.remove(i);
                    ProcessState::Dead
                } else if process_alive(p.pid, p.start_ticks) {
                    ProcessState::Running
                } else {
                    ProcessState::Exited
                };
                let raft = (p.role == Role::Coordinator && p.index > 0)
                    .then(|| ReplicaRole::read(&record.dir.join("log").join(p.index.to_string())))
                    .flatten();
                ProcessStatus {
                    role: p.role,
                    index: p.index,
                    pid: p.pid,
                    state,
                    restarts: p.restarts,
                    raft,
                    host: p.host.clone(),
                }
            })
            .collect();
        RunStatus {
            run_id: record.run_id,
            dir: record.dir,
            processes,
            stale: entry.stale,
            supervisor_pid: record.supervisor_pid,
            started_unix_ms: record.started_unix_ms,
            dead_nodes: dead,
        }
    }
}

/// Everything `hnav ps` prints.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct PsReport {
    /// The runs, oldest first.
    pub runs: Vec<RunStatus>,
}

impl PsReport {
    /// Every run of `registry` ([`RunRegistry::list_runs`]) with each process's current
    /// state.
    pub fn of(registry: &RunRegistry) -> PsReport {
        PsReport {
            runs: registry
                .list_runs()
                .into_iter()
                .map(RunStatus::of)
                .collect(),
        }
    }

    /// `{"runs": [...]}`, pretty-printed.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|_| r#"{"runs": []}"#.to_string())
    }

    /// The runs `arg` names: a run id, or a run directory (as a path from here). `None` when
    /// no run of the report is either.
    pub fn select(&self, arg: &str) -> Option<PsReport> {
        let wanted = std::path::Path::new(arg).canonicalize().ok();
        let runs: Vec<RunStatus> = self
            .runs
            .iter()
            .filter(|r| {
                r.run_id == arg
                    || r.dir == std::path::Path::new(arg)
                    || (wanted.is_some() && r.dir.canonicalize().ok() == wanted)
            })
            .cloned()
            .collect();
        (!runs.is_empty()).then_some(PsReport { runs })
    }

    /// One line per run (`hnav ps`): RUN, DIR, and its processes counted by state, with the
    /// Raft leader of a run with replicas (`10 running, leader coordinator:2 (term 2)`); a
    /// dead run is marked after its id, and a note under the table names `hnav clean RUN`.
    /// `hnav ps RUN` shows the processes ([`PsReport::render_table`]).
    pub fn render_summary(&self) -> String {
        if self.runs.is_empty() {
            return "no live runs\n".to_string();
        }
        let mut rows: Vec<[String; 3]> = vec![["RUN".into(), "DIR".into(), "PROCESSES".into()]];
        for run in &self.runs {
            let id = if run.stale {
                format!("{} (dead)", run.run_id)
            } else {
                run.run_id.clone()
            };
            rows.push([id, run.dir.display().to_string(), process_counts(run)]);
        }
        let mut out = aligned(&rows);
        out.push_str(&dead_run_notes(&self.runs));
        let any_dead = self.runs.iter().any(|r| {
            !r.dead_nodes.is_empty() || r.processes.iter().any(|p| p.state == ProcessState::Dead)
        });
        if any_dead {
            out.push_str(DEAD_NOTE);
        }
        if self.runs.iter().any(|r| !r.stale) {
            out.push_str("`hnav ps RUN` lists a run's processes\n");
        }
        out
    }

    /// A table with the columns RUN, DIR, ROLE, INDEX, PID, STATE (with a replica's Raft role
    /// and term: `running (leader, term 2)`), one row per process and
    /// per unmatched dead node; a dead run (its supervisor gone) is marked after its id, and
    /// a note under the table names `hnav clean RUN` for each.
    pub fn render_table(&self) -> String {
        if self.runs.is_empty() {
            return "no live runs\n".to_string();
        }
        let mut rows: Vec<[String; 6]> = vec![[
            "RUN".into(),
            "DIR".into(),
            "ROLE".into(),
            "INDEX".into(),
            "PID".into(),
            "STATE".into(),
        ]];
        let mut any_dead = false;
        for run in &self.runs {
            let id = if run.stale {
                format!("{} (dead)", run.run_id)
            } else {
                run.run_id.clone()
            };
            let dir = run.dir.display().to_string();
            for p in &run.processes {
                any_dead |= p.state == ProcessState::Dead;
                let mut state = match (p.state, &p.host) {
                    (ProcessState::Dead, _) => "dead *".to_string(),
                    (ProcessState::Remote, Some(h)) => format!("on host {h}"),
                    (s, _) => s.as_str().to_string(),
                };
                let pid = match p.state {
                    ProcessState::Remote => "-".to_string(),
                    _ => p.pid.to_string(),
                };
                if let Some(r) = p.raft.as_ref().filter(|_| p.state == ProcessState::Running) {
                    state += &format!(" ({}, term {})", r.role, r.term);
                }
                rows.push([
                    id.clone(),
                    dir.clone(),
                    p.role.name().into(),
                    p.index.to_string(),
                    pid,
                    state,
                ]);
            }
            for d in &run.dead_nodes {
                any_dead = true;
                let (role, index) = match d.name.rsplit_once('-') {
                    Some((r, i)) => (r.to_string(), i.to_string()),
                    None => (d.name.clone(), "-".to_string()),
                };
                let pid = d.pid.map_or_else(|| "?".to_string(), |p| p.to_string());
                rows.push([id.clone(), dir.clone(), role, index, pid, "dead *".into()]);
            }
            if run.processes.is_empty() && run.dead_nodes.is_empty() {
                rows.push([id, dir, "-".into(), "-".into(), "-".into(), "-".into()]);
            }
        }
        let mut out = aligned(&rows);
        out.push_str(&dead_run_notes(&self.runs));
        if any_dead {
            out.push_str(DEAD_NOTE);
        }
        out
    }
}

/// The footnote of a process marked `dead *`.
const DEAD_NOTE: &str = "* dead: the process died without leaving the run; its iceoryx2 node and \
                         shared memory remain until cleaned up\n";

/// `rows` as text, each column as wide as its widest cell, two spaces apart.
fn aligned<const N: usize>(rows: &[[String; N]]) -> String {
    let mut widths = [0usize; N];
    for row in rows {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(cell.chars().count());
        }
    }
    let mut out = String::new();
    for row in rows {
        let line: Vec<String> = row
            .iter()
            .zip(widths)
            .map(|(cell, w)| format!("{cell:<w$}"))
            .collect();
        out.push_str(line.join("  ").trim_end());
        out.push('\n');
    }
    out
}

/// A line for each dead run (its supervisor gone) naming the command that cleans it up.
fn dead_run_notes(runs: &[RunStatus]) -> String {
    runs.iter()
        .filter(|r| r.stale)
        .map(|run| {
            format!(
                "run {} is dead (its supervisor, pid {}, is gone): `hnav clean {}` removes what it left\n",
                run.run_id, run.supervisor_pid, run.run_id
            )
        })
        .collect()
}

/// A run's processes counted by state, in the order running, remote, exited, dead
/// (`150 running, 2 exited`), and the Raft leader if a replica says it leads.
fn process_counts(run: &RunStatus) -> String {
    let states = [
        ProcessState::Running,
        ProcessState::Remote,
        ProcessState::Exited,
        ProcessState::Dead,
    ];
    let mut parts: Vec<String> = states
        .iter()
        .filter_map(|s| {
            let n = run.processes.iter().filter(|p| p.state == *s).count();
            let word = match s {
                ProcessState::Remote => "on other hosts",
                ProcessState::Dead => "dead *",
                s => s.as_str(),
            };
            (n > 0).then(|| format!("{n} {word}"))
        })
        .collect();
    if !run.dead_nodes.is_empty() {
        parts.push(format!("{} dead node(s) *", run.dead_nodes.len()));
    }
    if parts.is_empty() {
        parts.push("none".into());
    }
    let mut text = parts.join(", ");
    let leader = run.processes.iter().find(|p| {
        p.state == ProcessState::Running && p.raft.as_ref().is_some_and(|r| r.role == "leader")
    });
    if let Some(p) = leader {
        let term = p.raft.as_ref().map_or(0, |r| r.term);
        text += &format!(", leader coordinator:{} (term {term})", p.index);
    }
    text
}
