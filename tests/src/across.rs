//! One run across hosts in network namespaces (`tests/multi_host.rs`): each host runs
//! `ip netns exec NS hnav run SCENARIO --host NAME` with its own iceoryx2 domain
//! (`HNAV_DOMAIN`) and run registry, so that only the hosts' bridges (Zenoh over TCP) link
//! them; the run's shared memory in every host's domain is purged at the end, also when the
//! test failed.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use hnav_runtime::transport::{purge_run, RunId};

use crate::netns::Net;
use crate::swarm::{log_tails, workspace_bin};
use crate::{Peer, TestRun};

/// Generous: debug builds of up to 20 processes and four bridges on a 2-core machine.
pub const RUN_TIMEOUT: Duration = Duration::from_secs(600);

/// The tests of a binary that run hosts run one at a time: each starts about 20 processes
/// and three or four bridges, and side by side on 2 cores they starved each other (a verdict
/// about a cut host must not depend on what the binary's other tests are doing).
pub fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static ONE: std::sync::Mutex<()> = std::sync::Mutex::new(());
    // A test that failed holding it poisons it; the next one still runs.
    ONE.lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Whether CI requires the namespace tests to run (`HNAV_REQUIRE_NETNS=1`, set by `.ci/run`
/// where its probe made a namespace and nftables is installed): a skip is then a failure.
pub fn required() -> bool {
    std::env::var_os("HNAV_REQUIRE_NETNS").is_some_and(|v| v == "1")
}

/// `n` hosts' namespaces for test `tag`, or `None` (said on stderr) where they cannot be
/// made.
pub fn net_or_skip(tag: &str, n: usize) -> Option<Net> {
    match Net::create(tag, n) {
        Ok(net) => Some(net),
        Err(e) if required() => {
            panic!("HNAV_REQUIRE_NETNS=1 but no network namespace could be made: {e}")
        }
        Err(e) => {
            eprintln!("skipped: no network namespaces here ({e})");
            None
        }
    }
}

/// Removes what the run left in each host's iceoryx2 domain, after its processes are gone
/// (declared before the [`TestRun`], so dropped after it kills them).
pub struct DomainPurge {
    /// The run.
    pub run: RunId,
    /// The hosts, whose names are their domains.
    pub hosts: Vec<String>,
}

impl Drop for DomainPurge {
    fn drop(&mut self) {
        for h in &self.hosts {
            if let Ok(run) = self.run.clone().in_domain(h) {
                if let Err(e) = purge_run(&run) {
                    eprintln!("cleanup of run {run} in domain {h} failed: {e}");
                }
            }
        }
    }
}

/// One run across hosts: a supervisor per host and its run directory.
pub struct Across {
    /// Each host's `hnav run`, in the placement's order.
    pub supervisors: Vec<Peer>,
    /// Each host's run directory.
    pub dirs: Vec<PathBuf>,
    /// The hosts' names.
    pub hosts: Vec<String>,
}

impl Across {
    /// Starts `hnav run SCENARIO --host H --hosts PLACEMENT` for every host `H` of `hosts`,
    /// host `i` in namespace `net.ns(i)`, its directory `tmp/H`, with `extra` arguments and
    /// `env` on top of each host's domain and registry.
    #[allow(clippy::too_many_arguments)]
    pub fn start(
        run: &mut TestRun,
        net: &Net,
        hosts: &[&str],
        placement: &Path,
        scenario: &Path,
        tmp: &Path,
        extra: &[&str],
        env: &[(&str, &Path)],
    ) -> Across {
        let hnav = workspace_bin("hnav").display().to_string();
        let mut across = Across {
            supervisors: Vec::new(),
            dirs: Vec::new(),
            hosts: hosts.iter().map(|h| h.to_string()).collect(),
        };
        for (i, name) in hosts.iter().enumerate() {
            let dir = tmp.join(name);
            let mut args: Vec<String> = ["netns", "exec", net.ns(i), &hnav, "run"]
                .iter()
                .map(|s| s.to_string())
                .collect();
            args.push(scenario.display().to_string());
            for a in ["--run", run.run.as_str(), "--host", name, "--no-record"] {
                args.push(a.to_string());
            }
            args.extend(["--hosts".into(), placement.display().to_string()]);
            args.extend(["--out".into(), dir.display().to_string()]);
            args.extend(extra.iter().map(|s| s.to_string()));
            let registry = tmp.join(format!("runs-{name}"));
            let domain = PathBuf::from(name);
            let mut all: Vec<(&str, &Path)> =
                vec![("HNAV_DOMAIN", &domain), ("HNAV_RUNS_DIR", &registry)];
            all.extend_from_slice(env);
            let peer = run
                .spawn_exact_env("ip", &args, &all)
                .expect("ip netns exec");
            across.supervisors.push(peer);
            across.dirs.push(dir);
        }
        across
    }

    /// Waits for every supervisor; each must exit 0 (every robot home, no collision).
    pub fn finish(&mut self) {
        let deadline = Instant::now() + RUN_TIMEOUT;
        for (i, p) in self.supervisors.iter_mut().enumerate() {
            let left = deadline.saturating_duration_since(Instant::now());
            let host = &self.hosts[i];
            let status = p.wait_exit(left).unwrap_or_else(|e| panic!("{host}: {e}"));
            let tails: String = self.dirs.iter().map(|d| log_tails(d)).collect();
            assert!(status.success(), "host {host} exited {status}\n{tails}");
        }
        for d in &self.dirs {
            let s = summary(d);
            assert_eq!(s["end"], "all-at-goal", "{}: {s}", d.display());
            assert_eq!(s["collisions"], 0, "{}: {s}", d.display());
        }
    }

    /// The tails of every host's process logs, for a failure's message.
    pub fn tails(&self) -> String {
        self.dirs.iter().map(|d| log_tails(d)).collect()
    }
}

/// A supervisor still running when the test ends (it failed) is asked to stop, so that it
/// stops its children (a SIGKILL would orphan them) before the run's memory is purged.
impl Drop for Across {
    fn drop(&mut self) {
        for p in &mut self.supervisors {
            let running = p.wait_exit(Duration::ZERO).is_err();
            if running && p.signal(nix::sys::signal::Signal::SIGTERM).is_ok() {
                let _ = p.wait_exit(Duration::from_secs(20));
            }
        }
    }
}

/// A run directory's `summary.json`.
pub fn summary(dir: &Path) -> serde_json::Value {
    let p = dir.join("summary.json");
    let text = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    serde_json::from_str(&text).unwrap()
}
