//! One child process of a run: how it is started, how its exit is noticed, reaped and
//! described, and how it is signalled.
//!
//! Every child gets **its own process group** (`process_group(0)`): Ctrl-C on the terminal
//! then reaches only the supervisor, which decides how to stop the run, and a stop can signal
//! everything the child started (helpers, shells) with one `killpg`.
//!
//! Its stdout and stderr are **appended** to a log file, so the output of every incarnation
//! of a restarted child stays in one place, in order.
//!
//! Its exit is reported by an [`ExitFd`] (a pidfd, see [`super::exit_fd`]) that an iceoryx2
//! `Waiter` can block on next to the run's topics: no timer, no polling of `waitpid`.
//!
//! Reaping is explicit ([`Child::try_reap`]) and happens exactly once; afterwards the child is
//! never signalled again, because its pid may already belong to an unrelated process. A
//! [`Child`] dropped while its process still runs kills the process group and reaps it, so
//! an early return or a panic in the supervisor leaves neither zombies nor orphans.

use std::cell::Cell;
use std::ffi::OsString;
use std::fs::OpenOptions;
use std::io;
use std::os::unix::process::CommandExt;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use nix::errno::Errno;
pub use nix::sys::signal::Signal;
use nix::sys::signal::{kill, killpg};
use nix::sys::wait::{waitid, waitpid, Id, WaitPidFlag, WaitStatus};
use nix::unistd::Pid;

use super::exit_fd::{ExitFd, WatchMode};
use hnav_runtime::msg::Role;
use hnav_runtime::transport::{Attachment, TransportError, Waiter};

/// What went wrong starting or signalling a child.
#[derive(Debug, thiserror::Error)]
pub enum ChildError {
    /// The log file (or its directory) could not be created or opened.
    #[error("{path}: cannot open the log file: {source}")]
    LogFile {
        /// The log file.
        path: PathBuf,
        /// The cause.
        source: io::Error,
    },
    /// The program could not be started.
    #[error("{program}: cannot start: {source}")]
    Spawn {
        /// The program.
        program: PathBuf,
        /// The cause.
        source: io::Error,
    },
    /// The exit descriptor could not be created; the child was killed and reaped.
    #[error("cannot watch child {pid} for its exit: {source}")]
    Watch {
        /// The child's pid.
        pid: u32,
        /// The cause.
        source: io::Error,
    },
    /// `kill`/`killpg` failed (other than "no such process", which is not an error here).
    #[error("cannot send {signal} to {target}: {source}")]
    Signal {
        /// `pid N` or `process group N`.
        target: String,
        /// The signal.
        signal: Signal,
        /// The cause.
        source: Errno,
    },
}

/// What to start: one process of a run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChildSpec {
    /// Which kind of process.
    pub role: Role,
    /// The agent index for [`Role::Agent`], else 0.
    pub index: u32,
    /// The executable.
    pub program: PathBuf,
    /// Its arguments (without the program name).
    pub args: Vec<OsString>,
    /// Where stdout and stderr are appended; parent directories are created.
    pub log_file: PathBuf,
    /// Extra environment variables, on top of the supervisor's environment.
    pub env: Vec<(OsString, OsString)>,
}

impl ChildSpec {
    /// A spec without arguments or extra environment.
    pub fn new(
        role: Role,
        index: u32,
        program: impl Into<PathBuf>,
        log_file: impl Into<PathBuf>,
    ) -> Self {
        Self {
            role,
            index,
            program: program.into(),
            args: Vec::new(),
            log_file: log_file.into(),
            env: Vec::new(),
        }
    }

    /// Appends one argument.
    pub fn arg(mut self, arg: impl Into<OsString>) -> Self {
        self.args.push(arg.into());
        self
    }

    /// Adds one environment variable.
    pub fn env(mut self, key: impl Into<OsString>, value: impl Into<OsString>) -> Self {
        self.env.push((key.into(), value.into()));
        self
    }

    /// The iceoryx2 node name the process uses: `sim`, `coordinator` or `agent-<index>`.
    pub fn node_name(&self) -> String {
        self.role.node_name(self.index)
    }
}

/// How a child ended, as `waitpid` reported it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ExitInfo {
    /// It called `exit` with this code.
    Exited(i32),
    /// A signal killed it.
    Signaled(Signal),
    /// Its status is unknown: someone else reaped it (`ECHILD`).
    Lost,
}

impl ExitInfo {
    /// Whether the exit counts as a failure for restart policies: a non-zero code, a fatal
    /// signal, or an unknown status.
    pub fn is_failure(&self) -> bool {
        !matches!(self, ExitInfo::Exited(0))
    }

    /// The exit code, if it exited normally.
    pub fn code(&self) -> Option<i32> {
        match self {
            ExitInfo::Exited(c) => Some(*c),
            _ => None,
        }
    }

    /// The signal that killed it, if any.
    pub fn signal(&self) -> Option<Signal> {
        match self {
            ExitInfo::Signaled(s) => Some(*s),
            _ => None,
        }
    }
}

