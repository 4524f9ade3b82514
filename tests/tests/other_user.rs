//! Several users on one machine: once root has run, another user's `hnav run` works (each
//! user has their own iceoryx2 directory), and a directory the user may not use is a clear
//! error naming it and the permission, with no file of the run left in `/dev/shm`.
//!
//! Switching user needs root (`setpriv`): without it the test fails and says so.

use std::os::unix::fs::{chown, MetadataExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use hnav_runtime::transport::{purge_run, run_shm_files, RunId, Transport, IPC_ROOT_ENV};
use hnav_tests::swarm::{repo_root, workspace_bin};

/// The unprivileged user the runs switch to (`nobody` on Debian).
const USER: u32 = 65534;

/// The demo takes ~13 s in the debug build on this machine.
const TIMEOUT: Duration = Duration::from_secs(180);

/// A copy of the binaries and the scenario that `USER` can reach, and a run directory it owns.
struct Sandbox {
    _dir: tempfile::TempDir,
    bin: PathBuf,
    scenario: PathBuf,
    out: PathBuf,
}

impl Sandbox {
    fn new() -> Sandbox {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        let bin = root.join("bin");
        let out = root.join("out");
        std::fs::create_dir(&bin).unwrap();
        std::fs::create_dir(&out).unwrap();
        for name in ["hnav", "hnav-sim", "hnav-agent", "hnav-coordinator"] {
            // A hard link costs no disk; a copy is the fallback across file systems.
            let (from, to) = (workspace_bin(name), bin.join(name));
            if std::fs::hard_link(&from, &to).is_err() {
                std::fs::copy(&from, &to).unwrap();
            }
            set_mode(&bin.join(name), 0o755);
        }
        let scenario = root.join("demo.toml");
        std::fs::copy(repo_root().join("scenarios/demo.toml"), &scenario).unwrap();
        set_mode(&scenario, 0o644);
        set_mode(root, 0o755);
        set_mode(&bin, 0o755);
        chown(&out, Some(USER), Some(USER)).unwrap();
        Sandbox {
            _dir: dir,
            bin,
            scenario,
            out,
        }
    }

    /// `hnav run` of the demo as `USER` with run id `run` (and `env`), waited for, bounded.
    fn run_as_user(&self, run: &RunId, env: &[(&str, &str)]) -> Output {
        let mut cmd = Command::new("setpriv");
        cmd.args([
            format!("--reuid={USER}"),
            format!("--regid={USER}"),
            "--clear-groups".into(),
        ])
        .arg(self.bin.join("hnav"))
        .arg("run")
        .arg(&self.scenario)
        .arg("--run")
        .arg(run.as_str())
        .arg("--out")
        .arg(self.out.join(run.as_str()))
        .env("HNAV_RUNS_DIR", self.out.join("registry"))
        .env_remove(IPC_ROOT_ENV)
        .stdin(Stdio::null());
        for (k, v) in env {
            cmd.env(k, v);
        }
        let child = cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn();
        let child = child.expect("setpriv starts");
        let pid = child.id();
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let _ = tx.send(child.wait_with_output());
        });
        match rx.recv_timeout(TIMEOUT) {
            Ok(out) => out.expect("wait"),
            Err(_) => {
                let _ = nix::sys::signal::kill(
                    nix::unistd::Pid::from_raw(pid as i32),
                    nix::sys::signal::Signal::SIGKILL,
                );
                panic!("hnav run as uid {USER} did not end within {TIMEOUT:?}");
            }
        }
    }
}

fn set_mode(p: &Path, mode: u32) {
    std::fs::set_permissions(p, std::fs::Permissions::from_mode(mode)).unwrap();
}

/// Removes a run's files from `/dev/shm` and from `USER`'s iceoryx2 directory, also when the
/// test failed.
struct Cleanup(RunId);

impl Drop for Cleanup {
    fn drop(&mut self) {
        std::env::set_var(IPC_ROOT_ENV, user_root());
        let _ = purge_run(&self.0);
        std::env::remove_var(IPC_ROOT_ENV);
    }
}

fn user_root() -> PathBuf {
    PathBuf::from(format!("/tmp/iceoryx2-{USER}/"))
}

/// Files under `dir` whose name holds the run's prefix.
fn files_of(dir: &Path, run: &RunId) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return out;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(files_of(&p, run));
        } else if e.file_name().to_string_lossy().contains(&run.prefix()) {
            out.push(p);
        }
    }
    out
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

#[test]
fn another_user_runs_after_root_and_a_forbidden_directory_is_named() {
    let uid = std::fs::metadata("/proc/self")
        .map(|m| m.uid())
        .unwrap_or(u32::MAX);
    assert_eq!(
        uid, 0,
        "this test needs root: it switches to uid {USER} with `setpriv` to run as another user"
    );
    // Root runs first: its iceoryx2 directory exists from now on, readable by root only.
    let root_run = RunId::unique("rootfirst");
    {
        let _t = Transport::builder(&root_run)
            .node_name("root")
            .create()
            .unwrap();
    }
    purge_run(&root_run).unwrap();
    let sandbox = Sandbox::new();

    let run = RunId::unique("otheruser");
    let _cleanup = Cleanup(run.clone());
    let out = sandbox.run_as_user(&run, &[]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "hnav run as uid {USER}:\n{}",
        text(&out)
    );
    assert_eq!(
        run_shm_files(&run),
        Vec::<PathBuf>::new(),
        "left in /dev/shm"
    );
    assert_eq!(files_of(&user_root(), &run), Vec::<PathBuf>::new());
    let meta = std::fs::metadata(user_root()).unwrap();
    assert_eq!(
        meta.uid(),
        USER,
        "{} is the user's own",
        user_root().display()
    );

    // Root's directory is closed to other users: pointing a run there is a named error.
    let forbidden = RunId::unique("forbidden");
    let _cleanup2 = Cleanup(forbidden.clone());
    let out = sandbox.run_as_user(&forbidden, &[(IPC_ROOT_ENV, "/tmp/iceoryx2")]);
    let said = text(&out);
    assert_eq!(out.status.code(), Some(2), "{said}");
    assert!(
        said.contains("cannot use the shared-memory directory /tmp/iceoryx2/: permission denied"),
        "the error names the directory and the permission:\n{said}"
    );
    assert!(!said.contains("InternalError"), "{said}");
    assert_eq!(
        run_shm_files(&forbidden),
        Vec::<PathBuf>::new(),
        "left in /dev/shm"
    );
}
