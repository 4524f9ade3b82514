//! Running whole swarms from tests: `hnav run` as a child process with a test's own run id,
//! a run directory in a temporary directory, and the registry of live runs kept out of the
//! machine's shared one.

use std::path::{Path, PathBuf};
use std::process::ExitStatus;
use std::time::Duration;

use crate::{Peer, TestRun};

/// A workspace binary (`hnav`, `hnav-agent`, ...) next to the test executable's directory:
/// cargo puts test executables in `target/<profile>/deps` and binaries in `target/<profile>`.
pub fn workspace_bin(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("the test executable has a path");
    let profile_dir = exe
        .parent()
        .and_then(Path::parent)
        .expect("test executables live in target/<profile>/deps");
    profile_dir.join(name)
}

/// The repository root (for scenarios and maps).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the tests crate is inside the workspace")
        .to_path_buf()
}

/// One `hnav run` of a test.
pub struct SwarmRun {
    /// The supervisor process.
    pub peer: Peer,
    /// The run directory.
    pub dir: PathBuf,
}

impl SwarmRun {
    /// Starts `hnav run SCENARIO --run <id> --out DIR EXTRA...` under `run`, with the run
    /// registry in `registry`.
    pub fn start(
        run: &mut TestRun,
        scenario: &Path,
        dir: &Path,
        registry: &Path,
        extra: &[&str],
    ) -> Result<SwarmRun, String> {
        let mut args: Vec<String> = vec![
            "run".into(),
            scenario.display().to_string(),
            "--run".into(),
            run.run.as_str().to_string(),
            "--out".into(),
            dir.display().to_string(),
        ];
        args.extend(extra.iter().map(|s| s.to_string()));
        let hnav = workspace_bin("hnav");
        // Only the child gets the registry: two tests of one binary with their own registries
        // raced on a process-wide `set_var`, and a run registered in the other test's one.
        let peer = run.spawn_exact_env(
            &hnav.display().to_string(),
            &args,
            &[("HNAV_RUNS_DIR", registry)],
        )?;
        Ok(SwarmRun {
            peer,
            dir: dir.to_path_buf(),
        })
    }

    /// Waits up to `timeout` for the supervisor to exit; on failure the error carries the
    /// tails of the processes' logs.
    pub fn finish(&mut self, timeout: Duration) -> Result<ExitStatus, String> {
        self.peer
            .wait_exit(timeout)
            .map_err(|e| format!("{e}\n{}", self.log_tails()))
    }

    /// The summary the supervisor wrote.
    pub fn summary(&self) -> Result<serde_json::Value, String> {
        let p = self.dir.join("summary.json");
        let text = std::fs::read_to_string(&p)
            .map_err(|e| format!("{}: {e}\n{}", p.display(), self.log_tails()))?;
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", p.display()))
    }

    /// The last lines of every process log of the run, for failure messages.
    pub fn log_tails(&self) -> String {
        log_tails(&self.dir)
    }
}

/// The last lines of every process log in run directory `dir`, for failure messages.
pub fn log_tails(dir: &Path) -> String {
    let mut out = String::new();
    let Ok(entries) = std::fs::read_dir(dir.join("logs")) else {
        return out;
    };
    let mut paths: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
    paths.sort();
    for p in paths {
        let text = std::fs::read_to_string(&p).unwrap_or_default();
        let lines: Vec<&str> = text.lines().collect();
        let tail = &lines[lines.len().saturating_sub(8)..];
        if !tail.is_empty() {
            out += &format!("--- {}\n{}\n", p.display(), tail.join("\n"));
        }
    }
    out
}

