//! `hnav clean`'s library half on fabricated registry entries: a dead run's leftover process
//! is killed (only while its pid is still the recorded process) and its entry removed; a
//! live run is refused. In its own test binary because it SIGKILLs processes.

use std::os::unix::process::CommandExt;
use std::process::Command;

use hnav_operator::supervisor::clean::{clean_dead_runs, clean_run, CleanError};
use hnav_operator::supervisor::proc_stat::pid_alive;
use hnav_operator::supervisor::registry::RunRegistry;
use hnav_runtime::msg::Role;
use hnav_runtime::transport::RunId;

/// The pid of a process that has exited and been reaped.
fn exited_pid() -> u32 {
    let mut c = Command::new("true").spawn().unwrap();
    let pid = c.id();
    c.wait().unwrap();
    pid
}

#[test]
fn a_dead_runs_leftover_process_is_killed_and_its_entry_removed() {
    let tmp = tempfile::tempdir().unwrap();
    let reg = RunRegistry::at(tmp.path());
    let run = RunId::unique("cleandead");
    // A child of a run whose supervisor died: the leader of its own process group.
    let mut leftover = Command::new("sleep")
        .arg("600")
        .process_group(0)
        .spawn()
        .unwrap();
    let mut rec = reg.new_record(&run, tmp.path().join("out"));
    rec.supervisor_pid = exited_pid();
    rec.supervisor_start_ticks = None;
    rec.set_process(Role::Agent, 0, leftover.id(), 0);
    // A recorded pid that now names another process (this test) must not be killed.
    rec.set_process(Role::Agent, 1, std::process::id(), 0);
    if let Some(p) = rec.processes.iter_mut().find(|p| p.index == 1) {
        p.start_ticks = p.start_ticks.map(|t| t + 1);
    }
    rec.write().unwrap();
    assert!(reg.list_runs()[0].stale);

    let cleaned: Vec<_> = clean_dead_runs(&reg)
        .into_iter()
        .map(Result::unwrap)
        .collect();
    assert_eq!(cleaned.len(), 1, "{cleaned:?}");
    assert_eq!((cleaned[0].killed, cleaned[0].registered), (1, true));
    let status = leftover.wait().unwrap();
    assert!(!status.success(), "the leftover exited by itself: {status}");
    assert!(reg.list_runs().is_empty());
    assert!(
        std::fs::read_dir(tmp.path()).unwrap().next().is_none(),
        "the registry keeps a file of the cleaned run"
    );
}

#[test]
fn a_live_run_is_not_cleaned() {
    let tmp = tempfile::tempdir().unwrap();
    let reg = RunRegistry::at(tmp.path());
    let run = RunId::unique("cleanlive");
    // This process plays the live supervisor.
    let rec = reg.new_record(&run, tmp.path().join("out"));
    rec.write().unwrap();
    let err = clean_run(&reg, &run).unwrap_err();
    assert!(
        matches!(err, CleanError::Live { pid, .. } if pid == std::process::id()),
        "{err}"
    );
    assert!(err.to_string().contains("is live"), "{err}");
    assert!(clean_dead_runs(&reg).is_empty());
    assert_eq!(reg.list_runs().len(), 1);
    assert!(pid_alive(std::process::id()));
}
