//! The on-disk list of live runs, so that `hnav ps` (a separate, short-lived process) can
//! find every supervisor on the machine and the processes it started.
//!
//! Each supervisor owns one JSON file, `<runs dir>/<key>.json`, holding a [`RunRecord`]; the
//! key is the run id, or `<run_id>.<domain>` for a run in an iceoryx2 domain (`HNAV_DOMAIN`,
//! or the host's name for `hnav run --host NAME`): the supervisors of two hosts of one run
//! across hosts can then share a machine, each with its own entry.
//! It rewrites the file after every spawn and restart, and removes it when the run ends.
//! Writes go through [`replace_file`] (a synced temporary file renamed over the old one): a
//! reader sees either the old record or the new one, never a torn one, and after a crash of
//! the machine `hnav ps` and `hnav clean` find whole records of the runs it ended.
//!
//! A supervisor that died without cleaning up leaves its file behind. Readers notice that its
//! supervisor is gone and report the run as *stale* (dead); `hnav clean` removes what it
//! left ([`super::clean`]). "Gone" means the pid does not exist, is a zombie, or now belongs
//! to another process: every record keeps the start time of each pid it names (from
//! `/proc/<pid>/stat`), so a reused pid is never taken for the run's process.
//!
//! A supervisor also holds an exclusive lock on `<runs dir>/<key>.lock` for its lifetime
//! ([`RunRegistry::claim`]): a second `hnav run` with the same id is refused before it
//! touches anything, and the kernel drops the lock when the supervisor dies.
//!
//! A run asked for by id alone ([`RunRegistry::find_live`]) is the entry of that id outside
//! any domain; failing that, its host's part on this machine, and where several hosts of it
//! run here, the part that runs the coordinator (the one with the log).
//!
//! The directory is `$HNAV_RUNS_DIR` if that is set, else `<temp dir>/hnav-runs`.
//! Tests use [`RunRegistry::at`] rather than the environment, which all the tests of one
//! binary share.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use hnav_runtime::durable::replace_file;
use hnav_runtime::file_lock::{try_lock, FileLock, TryLock};
use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::msg::Role;
use hnav_runtime::transport::{RunId, TransportError};

/// The environment variable that overrides the registry directory.
pub const RUNS_DIR_ENV: &str = "HNAV_RUNS_DIR";

/// What went wrong reading or writing a registry file.
#[derive(Debug, thiserror::Error)]
pub enum RegistryError {
    /// A file or directory operation failed.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// Another live supervisor holds the run id.
    #[error("run id {run} is in use by a live run (supervisor pid {}, directory {}); choose another --run, or stop that run first", pid.as_deref().unwrap_or("unknown"), dir.as_deref().unwrap_or("unknown"))]
    InUse {
        /// The run id.
        run: String,
        /// The holder's pid, as its lock file names it.
        pid: Option<String>,
        /// The holder's run directory, as its lock file names it.
        dir: Option<String>,
    },
    /// A record is not valid JSON of the expected shape.
    #[error("{path}: not a run record: {source}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: serde_json::Error,
    },
}

/// Why a run asked for by id (`hnav kill RUN`, `hnav services RUN`) is not a live one.
#[derive(Debug, thiserror::Error)]
pub enum LiveRunError {
    /// The run id is not a valid one.
    #[error(transparent)]
    RunId(#[from] hnav_runtime::transport::TransportError),
    /// The registry has no such run.
    #[error("no live run `{run}` in the run registry {} (`hnav ps` lists the live runs)", dir.display())]
    UnknownRun {
        /// The run id.
        run: String,
        /// The registry directory.
        dir: PathBuf,
    },
    /// The run's supervisor is gone.
    #[error("run `{run}` is dead: its supervisor (pid {pid}) is gone (`hnav clean {run}` removes what it left)")]
    DeadRun {
        /// The run id.
        run: String,
        /// The supervisor's pid.
        pid: u32,
    },
    /// The registry could not be read.
    #[error(transparent)]
    Registry(#[from] RegistryError),
}

/// Where run records live.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunRegistry {
    dir: PathBuf,
}

impl RunRegistry {
    /// A registry in `dir` (created on the first write).
    pub fn at(dir: impl Into<PathBuf>) -> Self {
        Self { dir: dir.into() }
    }

