//! Writes the generated part of the committed corpus (`seed-*` files of `fuzz/corpus/log`,
//! `record` and `payload`): consensus logs written by the real [`LogWriter`] and damaged the
//! ways the reader tells apart, each record kind's payload, and each shared-memory payload's
//! bytes. Run it after a format change, then commit the files:
//! `cargo test -p hnav-fuzz --test seed_corpus -- --ignored`.

use std::path::Path;

use hnav_fuzz::Target;
use hnav_runtime::consensus_log::{
    encode_frame, AgentEntry, EndReason, EndRecord, LifecycleRecord, LogWriter, Record,
    ReplanRecord, RoundRecord, RunHeader, UnreachableRecord, WriterOptions, FORMAT_VERSION,
    FRAME_HEADER_LEN, MAGIC,
};
use hnav_runtime::msg::{
    Candidate, CandidateFlags, CommitHeader, ConflictKind, Decision, Lifecycle, MapHeader,
    Odometry, Pose, Progress, Role, StartupPhase, StopReason, TruthHeader, Verdict, WheelCommand,
};
use hnav_runtime::scenario::FsyncPolicy;

fn header(version: u32) -> Record {
    Record::Header(RunHeader {
        version,
        scenario_hash: 0x0123_4567_89ab_cdef,
        seed: 1,
        clock: "lockstep".into(),
        width: 7,
        height: 5,
        agents: vec![
            AgentEntry {
                start: 0,
                goal: 6,
                speed: 1.0,
                priority: 1.0,
            },
            AgentEntry {
                start: 28,
                goal: 34,
                speed: 0.5,
                priority: 2.0,
            },
        ],
    })
}

fn decision(agent: u32, verdict: Verdict, kind: ConflictKind, cell: u32) -> Decision {
    Decision {
        agent,
        verdict: verdict as u8,
        refused: if verdict == Verdict::Block {
            0b0000_0100
        } else {
            0
        },
        kind: kind as u8,
        cell,
        ..Decision::default()
    }
}

fn candidate(round: u64, agent: u32, current: u32, probable: u32) -> Candidate {
    Candidate {
        round,
        agent,
        current,
        next: current,
        probable,
        priority: 1.0,
        speed: 1.0,
        ..Candidate::default()
    }
}

/// A short run's records as the coordinator writes them: rounds, a down and restart, a
/// replan, an unreachable report and the end.
fn run_records() -> Vec<Record> {
    let round = |r: u64, a: u32, b: u32| {
        Record::Round(RoundRecord::new(
            r,
            &[candidate(r, 0, a, a + 1), candidate(r, 1, b, b + 1)],
            &[
                decision(0, Verdict::Accept, ConflictKind::None, a + 1),
                decision(1, Verdict::Block, ConflictKind::Crossing, u32::MAX),
            ],
        ))
    };
    let life = |r: u64, l: Lifecycle| Record::Lifecycle(LifecycleRecord::new(r, &l));
    vec![
        header(FORMAT_VERSION),
        round(1, 0, 28),
        life(1, Lifecycle::down(Role::Agent, 1, 0)),
        life(1, Lifecycle::restarted(Role::Agent, 1, 1)),
        round(2, 1, 28),
        Record::Replan(ReplanRecord {
            round: 3,
            agent: 1,
            planner: "lazy-theta-star".into(),
            found: true,
            waypoints: vec![28, 30, 34],
        }),
        Record::Unreachable(UnreachableRecord {
            round: 3,
            agent: 0,
            cell: 2,
        }),
        round(3, 2, 28),
        Record::End(EndRecord {
            round: 3,
            at_goal: 1,
            reason: EndReason::AllAtGoalOrUnreachable,
        }),
    ]
}

