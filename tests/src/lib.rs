//! # hnav-tests
//!
//! Multi-process integration and fault-injection tests of HNAV, and what they share:
//!
//! - [`TestRun`]: a unique run id per test, child processes started with bounded waits on
//!   their output and exit, and clean-up of the run's shared memory in `Drop`, so a failing
//!   test leaves nothing behind in `/dev/shm`;
//! - the `hnav-test-peer` binary (`src/bin/hnav-test-peer.rs`): small publisher and
//!   subscriber roles the tests run as separate processes;
//! - the `hnav-rogue` binary (`src/bin/hnav-rogue.rs`) and [`rogue`], the hostile candidates
//!   it forges (`tests/rogue.rs`);
//! - [`pattern`]: the deterministic payloads both sides of a test agree on;
//! - [`lost_wakeup`]: both halves of the lost-wake-up reproducer (`tests/lost_wakeup.rs`);
//! - [`tmux`]: a terminal of a test's own for full-screen programs (`hnav top`, playback);
//! - [`netns`]: hosts on one machine (network namespaces, a switch, loss, partitions) for the
//!   multi-host tests (`tests/multi_host.rs`), and [`across`]: one run across those hosts;
//! - [`docs`]: what `tests/docs.rs` checks in the markdown (commands, links, paths).
//!
//! **Must not depend on**: `hnav-bench` or `hnav-fuzz` outside its test binaries (the chaos
//! campaign is a dev-dependency): the helpers here are what the tests share, not what they
//! measure.
//!
//! Modules, highest first (a module uses only those below it in this table; imports never run
//! back up):
//!
//! | module | what it holds |
//! |---|---|
//! | [`house`] | the workspace's import rules checked over its sources: rings of files, imports back up a `lib.rs` table |
//! | [`docs`] | what `tests/docs.rs` checks in the markdown: commands against `--help`, links, paths |
//! | [`across`] | one run across hosts in network namespaces: a supervisor per host, their domains purged |
//! | [`python`] | the Python of the client tests, or why they skip |
//! | [`swarm`] | one `hnav run` of a test: its scenario, its run directory, its log's digest |
//! | [`rogue`] | the hostile candidates `hnav-rogue` forges |
//! | [`lost_wakeup`] | both halves of the lost-wake-up reproducer |
//! | [`netns`] | hosts on one machine: network namespaces, a switch, loss, partitions |
//! | [`tmux`] | a terminal of a test's own for full-screen programs |
//! | [`pattern`] | the deterministic payloads both sides of a test agree on |
//!
//! Tests that SIGKILL processes live in their own test binaries (`tests/*_kill.rs`).
//! Tests that send other signals do too (`tests/waiter_signals.rs`).

pub mod across;
pub mod docs;
pub mod house;
pub mod lost_wakeup;
pub mod netns;
pub mod pattern;
pub mod python;
pub mod rogue;
pub mod swarm;
pub mod tmux;

use std::io::{BufRead, BufReader};
use std::process::{Command, ExitStatus, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use hnav_runtime::transport::{purge_run, RunId};
use nix::sys::signal::{kill, Signal};
use nix::unistd::Pid;

/// A child process of a test, with its stdout lines and exit status delivered on channels so
/// that every wait on it is bounded.
pub struct Peer {
    /// OS process id.
    pub pid: u32,
    lines: mpsc::Receiver<String>,
    exit: mpsc::Receiver<ExitStatus>,
    exited: Option<ExitStatus>,
}

impl Peer {
    /// Waits up to `timeout` for the next stdout line.
    pub fn next_line(&mut self, timeout: Duration) -> Result<String, String> {
        self.lines
            .recv_timeout(timeout)
            .map_err(|e| format!("no output from pid {} within {timeout:?}: {e}", self.pid))
    }

    /// Waits up to `timeout` for a stdout line starting with `prefix`, skipping others.
    pub fn wait_for_line(&mut self, prefix: &str, timeout: Duration) -> Result<String, String> {
        let deadline = std::time::Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            let line = self.next_line(left)?;
            if line.starts_with(prefix) {
                return Ok(line);
            }
        }
    }

    /// Waits up to `timeout` for the process to exit.
    pub fn wait_exit(&mut self, timeout: Duration) -> Result<ExitStatus, String> {
        if let Some(s) = self.exited {
            return Ok(s);
        }
        let status = self
            .exit
            .recv_timeout(timeout)
            .map_err(|e| format!("pid {} did not exit within {timeout:?}: {e}", self.pid))?;
        self.exited = Some(status);
        Ok(status)
    }

    /// Sends `signal` to the process.
    pub fn signal(&self, signal: Signal) -> Result<(), String> {
        kill(Pid::from_raw(self.pid as i32), signal).map_err(|e| e.to_string())
    }
}