    /// `$HNAV_RUNS_DIR` if set and not empty, else `<temp dir>/hnav-runs`.
    pub fn default_location() -> Self {
        match std::env::var_os(RUNS_DIR_ENV) {
            Some(d) if !d.is_empty() => Self::at(d),
            _ => Self::at(std::env::temp_dir().join("hnav-runs")),
        }
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// A new record of `run` (output directory `dir`, made absolute: the tools that read it,
    /// `hnav kill` writing to the run's journal, run elsewhere) for this process as its
    /// supervisor, started now, with no processes yet. Nothing is written until
    /// [`RunRecord::write`].
    pub fn new_record(&self, run: &RunId, dir: impl Into<PathBuf>) -> RunRecord {
        let dir: PathBuf = dir.into();
        let dir = std::path::absolute(&dir).unwrap_or(dir);
        let started_unix_ms = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_millis() as u64)
            .unwrap_or(0);
        let supervisor_pid = std::process::id();
        RunRecord {
            run_id: run.as_str().to_string(),
            dir,
            supervisor_pid,
            supervisor_start_ticks: process_start_ticks(supervisor_pid),
            started_unix_ms,
            processes: Vec::new(),
            process_args: Vec::new(),
            domain: run.domain().map(str::to_string),
            file: self.record_path(run),
        }
    }

    /// Every readable record, oldest run first. Unreadable or malformed files are skipped
    /// with a warning; a missing directory means no runs.
    pub fn list_runs(&self) -> Vec<RunEntry> {
        let entries = match std::fs::read_dir(&self.dir) {
            Ok(e) => e,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Vec::new(),
            Err(e) => {
                tracing::warn!(dir = %self.dir.display(), error = %e, "cannot read the run registry");
                return Vec::new();
            }
        };
        let mut runs = Vec::new();
        for entry in entries.filter_map(Result::ok) {
            let name = entry.file_name();
            let name = name.to_string_lossy();
            if name.starts_with('.') || !name.ends_with(".json") {
                continue; // temporary files of writes in flight, and strangers
            }
            match RunRecord::read(&entry.path()) {
                Ok(record) => {
                    let stale = !record.supervisor_alive();
                    runs.push(RunEntry { record, stale });
                }
                Err(e) => tracing::warn!(error = %e, "skipping run record"),
            }
        }
        runs.sort_by(|a, b| {
            (a.record.started_unix_ms, &a.record.run_id)
                .cmp(&(b.record.started_unix_ms, &b.record.run_id))
        });
        runs
    }

    /// The record of `run`, if the registry has one.
    pub fn find(&self, run: &RunId) -> Result<Option<RunRecord>, RegistryError> {
        let path = self.record_path(run);
        match RunRecord::read(&path) {
            Ok(r) => Ok(Some(r)),
            Err(RegistryError::Io { source, .. })
                if source.kind() == std::io::ErrorKind::NotFound =>
            {
                Ok(None)
            }
            Err(e) => Err(e),
        }
    }

    /// The record of the live run `run`: known to the registry and its supervisor alive.
    /// The id is the record's: in a host part's domain when that is what was found.
    pub fn find_live(&self, run: &str) -> Result<(RunId, RunRecord), LiveRunError> {
        let id = RunId::new(run)?;
        let record = match self.find(&id)? {
            Some(r) => r,
            None => self
                .host_part(&id)
                .ok_or_else(|| LiveRunError::UnknownRun {
                    run: run.into(),
                    dir: self.dir.clone(),
                })?,
        };
        let record = Self::alive(record)?;
        Ok((record.run()?, record))
    }

    /// The record of the live run `run`, its domain included (no other host's part).
    pub fn find_live_id(&self, run: &RunId) -> Result<RunRecord, LiveRunError> {
        let record = self.find(run)?.ok_or_else(|| LiveRunError::UnknownRun {
            run: run.as_str().into(),
            dir: self.dir.clone(),
        })?;
        Self::alive(record)
    }

