//! A run whose directory's disk fills up ends at once, cleanly: the process that met the full
//! disk exits with [`EXIT_NO_SPACE`](hnav_runtime::launch::EXIT_NO_SPACE) instead of panicking,
//! the supervisor does not restart it, ends the run (exit 3) naming the process and what it
//! was writing, writes no truncated `summary.json`, and the consensus log still verifies.
//!
//! The run directory is a 1 MiB tmpfs, nearly filled before the run starts, mounted in a
//! private mount namespace (`unshare -m`), so nothing outside the test sees it. That needs
//! root: without it the test fails and says so.

use std::os::unix::fs::MetadataExt;
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Command, ExitStatus, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use hnav_runtime::transport::run_shm_files;
use hnav_tests::swarm::{repo_root, verify_log, workspace_bin};
use hnav_tests::TestRun;
use nix::sys::signal::{killpg, Signal};
use nix::unistd::Pid;

/// Mounts the tmpfs, leaves `FREE_KIB` free on it, runs the swarm into it, then copies what
/// the run left there out to the host, where the test reads it.
const SCRIPT: &str = r#"
set -u
mount -t tmpfs -o size=1m,mode=0755 hnav-full-disk "$MNT" || exit 90
dd if=/dev/zero of="$MNT/filler" bs=1k count=$((1024 - FREE_KIB)) 2>/dev/null
"$HNAV" run "$SCENARIO" --run "$RUN_ID" --out "$MNT/run" >"$HOST/stdout" 2>"$HOST/stderr"
echo $? >"$HOST/rc"
cp -a "$MNT/run/." "$HOST/copy/"
"#;

/// Room for the start-up (one checkpoint page per agent, the log's first pages), far too
/// little for the demo's ~120 KB log: the disk fills around round 1 750 of 5 191.
const FREE_KIB: u32 = 64;

/// The whole run takes ~3 s here; before the fix it idled until its 60 s time limit.
const TIMEOUT: Duration = Duration::from_secs(120);

/// Kills the namespace's process group if the test ends before it did.
struct Group(i32, Option<mpsc::Receiver<std::io::Result<ExitStatus>>>);

impl Drop for Group {
    fn drop(&mut self) {
        if let Some(rx) = &self.1 {
            if rx.try_recv().is_err() {
                let _ = killpg(Pid::from_raw(self.0), Signal::SIGKILL);
                let _ = rx.recv_timeout(Duration::from_secs(10));
            }
        }
    }
}

fn require_root_and_unshare() {
    let uid = std::fs::metadata("/proc/self")
        .map(|m| m.uid())
        .unwrap_or(u32::MAX);
    assert_eq!(
        uid, 0,
        "this test needs root: it mounts a small tmpfs in a private mount namespace \
         (`unshare -m` + `mount -t tmpfs`) to fill the run directory's disk"
    );
    let ok = Command::new("unshare")
        .args(["-m", "true"])
        .status()
        .is_ok_and(|s| s.success());
    assert!(
        ok,
        "this test needs `unshare -m` (util-linux) and the right to create a mount namespace"
    );
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_default()
}

#[test]
fn a_full_disk_ends_the_run_at_once_with_a_named_cause_and_a_verifiable_log() {
    require_root_and_unshare();
    let run = TestRun::new("fulldisk");
    let host = tempfile::tempdir().unwrap();
    for sub in ["mnt", "copy", "registry"] {
        std::fs::create_dir(host.path().join(sub)).unwrap();
    }
    let mut child = Command::new("unshare")
        .args(["-m", "sh", "-c", SCRIPT])
        .env("MNT", host.path().join("mnt"))
        .env("HOST", host.path())
        .env("FREE_KIB", FREE_KIB.to_string())
        .env("HNAV", workspace_bin("hnav"))
        .env("SCENARIO", repo_root().join("scenarios/demo.toml"))
        .env("RUN_ID", run.run.as_str())
        .env("HNAV_RUNS_DIR", host.path().join("registry"))
        .stdin(Stdio::null())
        .process_group(0)
        .spawn()
        .expect("unshare starts");
    let (tx, rx) = mpsc::channel();
    let mut group = Group(child.id() as i32, None);
    std::thread::spawn(move || {
        let _ = tx.send(child.wait());
    });
    let status = rx
        .recv_timeout(TIMEOUT)
        .unwrap_or_else(|_| panic!("the run did not end within {TIMEOUT:?}"));
    group.1 = Some(rx);
    assert!(
        status.is_ok_and(|s| s.success()),
        "the namespace script failed"
    );

    let stderr = read(&host.path().join("stderr"));
    let rc = read(&host.path().join("rc"));
    assert_eq!(
        rc.trim(),
        "3",
        "hnav run's exit code; its stderr:\n{stderr}"
    );
    // Whichever writer meets the full disk first ends the run: the coordinator appending to
    // the consensus log, the sim writing its checkpoint (every period since the sim is
    // restartable), or an agent writing its checkpoint or its output (which one comes first
    // moves with what else the run writes, e.g. its recording).
    let coordinator = stderr
        .contains("no space left on device: coordinator stopped writing the consensus log in")
        && stderr.contains("mnt/run/log");
    let sim = stderr.contains("no space left on device: sim stopped writing its checkpoint")
        && stderr.contains("mnt/run/sim.ckpt");
    let agent = stderr.contains("no space left on device: agent-")
        && stderr.contains("stopped writing its checkpoint")
        && stderr.contains("mnt/run/agents/");
    assert!(
        coordinator || sim || agent,
        "the supervisor names the process, what it wrote and where:\n{stderr}"
    );
    assert!(
        !stderr.contains("restarted"),
        "a process was restarted:\n{stderr}"
    );
    assert!(
        !stderr.contains("exit code 101"),
        "a process panicked:\n{stderr}"
    );

    let copy = host.path().join("copy");
    for entry in std::fs::read_dir(copy.join("logs")).unwrap().flatten() {
        let text = read(&entry.path());
        assert!(
            !text.contains("panicked"),
            "{} holds a panic:\n{text}",
            entry.path().display()
        );
    }
    let summary = copy.join("summary.json");
    if summary.exists() {
        let text = read(&summary);
        assert!(
            serde_json::from_str::<serde_json::Value>(&text).is_ok(),
            "summary.json is not whole JSON: {text:?}"
        );
    }
    let (intact, report) = verify_log(&copy.join("log"));
    assert!(intact, "the consensus log does not verify:\n{report}");
    assert!(
        run_shm_files(&run.run).is_empty(),
        "the run left shared memory behind"
    );
}