/// The segments the real writer makes of `records`, `segment_bytes` at most each.
fn written(records: &[Record], segment_bytes: u64) -> Vec<Vec<u8>> {
    let dir = tempfile::tempdir().unwrap();
    let options = WriterOptions {
        fsync: FsyncPolicy::None,
        segment_bytes,
    };
    let (mut writer, _) = LogWriter::open_with(dir.path(), options).unwrap();
    for r in records {
        writer.append(r).unwrap();
    }
    writer.sync().unwrap();
    drop(writer);
    let mut segments = Vec::new();
    while let Ok(b) = std::fs::read(dir.path().join(format!("seg-{:08}.hlog", segments.len()))) {
        segments.push(b);
    }
    segments
}

fn frame(record: &Record) -> Vec<u8> {
    let mut buf = Vec::new();
    encode_frame(record, &mut buf).unwrap();
    buf
}

fn write(target: Target, name: &str, data: &[u8]) {
    let dir = target.corpus_dir();
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(Path::new(&dir).join(name), data).unwrap();
}

fn log_corpus() {
    let records = run_records();
    let intact = written(&records, u64::MAX).concat();
    write(Target::Log, "seed-intact.hlog", &intact);
    let split = written(&records, 160);
    assert!(split.len() > 1);
    write(Target::Log, "seed-segments.hlog", &split.concat());
    write(Target::Log, "seed-torn.hlog", &intact[..intact.len() - 5]);
    write(Target::Log, "seed-short-magic.hlog", &MAGIC[..5]);
    let mut zero = intact.clone();
    zero.extend_from_slice(&[0; 64]);
    write(Target::Log, "seed-zero-fill.hlog", &zero);
    let mut bad_crc = intact.clone();
    bad_crc[MAGIC.len() + frame(&records[0]).len() + FRAME_HEADER_LEN + 2] ^= 0x40;
    write(Target::Log, "seed-bad-crc.hlog", &bad_crc);
    let mut bad_magic = intact.clone();
    bad_magic[7] = b'2';
    write(Target::Log, "seed-bad-magic.hlog", &bad_magic);
    let unknown = [9u8];
    let mut unknown_kind = intact[..intact.len() - frame(records.last().unwrap()).len()].to_vec();
    unknown_kind.extend_from_slice(&(unknown.len() as u32).to_le_bytes());
    unknown_kind.extend_from_slice(&crc32c::crc32c(&unknown).to_le_bytes());
    unknown_kind.extend_from_slice(&unknown);
    unknown_kind.extend_from_slice(&frame(records.last().unwrap()));
    write(Target::Log, "seed-unknown-kind.hlog", &unknown_kind);
    // The writer refuses to write these two, so they are framed by hand.
    let by_hand = |records: &[Record]| {
        let mut bytes = MAGIC.to_vec();
        for r in records {
            bytes.extend_from_slice(&frame(r));
        }
        bytes
    };
    write(Target::Log, "seed-no-header.hlog", &by_hand(&records[1..3]));
    let mut other_version = records.clone();
    other_version[0] = header(FORMAT_VERSION + 1);
    write(Target::Log, "seed-version.hlog", &by_hand(&other_version));
    let mut gap = records.clone();
    gap.remove(4);
    write(
        Target::Log,
        "seed-round-gap.hlog",
        &written(&gap, u64::MAX).concat(),
    );
}

fn record_corpus() {
    for r in run_records().iter().chain([&header(FORMAT_VERSION + 1)]) {
        let f = frame(r);
        let name = format!("seed-{}-{}", r.kind(), r.round().unwrap_or(0));
        write(Target::Record, &name, &f[FRAME_HEADER_LEN..]);
    }
    write(Target::Record, "seed-unknown-kind", &[6, 1, 2, 3]);
    let mut trailing = frame(&run_records()[8])[FRAME_HEADER_LEN..].to_vec();
    trailing.push(0);
    write(Target::Record, "seed-trailing-byte", &trailing);
}

