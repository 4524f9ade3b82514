//! Snapshots and compaction: a replica far behind catches up from its leader's snapshot, a
//! compacted journal comes back after a restart, and the journals stay bounded.

use std::path::Path;

use hnav_runtime::consensus_log::{
    decode_record, read_decided, read_log, show, verify, AppliedState, Record,
};

use super::*;

/// What replica `id` applied: the snapshot's state it started from (if any), then the
/// records it was handed.
fn applied(c: &Cluster, id: u64) -> AppliedState {
    let i = id as usize - 1;
    let mut state = c.installed[i]
        .clone()
        .unwrap_or_else(|| AppliedState::new(&header()));
    for e in &c.committed[i] {
        state.fold(&decode_record(&e.data).unwrap());
    }
    state
}

fn journal(c: &Cluster, id: u64) -> std::path::PathBuf {
    c.journals.as_ref().unwrap().path().join(id.to_string())
}

/// Bytes of the segment files in `dir`.
fn bytes(dir: &Path) -> u64 {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".hlog"))
        .map(|e| e.metadata().unwrap().len())
        .sum()
}

#[test]
fn a_replica_restarted_far_behind_catches_up_from_a_snapshot() {
    let mut c = Cluster::compacting(3, 10);
    let (leader, _) = c.elect(100);
    c.propose_rounds(leader, 1..=5);
    c.run(3);
    let behind = (1..=3).find(|&id| id != leader).unwrap();
    c.kill(behind);
    // The others commit far past the threshold and compact their journals.
    c.propose_rounds(leader, 6..=60);
    c.run(3);
    for id in (1..=3).filter(|&id| id != behind) {
        assert!(c.get(id).snapshot_index() >= 50, "replica {id} compacted");
    }
    c.restart(behind);
    c.run(20);
    let r = c.get(behind);
    assert_eq!(r.installs(), 1, "it installed the leader's snapshot");
    assert!(r.snapshot_index() >= 50);
    // It went on from the snapshot's state, not from the entries it missed.
    let handed: Vec<u64> = c.committed[behind as usize - 1]
        .iter()
        .map(|e| e.index)
        .collect();
    assert!(handed.iter().all(|&i| i > 50), "{handed:?}");
    c.propose_rounds(leader, 61..=70);
    c.run(3);
    let want = applied(&c, leader);
    assert_eq!(want.round, 70);
    assert_eq!(want.records, 70);
    for id in 1..=3 {
        assert_eq!(applied(&c, id), want, "replica {id}'s state");
    }
    // Its journal is the snapshot and the entries after it; it reads back, verifies, and
    // comes back after another restart.
    c.get(behind).sync().unwrap();
    let dir = journal(&c, behind);
    let decided = read_decided(&dir).unwrap();
    assert_eq!(decided.decided(), 70);
    assert_eq!(decided.last_round(), 70);
    let report = verify(&dir);
    assert!(report.problems.is_empty(), "{}", report.render());
    c.restart(behind);
    c.run(3);
    assert_eq!(
        applied(&c, behind),
        want,
        "after a restart over its journal"
    );
}

#[test]
fn every_replica_restarted_over_a_compacted_journal_comes_back() {
    let mut c = Cluster::compacting(3, 8);
    let (leader, _) = c.elect(100);
    c.propose_rounds(leader, 1..=30);
    c.run(3);
    let want = applied(&c, leader);
    for id in 1..=3 {
        c.kill(id);
    }
    for id in 1..=3 {
        c.restart(id);
        assert!(c.get(id).snapshot_index() >= 24, "replica {id}");
    }
    // The last commit index may not have reached a follower's disk: a new leader's first
    // entry commits it again.
    let (leader, _) = c.elect(100);
    c.run(3);
    for id in 1..=3 {
        assert!(c.installed[id as usize - 1].is_some(), "replica {id}");
        assert_eq!(c.get(id).installs(), 0, "from its own journal");
        assert_eq!(applied(&c, id), want, "replica {id}");
    }
    c.propose_rounds(leader, 31..=40);
    c.run(3);
    let want = applied(&c, leader);
    assert_eq!(want.round, 40);
    for id in 1..=3 {
        assert_eq!(applied(&c, id), want, "replica {id}");
    }
}

#[test]
fn journals_stay_bounded_across_many_compactions() {
    const K: u64 = 20;
    let mut c = Cluster::compacting(3, K);
    let (leader, _) = c.elect(100);
    let mut most_records = 0;
    let mut most_bytes = [0u64; 2];
    for block in 0..20u64 {
        c.propose_rounds(leader, block * 25 + 1..=block * 25 + 25);
        for id in 1..=3 {
            most_records = most_records.max(c.get(id).journal_records());
            let b = bytes(&journal(&c, id));
            let half = usize::from(block >= 10);
            most_bytes[half] = most_bytes[half].max(b);
        }
    }
    c.run(3);
    assert!(c.get(leader).snapshot_index() >= 480);
    // Header, snapshot and hard state, then per entry since the snapshot its record and at
    // most one hard state (a commit index), and an uncommitted entry or two.
    let bound = 3 + 2 * (K + 2);
    assert!(most_records <= bound, "{most_records} records > {bound}");
    // The second half of the run (10 times the threshold later) needs about the bytes of
    // the first: only the varints of the growing round numbers and indices are longer.
    assert!(
        most_bytes[1] <= most_bytes[0] * 5 / 4,
        "journals grew: {most_bytes:?}"
    );
    // Without compaction the same run's journal holds every entry.
    let mut full = Cluster::durable(3);
    let (leader, _) = full.elect(100);
    full.propose_rounds(leader, 1..=500);
    assert!(full.get(leader).journal_records() > 500);
    assert!(bytes(&journal(&full, leader)) > 4 * most_bytes[1]);
}

#[test]
fn a_compacted_log_verifies_and_shows_its_snapshot_and_a_damaged_one_is_located() {
    let mut c = Cluster::compacting(3, 10);
    let (leader, _) = c.elect(100);
    c.propose_rounds(leader, 1..=25);
    c.run(3);
    c.get(leader).sync().unwrap();
    let dir = journal(&c, leader);
    let report = verify(&dir);
    assert!(report.problems.is_empty(), "{}", report.render());
    assert!(report.compacted >= 19, "{}", report.render());
    assert!(
        report.render().contains("snapshot   index"),
        "{}",
        report.render()
    );
    let records = read_log(&dir).unwrap().records;
    let Record::Snapshot(snap) = &records[1] else {
        panic!(
            "the first record after the header is {:?}",
            records[1].kind()
        );
    };
    let line = show::describe(&records[1], 4);
    assert!(
        line.starts_with(&format!("snapshot {}.{}", snap.term, snap.index)),
        "{line}"
    );
    assert!(line.contains("records through round"), "{line}");
    // A byte flipped in the snapshot's state: the frame's checksum names the place.
    for id in 1..=3 {
        c.kill(id);
    }
    let seg = dir.join("seg-00000000.hlog");
    let mut bytes = std::fs::read(&seg).unwrap();
    let at = read_log(&dir).unwrap().positions[1];
    let i = (at.offset + at.len - 2) as usize;
    bytes[i] ^= 0x5a;
    std::fs::write(&seg, &bytes).unwrap();
    let report = verify(&dir);
    let text = report.render();
    assert!(!report.is_intact(), "{text}");
    assert!(text.contains("seg-00000000.hlog"), "{text}");
    assert!(text.contains("checksum"), "{text}");
    assert!(read_decided(&dir).is_err());
}
