//! `hnav run --ros2` (or a scenario's `[ros2]`): the run's ROS 2 publisher, `hnav-ros2`.
//!
//! With robots outside HNAV (`[sim] kind = "ros2"`), `hnav-ros2 --robots` is the run's sim
//! instead, in the roster (`Slots::with_outside_robots`), and this one is not started.
//!
//! Otherwise it is one more process of the run, beside the roster rather than in it: started once the run's
//! services exist (with the recorder, before the sim) so that it hears the run from its first
//! sample; not waited for, given no hang deadline, not restarted. It only observes, so a
//! failure there (a router that never answers, a crash) is its log's business,
//! `DIR/logs/ros2.log`, and never the run's. It leaves on the supervisor's `Stop`; the
//! supervisor stops it first (SIGTERM, SIGKILL after the grace), so that its last messages
//! carry the run's last state.

use std::fs::OpenOptions;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::transport::DOMAIN_ENV;

/// How `hnav-ros2` joins the ROS 2 graph.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Ros2Options {
    /// The router to join (`--ros2-router`); `None`: the scenario's, else rmw_zenoh's
    /// default.
    pub router: Option<String>,
    /// Be the router on `tcp/127.0.0.1:7447` (none answered there).
    pub start_router: bool,
}

impl Ros2Options {
    /// Its `hnav-ros2` arguments: `--router ENDPOINT`, `--start-router`, or none.
    pub fn args(&self) -> Vec<String> {
        let mut a = Vec::new();
        if let Some(r) = &self.router {
            a.extend(["--router".to_string(), r.clone()]);
        }
        if self.start_router {
            a.push("--start-router".into());
        }
        a
    }
}

/// The running `hnav-ros2`.
pub struct Ros2Process {
    child: Child,
    log: PathBuf,
}

impl Ros2Process {
    /// Starts `bin_dir/hnav-ros2` for the run of `args`, its output appended to
    /// `dir/logs/ros2.log`.
    pub fn start(
        opts: &Ros2Options,
        args: &ProcessArgs,
        bin_dir: &Path,
        dir: &Path,
        domain: Option<&str>,
    ) -> std::io::Result<Ros2Process> {
        let log = dir.join("logs").join("ros2.log");
        if let Some(parent) = log.parent() {
            std::fs::create_dir_all(parent)?;
        }
        let out = OpenOptions::new().create(true).append(true).open(&log)?;
        let mut cmd = Command::new(bin_dir.join("hnav-ros2"));
        cmd.args(args.to_args()).args(opts.args());
        if let Some(d) = domain {
            cmd.env(DOMAIN_ENV, d);
        }
        // Its own process group, as every process of the run: a Ctrl-C at the terminal
        // reaches the supervisor only, which then stops it.
        cmd.stdin(Stdio::null())
            .stdout(out.try_clone()?)
            .stderr(out)
            .process_group(0);
        let child = cmd.spawn()?;
        Ok(Ros2Process { child, log })
    }

    /// Its log file.
    pub fn log(&self) -> &Path {
        &self.log
    }

    /// Stops it: SIGTERM, then SIGKILL if it is still there after `grace`; reaped either way.
    pub fn stop(mut self, grace: Duration) {
        let pid = nix::unistd::Pid::from_raw(self.child.id() as i32);
        if matches!(self.child.try_wait(), Ok(None)) {
            let _ = nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM);
        }
        let deadline = Instant::now() + grace;
        while Instant::now() < deadline {
            match self.child.try_wait() {
                Ok(Some(status)) => {
                    tracing::debug!(%status, "hnav-ros2 stopped");
                    return;
                }
                Ok(None) => std::thread::sleep(Duration::from_millis(10)),
                Err(_) => break,
            }
        }
        tracing::warn!("hnav-ros2 did not stop within {grace:?}: killed");
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