impl core::fmt::Display for ExitInfo {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ExitInfo::Exited(c) => write!(f, "exit code {c}"),
            ExitInfo::Signaled(s) => write!(f, "killed by {s}"),
            ExitInfo::Lost => f.write_str("exit status lost"),
        }
    }
}

/// A started child process. Its methods take `&self`, so a waiter attachment on
/// [`Child::exit_fd`] can stay attached while the child is signalled or reaped.
#[derive(Debug)]
pub struct Child {
    spec: ChildSpec,
    pid: Pid,
    exit_fd: ExitFd,
    started: Instant,
    exit: Cell<Option<ExitInfo>>,
}

impl Child {
    /// Starts `spec` in its own process group, stdin from `/dev/null`, stdout and stderr
    /// appended to `spec.log_file`, watched by a pidfd (or the waiter-thread fallback).
    pub fn spawn(spec: &ChildSpec) -> Result<Child, ChildError> {
        Self::spawn_with(spec, WatchMode::Auto)
    }

    /// [`Child::spawn`] with an explicit exit-watch mechanism.
    pub fn spawn_with(spec: &ChildSpec, mode: WatchMode) -> Result<Child, ChildError> {
        let log_err = |source| ChildError::LogFile {
            path: spec.log_file.clone(),
            source,
        };
        if let Some(dir) = spec.log_file.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(log_err)?;
        }
        let out = OpenOptions::new()
            .create(true)
            .append(true)
            .open(&spec.log_file)
            .map_err(log_err)?;
        let err = out.try_clone().map_err(log_err)?;
        let mut command = Command::new(&spec.program);
        let parent = std::process::id() as libc::pid_t;
        // SAFETY: the closure runs in the forked child before exec and only calls prctl(2) and
        // getppid(2), which are async-signal-safe, and builds an io::Error from a raw errno
        // (no allocation); it touches no memory shared with the parent.
        unsafe {
            command.pre_exec(move || {
                // No orphans: if the supervisor dies (even by SIGKILL) the child is killed.
                // The death signal follows the spawning *thread*; the supervisor spawns every
                // child from its main thread, which lives as long as the supervisor.
                if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                // A supervisor that died between the fork and the prctl sent no signal: the
                // child has been re-parented already and must not start.
                if libc::getppid() != parent {
                    return Err(std::io::Error::from_raw_os_error(libc::ESRCH));
                }
                Ok(())
            });
        }
        let std_child = command
            .args(&spec.args)
            .envs(spec.env.iter().map(|(k, v)| (k, v)))
            .process_group(0)
            .stdin(Stdio::null())
            .stdout(Stdio::from(out))
            .stderr(Stdio::from(err))
            .spawn()
            .map_err(|source| ChildError::Spawn {
                program: spec.program.clone(),
                source,
            })?;
        let raw_pid = std_child.id();
        // From here on the pid is reaped by us with waitpid, never through `std_child`
        // (dropping a std Child neither waits nor kills).
        drop(std_child);
        let pid = Pid::from_raw(raw_pid as libc::pid_t);
        match ExitFd::watch(raw_pid, mode) {
            Ok(exit_fd) => Ok(Child {
                spec: spec.clone(),
                pid,
                exit_fd,
                started: Instant::now(),
                exit: Cell::new(None),
            }),
            Err(source) => {
                let _ = killpg(pid, Signal::SIGKILL);
                let _ = reap_blocking(pid);
                Err(ChildError::Watch {
                    pid: raw_pid,
                    source,
                })
            }
        }
    }

    /// The process id (also its process-group id).
    pub fn pid(&self) -> u32 {
        self.pid.as_raw() as u32
    }

    /// What was started.
    pub fn spec(&self) -> &ChildSpec {
        &self.spec
    }

    /// When it was started.
    pub fn started(&self) -> Instant {
        self.started
    }

    /// The descriptor that becomes readable when the child exits; attach it to a `Waiter`
    /// with `attach_notification`, and drop the guard once the exit is handled (it stays
    /// readable).
    pub fn exit_fd(&self) -> &ExitFd {
        &self.exit_fd
    }

    /// Wakes `waiter` when the child exits (its exit descriptor becomes readable). Keep the
    /// attachment while the exit is unhandled and drop it after: the descriptor stays
    /// readable, and a waiter still watching it would never sleep again.
    pub fn watch<'w>(&self, waiter: &'w Waiter) -> Result<Attachment<'w, '_>, TransportError> {
        waiter.attach_fd(&self.exit_fd)
    }

    /// The exit, if [`Child::try_reap`] has reaped the child.
    pub fn exit(&self) -> Option<ExitInfo> {
        self.exit.get()
    }

    /// Reaps the child if it has exited (`waitpid` with `WNOHANG`), remembering the result;
    /// `None` while it runs. Before reaping, anything the child left running in its process
    /// group is killed with SIGKILL (the still unreaped leader keeps the group id from being
    /// reused), so a restart never runs next to a previous incarnation's helpers.
    pub fn try_reap(&self) -> Option<ExitInfo> {
        if let Some(e) = self.exit.get() {
            return Some(e);
        }
        let peek = loop {
            match waitid(
                Id::Pid(self.pid),
                WaitPidFlag::WEXITED | WaitPidFlag::WNOHANG | WaitPidFlag::WNOWAIT,
            ) {
                Err(Errno::EINTR) => continue,
                other => break other,
            }
        };
        match peek {
            Ok(WaitStatus::StillAlive) => return None,
            Ok(_) => {}
            Err(Errno::ECHILD) => {
                tracing::warn!(
                    pid = self.pid(),
                    "child was reaped elsewhere; exit status lost"
                );
                self.exit.set(Some(ExitInfo::Lost));
                return Some(ExitInfo::Lost);
            }
            Err(e) => {
                tracing::warn!(pid = self.pid(), error = %e, "waitid failed");
                return None;
            }
        }
        let _ = killpg(self.pid, Signal::SIGKILL);
        let info = reap_blocking(self.pid);
        self.exit.set(Some(info));
        Some(info)
    }

    /// Blocks until the child exits or `timeout` passes (`None`: no limit), then reaps it.
    pub fn wait(&self, timeout: Option<Duration>) -> Option<ExitInfo> {
        if let Some(e) = self.try_reap() {
            return Some(e);
        }
        if self.exit_fd.wait(timeout) {
            self.try_reap()
        } else {
            None
        }
    }

    /// Reaps with a blocking `waitpid`; only for a child that was sent SIGKILL (or has exited).
    pub(crate) fn reap_blocking(&self) -> ExitInfo {
        if let Some(e) = self.exit.get() {
            return e;
        }
        let info = reap_blocking(self.pid);
        self.exit.set(Some(info));
        info
    }

    /// Blocks until the child is stopped (by SIGSTOP) or has exited, and says which: `true`
    /// stopped. A stop cannot be refused, so this returns as soon as the kernel has stopped
    /// every thread of the child (a thread in an uninterruptible sleep, an `fsync`, say,
    /// finishes that first). An exit is left unreaped for [`Child::try_reap`]; the stop is
    /// consumed, so that a later freeze waits for its own.
    pub fn wait_stopped(&self) -> bool {
        if self.exit.get().is_some() {
            return false;
        }
        let seen = loop {
            match waitid(
                Id::Pid(self.pid),
                WaitPidFlag::WSTOPPED | WaitPidFlag::WEXITED | WaitPidFlag::WNOWAIT,
            ) {
                Err(Errno::EINTR) => continue,
                other => break other,
            }
        };
        match seen {
            Ok(WaitStatus::Stopped(..)) => {
                let _ = waitid(
                    Id::Pid(self.pid),
                    WaitPidFlag::WSTOPPED | WaitPidFlag::WNOHANG,
                );
                true
            }
            _ => false,
        }
    }

    /// Sends `signal` to the child process only. Does nothing once the child is reaped.
    pub fn signal(&self, signal: Signal) -> Result<(), ChildError> {
        if self.exit.get().is_some() {
            return Ok(());
        }
        match kill(self.pid, signal) {
            Ok(()) | Err(Errno::ESRCH) => Ok(()),
            Err(source) => Err(ChildError::Signal {
                target: format!("pid {}", self.pid),
                signal,
                source,
            }),
        }
    }

    /// Sends `signal` to the child's whole process group (`killpg`): the child and
    /// everything it started. Does nothing once the child is reaped.
    pub fn signal_group(&self, signal: Signal) -> Result<(), ChildError> {
        if self.exit.get().is_some() {
            return Ok(());
        }
        match killpg(self.pid, signal) {
            Ok(()) | Err(Errno::ESRCH) => Ok(()),
            Err(source) => Err(ChildError::Signal {
                target: format!("process group {}", self.pid),
                signal,
                source,
            }),
        }
    }
}

impl Drop for Child {
    fn drop(&mut self) {
        if self.exit.get().is_none() {
            tracing::warn!(
                pid = self.pid(),
                node = self.spec.node_name(),
                "child dropped while still running: killing its process group"
            );
            let _ = killpg(self.pid, Signal::SIGKILL);
            let _ = reap_blocking(self.pid);
        }
    }
}

/// `waitpid` without `WNOHANG`, retried on `EINTR`. Only called when the child has exited or
/// was just sent SIGKILL, so it returns promptly.
fn reap_blocking(pid: Pid) -> ExitInfo {
    loop {
        match waitpid(pid, None) {
            Ok(WaitStatus::Exited(_, code)) => return ExitInfo::Exited(code),
            Ok(WaitStatus::Signaled(_, sig, _)) => return ExitInfo::Signaled(sig),
            Ok(_) | Err(Errno::EINTR) => continue,
            Err(_) => return ExitInfo::Lost,
        }
    }
}
