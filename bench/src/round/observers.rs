//! The run's observers beside a measured round (`--observers`): what `hnav run --ros2` and
//! `hnav run --foxglove` add to a run, so that the round can be measured with and without
//! them in one run of the benchmark.
//!
//! - `ros2`: `hnav-ros2` as `hnav run --ros2` starts it (a process beside the run, reading
//!   every topic it reads and publishing each commit on `/hnav/decisions` at once, the state
//!   at 20 Hz), being its own Zenoh router on a free port: the ROS 2 side's work up to the
//!   network, without a remote subscriber (whose cost is the network's and the other
//!   machine's).
//! - `foxglove`: the live Foxglove view as `hnav run --foxglove` runs it (a thread of the
//!   supervisor's process, here the benchmark's, which plays the agents), listening on a
//!   free port, with no client connected.
//!
//! The round benchmark's run has no sim, so neither sees ground truth; both see every commit,
//! which is the work they add per round.

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context, Result};

use hnav_operator::supervisor::registry::RunRegistry;
use hnav_operator::viewer::live::LiveView;
use hnav_operator::viewer::Server;
use hnav_runtime::launch::ProcessArgs;
use hnav_runtime::transport::RunId;

/// How long `hnav-ros2` may take to say its node is up.
const UP_TIMEOUT: Duration = Duration::from_secs(20);

/// Which observers a point runs with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Observers {
    /// `hnav-ros2` beside the run.
    pub ros2: bool,
    /// The live Foxglove view.
    pub foxglove: bool,
}

impl Observers {
    /// `none`, `ros2`, `foxglove` or `ros2+foxglove`.
    pub fn name(self) -> &'static str {
        match (self.ros2, self.foxglove) {
            (false, false) => "none",
            (true, false) => "ros2",
            (false, true) => "foxglove",
            (true, true) => "ros2+foxglove",
        }
    }

    /// Parses [`Observers::name`]'s forms.
    pub fn parse(s: &str) -> Result<Observers, String> {
        let mut o = Observers::default();
        if s == "none" {
            return Ok(o);
        }
        for part in s.split('+') {
            match part {
                "ros2" => o.ros2 = true,
                "foxglove" => o.foxglove = true,
                other => {
                    return Err(format!(
                        "unknown observer {other:?}: expected none, ros2, foxglove or ros2+foxglove"
                    ))
                }
            }
        }
        Ok(o)
    }
}

/// The observers of one measured point, running.
pub struct Running {
    ros2: Option<Child>,
    view: Option<LiveView>,
    /// The registry the view finds the run in, removed with it.
    registry: Option<tempfile::TempDir>,
}

impl Running {
    /// Starts `which` for run `run` of `args` (its files in `dir`), `hnav-ros2` from
    /// `bin_dir`; returns once each is up.
    pub fn start(
        which: Observers,
        run: &RunId,
        args: &ProcessArgs,
        dir: &Path,
        bin_dir: &Path,
    ) -> Result<Running> {
        let mut running = Running {
            ros2: None,
            view: None,
            registry: None,
        };
        if which.ros2 {
            let port = free_port()?;
            let log = dir.join("ros2.log");
            let out =
                std::fs::File::create(&log).with_context(|| format!("create {}", log.display()))?;
            let child = Command::new(bin_dir.join("hnav-ros2"))
                .args(args.to_args())
                .arg("--listen")
                .arg(format!("tcp/127.0.0.1:{port}"))
                .stdin(Stdio::null())
                .stdout(out.try_clone()?)
                .stderr(out)
                .spawn()
                .context("start hnav-ros2")?;
            running.ros2 = Some(child);
            wait_for(&log, "ros2 node up", UP_TIMEOUT)?;
        }
        if which.foxglove {
            let tmp = tempfile::tempdir().context("a run registry for the view")?;
            let registry = RunRegistry::at(tmp.path());
            let mut record = registry.new_record(run, dir);
            record.set_process_args(args);
            record
                .write()
                .map_err(|e| anyhow!("register the run: {e}"))?;
            let server = Server::bind(([127, 0, 0, 1], 0).into())
                .map_err(|e| anyhow!("the Foxglove view: {e}"))?;
            running.view = Some(
                LiveView::start_in(registry, server, run.as_str().to_string())
                    .context("start the Foxglove view")?,
            );
            running.registry = Some(tmp);
        }
        Ok(running)
    }

    /// Stops them (`hnav-ros2` by SIGTERM, then reaped).
    pub fn stop(mut self) {
        self.end();
    }

    fn end(&mut self) {
        if let Some(v) = self.view.take() {
            v.finish();
        }
        if let Some(mut c) = self.ros2.take() {
            let pid = nix::unistd::Pid::from_raw(c.id() as i32);
            let _ = nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM);
            let deadline = Instant::now() + Duration::from_secs(5);
            while matches!(c.try_wait(), Ok(None)) && Instant::now() < deadline {
                std::thread::sleep(Duration::from_millis(10));
            }
            let _ = c.kill();
            let _ = c.wait();
        }
        self.registry.take();
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        self.end();
    }
}

/// A TCP port nothing listens on now.
fn free_port() -> Result<u16> {
    let l = std::net::TcpListener::bind("127.0.0.1:0").context("a free port")?;
    Ok(l.local_addr()?.port())
}

/// Waits up to `timeout` for `file` to hold `line`, reading it again every 20 ms.
fn wait_for(file: &Path, line: &str, timeout: Duration) -> Result<()> {
    let deadline = Instant::now() + timeout;
    loop {
        let text = std::fs::read_to_string(file).unwrap_or_default();
        if text.contains(line) {
            return Ok(());
        }
        if Instant::now() >= deadline {
            bail!(
                "{} did not say {line:?} within {timeout:?}:\n{text}",
                file.display()
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back() {
        for o in [
            Observers::default(),
            Observers {
                ros2: true,
                foxglove: false,
            },
            Observers {
                ros2: false,
                foxglove: true,
            },
            Observers {
                ros2: true,
                foxglove: true,
            },
        ] {
            assert_eq!(Observers::parse(o.name()), Ok(o));
        }
        assert!(Observers::parse("rviz").is_err());
    }
}