/// One test's run: a unique [`RunId`] and the processes started for it.
///
/// Dropping it kills the processes still running, reaps them and purges the run's
/// shared-memory resources, also when the test failed.
pub struct TestRun {
    /// The run id (unique per test and process).
    pub run: RunId,
    peers: Vec<(u32, mpsc::Receiver<ExitStatus>)>,
}

impl TestRun {
    /// A run with a fresh id tagged `tag`.
    pub fn new(tag: &str) -> Self {
        Self {
            run: RunId::unique(tag),
            peers: Vec::new(),
        }
    }

    /// Starts `program` with `args` (the run id is passed as `--run <id>` first).
    pub fn spawn(&mut self, program: &str, args: &[&str]) -> Result<Peer, String> {
        let mut all = vec!["--run", self.run.as_str()];
        all.extend_from_slice(args);
        let all: Vec<String> = all.iter().map(|s| s.to_string()).collect();
        self.spawn_exact(program, &all)
    }

    /// Starts `program` with exactly `args` (the caller places the run id, e.g. after a
    /// subcommand: `hnav run --run <id> ...`).
    pub fn spawn_exact(&mut self, program: &str, args: &[String]) -> Result<Peer, String> {
        self.spawn_exact_env(program, args, &[])
    }

    /// [`TestRun::spawn_exact`] with `env` added to the child's environment only. Tests of
    /// one binary run in parallel threads of one process, so a variable that differs between
    /// them must never go through `std::env::set_var`: another test's spawn would inherit it.
    pub fn spawn_exact_env(
        &mut self,
        program: &str,
        args: &[String],
        env: &[(&str, &std::path::Path)],
    ) -> Result<Peer, String> {
        let mut child = Command::new(program)
            .args(args)
            .envs(env.iter().map(|(k, v)| (*k, *v)))
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .map_err(|e| format!("cannot start {program}: {e}"))?;
        let pid = child.id();
        let stdout = child.stdout.take().ok_or("no stdout")?;
        let (line_tx, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if line_tx.send(line).is_err() {
                    break;
                }
            }
        });
        let (exit_tx, exit) = mpsc::channel();
        let (guard_tx, guard_rx) = mpsc::channel();
        std::thread::spawn(move || {
            if let Ok(status) = child.wait() {
                let _ = exit_tx.send(status);
                let _ = guard_tx.send(status);
            }
        });
        self.peers.push((pid, guard_rx));
        Ok(Peer {
            pid,
            lines,
            exit,
            exited: None,
        })
    }
}

impl Drop for TestRun {
    fn drop(&mut self) {
        for (pid, exit) in &self.peers {
            if exit.try_recv().is_err() {
                let _ = kill(Pid::from_raw(*pid as i32), Signal::SIGKILL);
                let _ = exit.recv_timeout(Duration::from_secs(10));
            }
        }
        if let Err(e) = purge_run(&self.run) {
            eprintln!("cleanup of run {} failed: {e}", self.run);
        }
    }
}

/// A loopback TCP port nothing listens on now (the kernel's choice), so that tests running
/// in parallel do not collide; whoever binds it next should do so soon.
pub fn free_port() -> u16 {
    let l = std::net::TcpListener::bind("127.0.0.1:0").expect("a free loopback port");
    l.local_addr().expect("a bound listener's address").port()
}