    /// `record`, if its supervisor is alive.
    fn alive(record: RunRecord) -> Result<RunRecord, LiveRunError> {
        if record.supervisor_alive() {
            Ok(record)
        } else {
            Err(LiveRunError::DeadRun {
                run: record.run_id,
                pid: record.supervisor_pid,
            })
        }
    }

    /// For an id outside any domain: the part of run `run` that a host of a run across hosts
    /// runs on this machine (in the host's domain); of several, the one that runs the
    /// coordinator, else the oldest; live parts before dead ones.
    fn host_part(&self, run: &RunId) -> Option<RunRecord> {
        if run.domain().is_some() {
            return None;
        }
        let mut parts: Vec<RunEntry> = self
            .list_runs()
            .into_iter()
            .filter(|e| e.record.run_id == run.as_str() && e.record.domain.is_some())
            .collect();
        let coordinator = |r: &RunRecord| {
            r.processes
                .iter()
                .any(|p| p.role == Role::Coordinator && p.host.is_none())
        };
        // Stable: the registry's order (oldest first) among equals.
        parts.sort_by_key(|e| (e.stale, !coordinator(&e.record)));
        parts.into_iter().next().map(|e| e.record)
    }

    /// The live part of run `run` that host `host` of a run across hosts runs on this
    /// machine, if one does (`hnav kill` of a process of another host).
    pub fn live_host_part(&self, run: &str, host: &str) -> Option<RunRecord> {
        let id = RunId::new(run).ok()?.in_domain(host).ok()?;
        self.find_live_id(&id).ok()
    }

    /// Claims `run` for this process (a supervisor starting it in `dir`, or `hnav clean`
    /// removing it) until the claim is released or the process dies. Refused with
    /// [`RegistryError::InUse`] while another process holds it.
    pub fn claim(&self, run: &RunId, dir: &Path) -> Result<RunClaim, RegistryError> {
        let path = self.dir.join(format!("{}.lock", key(run)));
        let fields = [
            ("run", run.as_str().to_string()),
            ("pid", std::process::id().to_string()),
            ("dir", dir.display().to_string()),
        ];
        match try_lock(&path, &fields) {
            Ok(TryLock::Acquired(lock)) => Ok(RunClaim { lock }),
            Ok(TryLock::Held(holder)) => Err(RegistryError::InUse {
                run: run.as_str().to_string(),
                pid: holder.get("pid").map(str::to_string),
                dir: holder.get("dir").map(str::to_string),
            }),
            Err(source) => Err(RegistryError::Io { path, source }),
        }
    }

    fn record_path(&self, run: &RunId) -> PathBuf {
        self.dir.join(format!("{}.json", key(run)))
    }
}

/// The name of `run`'s files in the registry: its id, or `<id>.<domain>` in a domain (`.` is
/// in no id and no domain, so no two runs share a key).
fn key(run: &RunId) -> String {
    match run.domain() {
        None => run.as_str().to_string(),
        Some(domain) => format!("{}.{domain}", run.as_str()),
    }
}

/// A run id claimed with [`RunRegistry::claim`].
#[derive(Debug)]
pub struct RunClaim {
    lock: FileLock,
}

impl RunClaim {
    /// Gives the id up and removes its lock file.
    pub fn release(self) -> Result<(), RegistryError> {
        let path = self.lock.path().to_path_buf();
        self.lock
            .remove()
            .map_err(|source| RegistryError::Io { path, source })
    }
}

/// One process of a run, as its supervisor last recorded it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ProcessRecord {
    /// Its role ([`Role::name`] in JSON).
    pub role: Role,
    /// The agent index, else 0.
    pub index: u32,
    /// The pid of its current incarnation (also its process group: every child leads its own).
    pub pid: u32,
    /// When that pid started (clock ticks since boot), to tell it from a reused pid.
    #[serde(default)]
    pub start_ticks: Option<u64>,
    /// Restarts so far.
    pub restarts: u32,
    /// In a run across hosts, the other host that runs it (its pid is then 0: this
    /// supervisor only knows that it is there).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub host: Option<String>,
}