/// The bytes of a payload value.
fn bytes_of<T: Copy>(value: &T) -> Vec<u8> {
    // SAFETY: every `msg` payload is `#[repr(C)]` without padding (their layout tests), so all
    // `size_of::<T>()` bytes of `value` are initialised.
    unsafe {
        std::slice::from_raw_parts((value as *const T).cast::<u8>(), std::mem::size_of::<T>())
    }
    .to_vec()
}

fn payload(kind: u8, name: &str, bytes: Vec<u8>, keep: usize) {
    let mut data = vec![kind];
    data.extend_from_slice(&bytes[..keep.min(bytes.len())]);
    write(Target::Payload, &format!("seed-{kind}-{name}"), &data);
}

fn payload_corpus() {
    let c = Candidate {
        flags: CandidateFlags::RESTARTED,
        ..candidate(40, 3, 17, 18)
    };
    payload(0, "candidate", bytes_of(&c), usize::MAX);
    let nan = Candidate {
        priority: f32::NAN,
        ..c
    };
    payload(0, "candidate-nan", bytes_of(&nan), usize::MAX);
    let d = decision(2, Verdict::Replan, ConflictKind::HeadOn, 9);
    payload(1, "decision", bytes_of(&d), usize::MAX);
    // A slice sample as it sits in shared memory: the header, then its elements.
    let commit = CommitHeader {
        round: 41,
        count: 3,
        term: 0,
    };
    let mut bytes = bytes_of(&commit);
    for d in [
        decision(0, Verdict::Accept, ConflictKind::None, 1),
        decision(1, Verdict::Block, ConflictKind::StableCell, u32::MAX),
        decision(2, Verdict::Hold, ConflictKind::Reserved, u32::MAX),
    ] {
        bytes.extend(bytes_of(&d));
    }
    payload(2, "commit", bytes, usize::MAX);
    let truth = TruthHeader {
        sim_time_ns: 5_000_000,
        period: 5,
        robots: 2,
        collisions: 0,
    };
    let mut bytes = bytes_of(&truth);
    for p in [
        Pose::default(),
        Pose {
            x_m: 1.5,
            y_m: 0.5,
            theta_rad: 1.0,
        },
    ] {
        bytes.extend(bytes_of(&p));
    }
    payload(3, "truth", bytes, usize::MAX);
    for (name, l) in [
        ("up", Lifecycle::up(Role::Agent, 3)),
        ("stop", Lifecycle::stop(StopReason::TimeLimit)),
        (
            "phase",
            Lifecycle::phase(Role::Agent, 1, StartupPhase::BuildingNeuralMap, 12),
        ),
        ("hold", Lifecycle::hold(300)),
    ] {
        payload(4, &format!("lifecycle-{name}"), bytes_of(&l), usize::MAX);
    }
    let p = Progress {
        round: 9,
        agents: 6,
        at_goal: 6,
        done: Progress::ALL_AT_GOAL,
        ..Progress::default()
    };
    payload(5, "progress", bytes_of(&p), usize::MAX);
    let h = MapHeader {
        round: 2,
        agent: 1,
        width: 12,
        height: 12,
        iterations: 40,
        target: 7,
        activation: 2,
        reserved: [0; 3],
    };
    payload(6, "map-header", bytes_of(&h), usize::MAX);
    let w = WheelCommand {
        period: 3,
        agent: 1,
        flags: 0,
        left_rad_s: 2.0,
        right_rad_s: -2.0,
    };
    payload(7, "wheel-command", bytes_of(&w), usize::MAX);
    let o = Odometry {
        sim_time_ns: 1,
        period: 3,
        agent: 1,
        flags: Odometry::FIX,
        ticks_left: -7,
        ticks_right: 12,
        fix: Pose {
            x_m: 0.4,
            y_m: 0.24,
            theta_rad: -1.5,
        },
    };
    payload(8, "odometry", bytes_of(&o), usize::MAX);
}

#[test]
#[ignore = "writes the committed corpus; run by hand after a format change"]
fn write_seed_corpus() {
    log_corpus();
    record_corpus();
    payload_corpus();
}
