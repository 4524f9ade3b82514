//! SIGKILL of a process holding publishers: the transport sees the node dead and cleans up.
//! In its own test binary because it kills processes.

use std::time::Duration;

use hnav_runtime::transport::{purge_run, run_shm_files, NodeLiveness, Transport};
use hnav_tests::TestRun;
use nix::sys::signal::Signal;

const PEER: &str = env!("CARGO_BIN_EXE_hnav-test-peer");

#[test]
fn a_killed_publisher_is_reported_dead_and_its_shared_memory_removed() {
    let mut run = TestRun::new("kill");
    let mut holder = run.spawn(PEER, &["hold"]).unwrap();
    holder
        .wait_for_line("READY", Duration::from_secs(60))
        .unwrap();
    assert!(
        !run_shm_files(&run.run).is_empty(),
        "the holder's publishers should have shared memory"
    );
    let before = Transport::nodes_of(&run.run).unwrap();
    assert!(before
        .iter()
        .any(|n| n.name == "holder" && n.liveness == NodeLiveness::Alive));

    holder.signal(Signal::SIGKILL).unwrap();
    let status = holder.wait_exit(Duration::from_secs(30)).unwrap();
    assert!(!status.success());

    let after = Transport::nodes_of(&run.run).unwrap();
    let dead: Vec<_> = after
        .iter()
        .filter(|n| n.name == "holder" && n.liveness == NodeLiveness::Dead)
        .collect();
    assert_eq!(dead.len(), 1, "nodes after kill: {after:?}");
    assert_eq!(dead[0].pid, Some(holder.pid as i32));

    // A supervisor-like observer, outside the run, removes the dead node's resources.
    let report = Transport::cleanup_dead_nodes_of(&run.run).unwrap();
    assert_eq!(report.removed.len(), 1, "{report:?}");
    assert_eq!(report.removed[0].name, "holder");
    assert_eq!(report.alive, 0);
    assert!(Transport::nodes_of(&run.run).unwrap().is_empty());

    purge_run(&run.run).unwrap();
    assert_eq!(run_shm_files(&run.run), Vec::<std::path::PathBuf>::new());
}