/// The registry file of one run.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunRecord {
    /// The run id.
    pub run_id: String,
    /// The run's output directory.
    pub dir: PathBuf,
    /// The supervisor's pid.
    pub supervisor_pid: u32,
    /// When the supervisor started (clock ticks since boot), to tell it from a reused pid.
    #[serde(default)]
    pub supervisor_start_ticks: Option<u64>,
    /// When the supervisor started the run, in milliseconds since the Unix epoch.
    pub started_unix_ms: u64,
    /// The run's processes, one entry per role and index.
    pub processes: Vec<ProcessRecord>,
    /// The command line the run's processes share ([`ProcessArgs::to_args`]) with the scenario
    /// and the run directory absolute, so that a viewer started elsewhere (`hnav top`) loads
    /// the same scenario; empty in records of supervisors that predate it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub process_args: Vec<String>,
    /// The iceoryx2 domain the run's processes here meet in ([`RunId::domain`]): the host's
    /// name for a host of a run across hosts, or `HNAV_DOMAIN`; none outside a domain.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub domain: Option<String>,
    #[serde(skip)]
    file: PathBuf,
}

impl RunRecord {
    /// Reads a record file.
    pub fn read(path: &Path) -> Result<RunRecord, RegistryError> {
        let text = std::fs::read(path).map_err(|source| RegistryError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut record: RunRecord =
            serde_json::from_slice(&text).map_err(|source| RegistryError::Parse {
                path: path.to_path_buf(),
                source,
            })?;
        record.file = path.to_path_buf();
        Ok(record)
    }

    /// The file this record is written to (or was read from).
    pub fn path(&self) -> &Path {
        &self.file
    }

    /// The run's id in its domain, as its processes here name their shared memory. A record
    /// that names no domain (also those of supervisors that predate the field) takes
    /// `HNAV_DOMAIN`'s, as its supervisor did.
    pub fn run(&self) -> Result<RunId, TransportError> {
        let id = RunId::new(&self.run_id)?;
        match &self.domain {
            Some(d) => id.in_domain(d),
            None => Ok(id),
        }
    }

    /// Whether the supervisor that wrote this record still runs.
    pub fn supervisor_alive(&self) -> bool {
        process_alive(self.supervisor_pid, self.supervisor_start_ticks)
    }

    /// Records the current incarnation of `role`/`index`, replacing an older one.
    pub fn set_process(&mut self, role: Role, index: u32, pid: u32, restarts: u32) {
        let start_ticks = match self
            .processes
            .iter()
            .find(|p| p.role == role && p.index == index && p.pid == pid)
        {
            Some(p) if p.start_ticks.is_some() => p.start_ticks,
            _ => process_start_ticks(pid),
        };
        self.put(ProcessRecord {
            role,
            index,
            pid,
            start_ticks,
            restarts,
            host: None,
        });
    }

    /// Records process `role`/`index` as run by another host, `host`.
    pub fn set_remote(&mut self, role: Role, index: u32, host: &str) {
        self.put(ProcessRecord {
            role,
            index,
            pid: 0,
            start_ticks: None,
            restarts: 0,
            host: Some(host.to_string()),
        });
    }

    /// Replaces the entry of `new`'s role and index, or adds it.
    fn put(&mut self, new: ProcessRecord) {
        let same = |p: &&mut ProcessRecord| p.role == new.role && p.index == new.index;
        match self.processes.iter_mut().find(same) {
            Some(p) => *p = new,
            None => self.processes.push(new),
        }
    }

    /// Records the processes' shared command line ([`RunRecord::process_args`]).
    pub fn set_process_args(&mut self, args: &ProcessArgs) {
        let mut args = args.clone();
        fn absolute(p: &Path) -> PathBuf {
            std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
        }
        args.scenario = absolute(&args.scenario);
        args.dir = args.dir.as_deref().map(absolute);
        self.process_args = args
            .to_args()
            .into_iter()
            .map(|a| a.to_string_lossy().into_owned())
            .collect();
    }

    /// The processes' shared command line, parsed back; `None` when the record has none or it
    /// does not parse (a record of another version).
    pub fn parsed_process_args(&self) -> Option<ProcessArgs> {
        #[derive(clap::Parser)]
        struct Line {
            #[command(flatten)]
            args: ProcessArgs,
        }
        if self.process_args.is_empty() {
            return None;
        }
        let argv = std::iter::once("hnav").chain(self.process_args.iter().map(String::as_str));
        <Line as clap::Parser>::try_parse_from(argv)
            .ok()
            .map(|l| l.args)
    }

    /// Writes the record whole or not at all ([`replace_file`]: synced temporary file, then
    /// rename), creating the directory.
    pub fn write(&self) -> Result<(), RegistryError> {
        let dir = self.file.parent().unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir).map_err(|source| RegistryError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        let json = serde_json::to_vec_pretty(self).map_err(|source| RegistryError::Parse {
            path: self.file.clone(),
            source,
        })?;
        replace_file(&self.file, &json).map_err(|source| RegistryError::Io {
            path: self.file.clone(),
            source,
        })
    }

    /// Removes the record file; a file already gone is not an error.
    pub fn remove(&self) -> Result<(), RegistryError> {
        match std::fs::remove_file(&self.file) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
            Err(source) => Err(RegistryError::Io {
                path: self.file.clone(),
                source,
            }),
        }
    }
}