/// A digest of consensus-log records, for notes and test output: SHA-256 over their
/// payload encodings, in hex.
pub fn records_digest(records: &[hnav_runtime::consensus_log::Record]) -> String {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    let mut buf = Vec::new();
    for r in records {
        buf.clear();
        hnav_runtime::consensus_log::encode_record(r, &mut buf)
            .expect("a record read from a log encodes");
        h.update(&buf);
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// Runs `hnav log verify DIR` and returns whether it exited 0, with its output.
pub fn verify_log(dir: &Path) -> (bool, String) {
    match std::process::Command::new(workspace_bin("hnav"))
        .args(["log", "verify"])
        .arg(dir)
        .output()
    {
        Ok(o) => (
            o.status.success(),
            format!(
                "{}{}",
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            ),
        ),
        Err(e) => (false, e.to_string()),
    }
}

/// Runs `scenario` in lockstep into `dir` and checks the end a swarm test expects of it:
/// exit 0, `all-at-goal`, no collision, `agents` robots all at their goals, a log that
/// verifies. Returns the summary and the log segment's bytes, which two lockstep runs of one
/// scenario must write identically. Panics (the test fails) with the processes' log tails.
pub fn lockstep_all_home(
    tag: &str,
    scenario: &Path,
    dir: &Path,
    registry: &Path,
    agents: usize,
) -> (serde_json::Value, Vec<u8>) {
    const RUN_TIMEOUT: Duration = Duration::from_secs(300);
    let mut run = TestRun::new(tag);
    let mut swarm = SwarmRun::start(&mut run, scenario, dir, registry, &["--mode", "lockstep"])
        .expect("hnav run starts");
    let status = swarm.finish(RUN_TIMEOUT).expect("hnav run ends");
    assert!(status.success(), "{status}\n{}", swarm.log_tails());
    let s = swarm.summary().unwrap();
    assert_eq!(s["end"], "all-at-goal", "{s}\n{}", swarm.log_tails());
    assert_eq!(s["collisions"], 0, "{s}");
    let robots = s["agents"].as_array().unwrap();
    assert_eq!(robots.len(), agents, "{s}");
    assert!(robots.iter().all(|a| a["reached_goal"] == true), "{s}");
    let (ok, report) = verify_log(&dir.join("log"));
    assert!(ok, "log does not verify:\n{report}");
    let log = std::fs::read(dir.join("log/seg-00000000.hlog")).unwrap();
    (s, log)
}

/// A scenario of `agents` robots on the MovingAI map `map` (absolute path), each with a
/// seeded random start and a goal whose octile shortest path (no corner cutting) is
/// `min_len..=max_len` cells long, all starts and goals distinct, at `speed` cells/s. Written
/// to `dir/scenario.toml`; returns its path.
pub fn generated_scenario(
    dir: &Path,
    map: &Path,
    agents: usize,
    seed: u64,
    (min_len, max_len): (f64, f64),
    speed: f64,
) -> PathBuf {
    use hnav_runtime::grid::movingai::read_map_file;
    use hnav_runtime::grid::shortest::octile_shortest_path_len;
    use hnav_runtime::grid::{Cell, CornerCutting};
    use hnav_runtime::hash::SplitMix64;

    let grid = read_map_file(map).expect("a readable map");
    let free: Vec<Cell> = grid.passable_cells().collect();
    let mut rng = SplitMix64::new(seed);
    let mut pick = || free[(rng.next_u64() % free.len() as u64) as usize];
    let mut used = std::collections::HashSet::new();
    let mut text = format!(
        "name = \"generated-{agents}\"\n\n[map]\nfile = {:?}\ncorner_cutting = false\n\n[sim]\nseed = {seed}\n\n[coordinator]\nrules = \"dissertation\"\ntime_limit_s = 300\n",
        map.display().to_string()
    );
    let mut n = 0;
    while n < agents {
        let (s, g) = (pick(), pick());
        if used.contains(&s) || used.contains(&g) || s == g {
            continue;
        }
        match octile_shortest_path_len(&grid, s, g, CornerCutting::Forbidden) {
            Some(len) if (min_len..=max_len).contains(&len) => {}
            _ => continue,
        }
        used.insert(s);
        used.insert(g);
        text += &format!(
            "\n[[agents]]\nstart = [{}, {}]\ngoal = [{}, {}]\nspeed = {speed}\n",
            s.x, s.y, g.x, g.y
        );
        n += 1;
    }
    let path = dir.join("scenario.toml");
    std::fs::write(&path, text).expect("scenario written");
    path
}

/// Runs `hnav ps --json` against the registry in `registry` until `accept` likes a run of the
/// output or `timeout` passes (the supervisor registers its run right after spawning).
pub fn wait_for_ps(
    registry: &Path,
    run_id: &str,
    timeout: Duration,
    accept: impl Fn(&serde_json::Value) -> bool,
) -> Result<serde_json::Value, String> {
    let deadline = std::time::Instant::now() + timeout;
    let mut last = String::new();
    while std::time::Instant::now() < deadline {
        let out = std::process::Command::new(workspace_bin("hnav"))
            .args(["ps", "--json"])
            .env("HNAV_RUNS_DIR", registry)
            .output()
            .map_err(|e| e.to_string())?;
        last = String::from_utf8_lossy(&out.stdout).to_string();
        if let Ok(v) = serde_json::from_str::<serde_json::Value>(&last) {
            let found = v["runs"]
                .as_array()
                .and_then(|runs| runs.iter().find(|r| r["run_id"] == run_id).cloned());
            if let Some(run) = found.filter(|r| accept(r)) {
                return Ok(run);
            }
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    Err(format!(
        "run {run_id} not listed as expected within {timeout:?}; last output:\n{last}"
    ))
}

/// What a short `hnav` command printed, and how it ended.
#[derive(Debug)]
pub struct HnavOutput {
    /// Its exit status.
    pub status: ExitStatus,
    /// Its stdout.
    pub stdout: String,
    /// Its stderr.
    pub stderr: String,
}

/// Runs `hnav ARGS...` with the run registry in `registry` and waits up to `timeout` for it
/// to exit (it is killed after that, and the error says so), collecting its output.
pub fn hnav_output(
    args: &[String],
    registry: &Path,
    timeout: Duration,
) -> Result<HnavOutput, String> {
    use std::io::Read;
    use std::process::{Command, Stdio};
    let mut child = Command::new(workspace_bin("hnav"))
        .args(args)
        .env("HNAV_RUNS_DIR", registry)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start hnav: {e}"))?;
    let pid = child.id();
    let read = |mut r: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut s = String::new();
            let _ = r.read_to_string(&mut s);
            s
        })
    };
    let out = read(Box::new(child.stdout.take().ok_or("no stdout")?));
    let err = read(Box::new(child.stderr.take().ok_or("no stderr")?));
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(child.wait());
    });
    let status = match rx.recv_timeout(timeout) {
        Ok(Ok(status)) => status,
        Ok(Err(e)) => return Err(format!("hnav {args:?}: {e}")),
        Err(_) => {
            let _ = nix::sys::signal::kill(
                nix::unistd::Pid::from_raw(pid as i32),
                nix::sys::signal::Signal::SIGKILL,
            );
            return Err(format!("hnav {args:?} did not exit within {timeout:?}"));
        }
    };
    Ok(HnavOutput {
        status,
        stdout: out.join().unwrap_or_default(),
        stderr: err.join().unwrap_or_default(),
    })
}

/// The lifecycle records of the log in `dir`: (round, role, index, event).
pub fn lifecycle_records(
    dir: &std::path::Path,
) -> Vec<(
    u64,
    Option<hnav_runtime::msg::Role>,
    u32,
    Option<hnav_runtime::msg::LifecycleEvent>,
)> {
    hnav_runtime::consensus_log::read_log(dir)
        .unwrap()
        .records
        .iter()
        .filter_map(|r| match r {
            hnav_runtime::consensus_log::Record::Lifecycle(l) => Some((
                l.round,
                hnav_runtime::msg::Role::from_u8(l.role),
                l.index,
                hnav_runtime::msg::LifecycleEvent::from_u8(l.event),
            )),
            _ => None,
        })
        .collect()
}
