//! Records and logs the tests share.

use std::fs;
use std::path::Path;

use hnav_runtime::consensus_log::{
    verify, AgentEntry, EndReason, EndRecord, LifecycleRecord, LogWriter, LoggedDecision, Record,
    ReplanRecord, RoundRecord, RunHeader, VerifyStatus, WriterOptions, FORMAT_VERSION,
};
use hnav_runtime::msg::{ConflictKind, Verdict, NO_CELL};
use hnav_runtime::scenario::FsyncPolicy;

/// Grid width of every test log.
pub const WIDTH: u32 = 10;

/// Grid height of every test log.
pub const HEIGHT: u32 = 8;

/// Large enough that a test log never rolls over.
pub const ONE_SEGMENT: u64 = 1 << 20;

/// The header of a run of `agents` agents (at most `WIDTH * HEIGHT / 2`), agent `i` starting
/// on cell `11 + i`.
pub fn header(agents: u32) -> Record {
    let cells = WIDTH * HEIGHT;
    Record::Header(RunHeader {
        version: FORMAT_VERSION,
        scenario_hash: 0x0123_4567_89ab_cdef,
        seed: 42,
        clock: "lockstep".into(),
        width: WIDTH,
        height: HEIGHT,
        agents: (0..agents)
            .map(|i| AgentEntry {
                start: (11 + i) % cells,
                goal: cells - 1 - i,
                speed: 1.0 / f64::from(1 + i % 2),
                priority: 1.0 + f64::from(i),
            })
            .collect(),
    })
}

/// Round `n` of `agents` agents: even agents move to cell `22 + agent`, odd ones are blocked
/// crossing (north and north-east refused). Round 1 of two agents is shown as
/// `accept a0->[2, 2] block a1 crossing (N,NE)`.
pub fn round(n: u64, agents: u32) -> Record {
    Record::Round(RoundRecord {
        round: n,
        candidates: agents,
        candidates_digest: n.wrapping_mul(0x9E37_79B9_7F4A_7C15),
        decisions: (0..agents)
            .map(|agent| {
                let accept = agent % 2 == 0;
                LoggedDecision {
                    agent,
                    verdict: if accept {
                        Verdict::Accept
                    } else {
                        Verdict::Block
                    } as u8,
                    refused: if accept { 0 } else { 0b11 },
                    kind: if accept {
                        ConflictKind::None
                    } else {
                        ConflictKind::Crossing
                    } as u8,
                    cell: if accept { 22 + agent } else { NO_CELL },
                    waypoint: NO_CELL,
                }
            })
            .collect(),
    })
}

/// A two-agent log with a record of every kind, ending with the end record.
pub fn every_kind() -> Vec<Record> {
    let mut v = vec![header(2), round(1, 2), round(2, 2)];
    v.push(Record::Lifecycle(LifecycleRecord {
        round: 2,
        role: 3,
        index: 1,
        event: 3,
        restarts: 1,
    }));
    v.push(Record::Replan(ReplanRecord {
        round: 3,
        agent: 1,
        planner: "lazy-theta-star".into(),
        found: true,
        waypoints: vec![12, 14, 34, 3],
    }));
    v.push(round(3, 2));
    v.push(round(4, 2));
    v.push(Record::End(EndRecord {
        round: 4,
        at_goal: 2,
        reason: EndReason::AllAtGoal,
    }));
    v
}

/// Writes `records` to a new log in `dir` with the writer (without fsync: the tests damage
/// bytes, they do not cut power), rolling over to a new segment before a record that would
/// take the current one past `segment_bytes`. Returns (segment, offset) of each record.
pub fn write_log(dir: &Path, records: &[Record], segment_bytes: u64) -> Vec<(u32, usize)> {
    let options = WriterOptions {
        fsync: FsyncPolicy::None,
        segment_bytes,
    };
    let (mut log, recovered) = LogWriter::open_with(dir, options).unwrap();
    assert_eq!(recovered.records, [], "{} is a new log", dir.display());
    records
        .iter()
        .map(|r| {
            let offset = log.append(r).unwrap();
            (log.segment(), offset as usize)
        })
        .collect()
}

/// Fails with the verify report unless the log in `dir` is intact.
pub fn assert_intact(dir: &Path) {
    let report = verify(dir);
    assert_eq!(report.status(), VerifyStatus::Intact, "{}", report.render());
}

/// The bytes of every file in `dir`, in name order.
pub fn read_files(dir: &Path) -> Vec<Vec<u8>> {
    let mut v: Vec<_> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    v.sort();
    v.iter().map(|p| fs::read(p).unwrap()).collect()
}