/// A record found in the registry.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunEntry {
    /// The record.
    pub record: RunRecord,
    /// Its supervisor is gone: the file was left behind.
    pub stale: bool,
}

/// Whether a pid names a live process: `kill(pid, 0)` succeeds (or is refused, which means
/// the process exists but belongs to someone else), and it is not a zombie.
pub fn pid_alive(pid: u32) -> bool {
    // pid 0 and negative values address process groups, not a process.
    let Ok(raw) = i32::try_from(pid) else {
        return false;
    };
    if raw <= 0 {
        return false;
    }
    match nix::sys::signal::kill(nix::unistd::Pid::from_raw(raw), None) {
        Ok(()) | Err(nix::errno::Errno::EPERM) => !is_zombie(pid),
        Err(_) => false,
    }
}

/// Whether `pid` is alive ([`pid_alive`]) and, when `start_ticks` is known, is still the
/// process that started then rather than a later one that got the same pid.
pub fn process_alive(pid: u32, start_ticks: Option<u64>) -> bool {
    if !pid_alive(pid) {
        return false;
    }
    match (start_ticks, process_start_ticks(pid)) {
        (Some(want), Some(now)) => want == now,
        // Without /proc to ask, the pid is all there is.
        _ => true,
    }
}

/// When `pid` started, in clock ticks since boot: field 22 of `/proc/<pid>/stat`.
pub fn process_start_ticks(pid: u32) -> Option<u64> {
    stat_field(pid, 22)
}

/// The CPU time `pid` has used so far, user and system, in clock ticks: fields 14 and 15
/// of `/proc/<pid>/stat`. `hnav top` turns two readings into a CPU share.
pub fn process_cpu_ticks(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let fields = fields_after_name(&stat)?;
    let mut fields = fields.skip(11);
    let user: u64 = fields.next()?.parse().ok()?;
    let system: u64 = fields.next()?.parse().ok()?;
    Some(user + system)
}

/// Field `n` (1-based, as `proc(5)` numbers them; `n >= 3`) of `/proc/<pid>/stat`.
fn stat_field(pid: u32, n: usize) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let field = fields_after_name(&stat)?.nth(n - 3)?.parse().ok();
    field
}

/// The fields of a `/proc/<pid>/stat` line from field 3 (the state) on.
fn fields_after_name(stat: &str) -> Option<impl Iterator<Item = &str>> {
    // The command name (field 2) is parenthesised and may itself hold spaces or ')'.
    Some(stat[stat.rfind(')')? + 1..].split_whitespace())
}

