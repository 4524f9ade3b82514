//! A restarted process that hangs before its `Up` is watched like any other: declared hung
//! once its start-up timeout passes, SIGKILLed and restarted again. Before, the hang watch
//! followed a restart only from its `Up`, so a restart that never came up was watched by
//! nobody and a lockstep run waited for it for ever (issue 38, item 5).
//!
//! The agent binary is wrapped (`hnav run --bin-dir`): its first restart (`--resume`) stops
//! itself with SIGSTOP before it does anything, as a process stuck in its start-up would.

use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::time::Duration;

use hnav_tests::swarm::{repo_root, workspace_bin, SwarmRun};
use hnav_tests::TestRun;

/// Far above the run plus one start-up timeout, far below a CI job's limit.
const BOUND: Duration = Duration::from_secs(180);

/// A bin directory whose `hnav-agent` stops itself on the first `--resume` (the mark
/// directory is made once) and is the real agent otherwise.
fn bin_dir(dir: &Path) -> std::path::PathBuf {
    let bin = dir.join("bin");
    std::fs::create_dir(&bin).unwrap();
    for name in ["hnav-sim", "hnav-coordinator"] {
        std::os::unix::fs::symlink(workspace_bin(name), bin.join(name)).unwrap();
    }
    let script = format!(
        "#!/bin/sh\n\
         case \" $* \" in\n\
         *\" --resume \"*) if mkdir '{mark}' 2>/dev/null; then kill -STOP $$; fi ;;\n\
         esac\n\
         exec '{real}' \"$@\"\n",
        mark = dir.join("stopped-once").display(),
        real = workspace_bin("hnav-agent").display(),
    );
    let agent = bin.join("hnav-agent");
    std::fs::write(&agent, script).unwrap();
    std::fs::set_permissions(&agent, std::fs::Permissions::from_mode(0o755)).unwrap();
    bin
}

#[test]
fn a_restart_that_hangs_before_its_up_is_hung_killed_and_restarted_again() {
    let tmp = tempfile::tempdir().unwrap();
    let demo = std::fs::read_to_string(repo_root().join("scenarios/demo.toml")).unwrap();
    let scenario = tmp.path().join("demo.toml");
    // A short start-up timeout keeps the test short.
    std::fs::write(&scenario, format!("{demo}\n[run]\nstartup_timeout_s = 3\n")).unwrap();
    let bin = bin_dir(tmp.path());
    let mut run = TestRun::new("hangup");
    let mut swarm = SwarmRun::start(
        &mut run,
        &scenario,
        &tmp.path().join("out"),
        &tmp.path().join("runs"),
        &[
            "--mode",
            "lockstep",
            "--kill",
            "agent:0@round:100",
            "--bin-dir",
            &bin.display().to_string(),
        ],
    )
    .expect("hnav run starts");
    let status = swarm.finish(BOUND);
    let status = status.unwrap_or_else(|e| panic!("the run never ended: {e}"));
    assert!(status.success(), "{status}\n{}", swarm.log_tails());
    assert!(
        tmp.path().join("stopped-once").exists(),
        "the restart was never stopped"
    );
    let s = swarm.summary().unwrap();
    assert_eq!(s["end"], "all-at-goal", "{s}");
    assert_eq!(s["restarts"]["agent-0"], 2, "{s}");
    let events = std::fs::read_to_string(tmp.path().join("out/events.jsonl")).unwrap();
    let hung: Vec<&str> = events
        .lines()
        .filter(|l| l.contains("\"hung\"") && l.contains("\"agent-0\""))
        .collect();
    assert_eq!(hung.len(), 1, "{events}");
}