/// Reads the state letter of `/proc/<pid>/stat` (after the parenthesised command name).
fn is_zombie(pid: u32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .ok()
        .and_then(|s| {
            s.rfind(')')
                .map(|i| s[i + 1..].trim_start().starts_with('Z'))
        })
        .unwrap_or(false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_process_is_alive_and_a_wrong_start_time_is_not() {
        let me = std::process::id();
        let ticks = process_start_ticks(me).expect("/proc names our start time");
        assert!(process_alive(me, Some(ticks)));
        assert!(process_alive(me, None));
        assert!(!process_alive(me, Some(ticks + 1)), "a reused pid");
    }

    #[test]
    fn cpu_ticks_grow_while_this_process_computes() {
        let me = std::process::id();
        let before = process_cpu_ticks(me).expect("/proc names our CPU time");
        let spin_until = std::time::Instant::now() + std::time::Duration::from_secs(5);
        let mut x = 0u64;
        while process_cpu_ticks(me).unwrap() < before + 2 && std::time::Instant::now() < spin_until
        {
            for i in 0..100_000u64 {
                x = std::hint::black_box(x.wrapping_mul(31).wrapping_add(i));
            }
        }
        assert!(
            process_cpu_ticks(me).unwrap() >= before + 2,
            "no CPU time counted in 5 s of computing"
        );
    }

    #[test]
    fn two_hosts_of_one_run_share_a_registry_each_in_its_domain() {
        let tmp = tempfile::tempdir().unwrap();
        let registry = RunRegistry::at(tmp.path());
        let id = RunId::new("across-1").unwrap();
        let (base, robots) = (
            id.clone().in_domain("base").unwrap(),
            id.clone().in_domain("robot-0").unwrap(),
        );
        let _b = registry.claim(&base, Path::new("out-base")).unwrap();
        let _r = registry.claim(&robots, Path::new("out-robots")).unwrap();
        assert!(
            matches!(
                registry.claim(&base, Path::new("x")),
                Err(RegistryError::InUse { .. })
            ),
            "one host's part is still claimed once only"
        );
        let me = std::process::id();
        let mut r = registry.new_record(&robots, "out-robots");
        r.set_process(Role::Agent, 0, me, 0);
        r.set_remote(Role::Coordinator, 0, "base");
        r.write().unwrap();
        let mut b = registry.new_record(&base, "out-base");
        b.set_process(Role::Coordinator, 0, me, 0);
        b.set_remote(Role::Agent, 0, "robot-0");
        b.write().unwrap();
        assert_eq!(registry.list_runs().len(), 2);
        // By id alone: the part with the coordinator, in its domain.
        let (found, record) = registry.find_live("across-1").unwrap();
        let cwd = std::env::current_dir().unwrap();
        assert_eq!((found, record.dir), (base.clone(), cwd.join("out-base")));
        assert_eq!(
            registry
                .live_host_part("across-1", "robot-0")
                .unwrap()
                .run()
                .unwrap(),
            robots
        );
        assert!(registry.live_host_part("across-1", "robot-1").is_none());
        assert_eq!(
            registry.find_live_id(&robots).unwrap().dir,
            cwd.join("out-robots")
        );
    }

    #[test]
    fn process_args_come_back_absolute() {
        let registry = RunRegistry::at("/nonexistent");
        let run = RunId::new("args-1").unwrap();
        let mut record = registry.new_record(&run, "out");
        assert_eq!(record.parsed_process_args(), None);
        let args = ProcessArgs {
            run: "args-1".into(),
            scenario: "scenarios/demo.toml".into(),
            agents: Some(3),
            seed: Some(7),
            mode: None,
            replicas: None,
            dir: Some("out".into()),
            resume: false,
            faults: Vec::new(),
        };
        record.set_process_args(&args);
        let back = record.parsed_process_args().unwrap();
        let cwd = std::env::current_dir().unwrap();
        assert_eq!(back.scenario, cwd.join("scenarios/demo.toml"));
        assert_eq!(back.dir, Some(cwd.join("out")));
        assert_eq!((back.agents, back.seed), (Some(3), Some(7)));
    }
}
