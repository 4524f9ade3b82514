//! The consensus-log format: records, framing, torn tails vs corruption, segments, verify and
//! the `hnav log` command. Logs are written here frame by frame with `encode_frame` (the
//! writer itself lives in hnav-coordinator).

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use hnav_runtime::consensus_log::{
    candidates_digest, encode_frame, read_log, segment_path, verify, AgentEntry, EndReason,
    EndRecord, FrameProblem, LifecycleRecord, LogError, LoggedDecision, Record, ReplanRecord,
    RoundRecord, RunHeader, VerifyStatus, FORMAT_VERSION, MAGIC,
};
use hnav_runtime::msg::{Candidate, Decision, NO_CELL};

fn header() -> Record {
    Record::Header(RunHeader {
        version: FORMAT_VERSION,
        scenario_hash: 0x0123_4567_89ab_cdef,
        seed: 42,
        clock: "lockstep".into(),
        width: 10,
        height: 8,
        agents: vec![
            AgentEntry {
                start: 11,
                goal: 55,
                speed: 1.0,
                priority: 1.0,
            },
            AgentEntry {
                start: 12,
                goal: 3,
                speed: 0.5,
                priority: 2.0,
            },
        ],
    })
}

fn round(n: u64) -> Record {
    Record::Round(RoundRecord {
        round: n,
        candidates: 2,
        candidates_digest: n.wrapping_mul(0x9E37_79B9_7F4A_7C15),
        decisions: vec![
            LoggedDecision {
                agent: 0,
                verdict: 1,
                refused: 0,
                kind: 0,
                cell: 22,
                waypoint: NO_CELL,
            },
            LoggedDecision {
                agent: 1,
                verdict: 2,
                refused: 0b11,
                kind: 1,
                cell: NO_CELL,
                waypoint: NO_CELL,
            },
        ],
    })
}

fn every_kind() -> Vec<Record> {
    let mut v = vec![header(), round(1), round(2)];
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
    v.push(round(3));
    v.push(round(4));
    v.push(Record::End(EndRecord {
        round: 4,
        at_goal: 2,
        reason: EndReason::AllAtGoal,
    }));
    v
}

/// Writes `records` as a log, starting a new segment before a record that would take the
/// current one past `segment_bytes` (as the writer does). Returns (segment, offset) of each.
fn write_log(dir: &Path, records: &[Record], segment_bytes: usize) -> Vec<(u32, usize)> {
    let mut segments = vec![MAGIC.to_vec()];
    let mut at = Vec::new();
    for r in records {
        let mut frame = Vec::new();
        encode_frame(r, &mut frame).unwrap();
        let cur = segments.last().unwrap();
        if cur.len() > MAGIC.len() && cur.len() + frame.len() > segment_bytes {
            segments.push(MAGIC.to_vec());
        }
        let n = segments.len() as u32 - 1;
        let cur = segments.last_mut().unwrap();
        at.push((n, cur.len()));
        cur.extend_from_slice(&frame);
    }
    fs::create_dir_all(dir).unwrap();
    for (n, bytes) in segments.iter().enumerate() {
        fs::write(segment_path(dir, n as u32), bytes).unwrap();
    }
    at
}

fn hnav(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_hnav"))
        .args(args)
        .output()
        .unwrap();
    let text = |b: Vec<u8>| String::from_utf8_lossy(&b).into_owned();
    (
        out.status.code().unwrap_or(-1),
        text(out.stdout),
        text(out.stderr),
    )
}

fn p(dir: &Path) -> &str {
    dir.to_str().unwrap()
}

#[test]
fn every_record_kind_round_trips() {
    let tmp = tempfile::tempdir().unwrap();
    let mut records = every_kind();
    for reason in [EndReason::TimeLimit, EndReason::Stopped] {
        records.push(Record::End(EndRecord {
            round: 4,
            at_goal: 0,
            reason,
        }));
    }
    let at = write_log(tmp.path(), &records, 1 << 20);
    let log = read_log(tmp.path()).unwrap();
    assert_eq!(log.records, records);
    assert_eq!(log.torn, None);
    assert_eq!(log.segments.len(), 1);
    for (pos, &(seg, off)) in log.positions.iter().zip(&at) {
        assert_eq!((pos.segment, pos.offset), (seg, off as u64));
    }
}

#[test]
fn decisions_convert_both_ways_and_the_digest_hashes_fields_in_agent_order() {
    let d = Decision {
        agent: 7,
        verdict: 4,
        refused: 0x81,
        kind: 6,
        reserved: 0,
        cell: 99,
        waypoint: 123,
    };
    assert_eq!(Decision::from(&LoggedDecision::from(&d)), d);

    let c = |agent, next| Candidate {
        round: 5,
        agent,
        current: 1,
        next,
        probable: 3,
        priority: 1.5,
        speed: 2.0,
        flags: 0,
        reserved: 0,
    };
    let sorted = [c(0, 2), c(1, 4), c(2, 6)];
    let shuffled = [c(2, 6), c(0, 2), c(1, 4)];
    assert_eq!(candidates_digest(&sorted), candidates_digest(&shuffled));
    assert_ne!(candidates_digest(&sorted), candidates_digest(&sorted[..2]));
    let mut changed = sorted;
    changed[1].priority = 1.25;
    assert_ne!(candidates_digest(&sorted), candidates_digest(&changed));
    let mut reserved = sorted;
    reserved[0].reserved = 9;
    assert_eq!(candidates_digest(&sorted), candidates_digest(&reserved));

    let rec = RoundRecord::new(5, &shuffled, &[d]);
    assert_eq!(rec.candidates, 3);
    let commit = rec.commit();
    assert_eq!((commit.round, commit.decisions()), (5, &[d][..]));
}

#[test]
fn a_cut_at_every_offset_of_the_last_record_is_a_torn_tail() {
    let tmp = tempfile::tempdir().unwrap();
    let full = tmp.path().join("full");
    let records = every_kind();
    let at = write_log(&full, &records, 1 << 20);
    let bytes = fs::read(segment_path(&full, 0)).unwrap();
    let last = at.last().unwrap().1;
    for cut in last..bytes.len() {
        let dir = tmp.path().join(format!("cut-{cut}"));
        fs::create_dir(&dir).unwrap();
        fs::write(segment_path(&dir, 0), &bytes[..cut]).unwrap();
        let log = read_log(&dir).unwrap_or_else(|e| panic!("cut at {cut}: {e}"));
        assert_eq!(log.records, records[..records.len() - 1], "cut at {cut}");
        let report = verify(&dir);
        if cut == last {
            assert_eq!(log.torn, None);
            assert_eq!(report.status(), VerifyStatus::Intact, "{}", report.render());
        } else {
            let torn = log.torn.as_ref().expect("torn tail");
            assert_eq!(
                (torn.segment, torn.offset),
                (0, last as u64),
                "cut at {cut}"
            );
            assert_eq!(torn.bytes, (cut - last) as u64);
            assert_eq!(report.status(), VerifyStatus::NotIntact);
            assert_eq!(report.torn.as_ref().map(|t| t.bytes), Some(torn.bytes));
        }
        // Reading changed nothing.
        assert_eq!(fs::read(segment_path(&dir, 0)).unwrap(), &bytes[..cut]);
        fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn a_damaged_final_record_and_a_zero_filled_tail_are_torn() {
    let tmp = tempfile::tempdir().unwrap();
    let records = every_kind();
    let at = write_log(tmp.path(), &records, 1 << 20);
    let path = segment_path(tmp.path(), 0);
    let good = fs::read(&path).unwrap();
    let last = at.last().unwrap().1;

    let mut flipped = good.clone();
    *flipped.last_mut().unwrap() ^= 0x40;
    fs::write(&path, &flipped).unwrap();
    let log = read_log(tmp.path()).unwrap();
    let torn = log.torn.unwrap();
    assert_eq!(torn.offset, last as u64);
    assert!(matches!(torn.problem, FrameProblem::BadChecksum { .. }));

    let mut zeros = good[..last].to_vec();
    zeros.extend_from_slice(&[0; 100]);
    fs::write(&path, &zeros).unwrap();
    let log = read_log(tmp.path()).unwrap();
    assert_eq!(log.records.len(), records.len() - 1);
    let torn = log.torn.unwrap();
    assert_eq!((torn.offset, torn.bytes), (last as u64, 100));
    assert_eq!(torn.problem, FrameProblem::ZeroFill { bytes: 100 });
}

#[test]
fn a_flipped_byte_in_a_middle_record_is_corruption_at_its_offset() {
    let tmp = tempfile::tempdir().unwrap();
    let records = every_kind();
    let at = write_log(tmp.path(), &records, 1 << 20);
    let path = segment_path(tmp.path(), 0);
    let good = fs::read(&path).unwrap();
    let (start, end) = (at[3].1, at[4].1);
    // Every byte of the record: its length, its checksum and its payload.
    for i in start..end {
        for bit in [0x01u8, 0x80] {
            let mut bad = good.clone();
            bad[i] ^= bit;
            fs::write(&path, &bad).unwrap();
            match read_log(tmp.path()) {
                Err(LogError::Corrupt {
                    path: p, offset, ..
                }) => {
                    assert_eq!(p, path);
                    assert_eq!(offset, start as u64, "byte {i} bit {bit:#x}");
                }
                other => panic!("byte {i} bit {bit:#x}: {other:?}"),
            }
            let report = verify(tmp.path());
            assert_eq!(report.status(), VerifyStatus::NotIntact);
            assert_eq!(report.counts.total(), 3, "records before the damage");
            assert!(report.render().contains(&format!("byte {start}")));
            assert_eq!(fs::read(&path).unwrap(), bad, "verify changed nothing");
        }
    }
}

#[test]
fn segments_roll_over_and_damage_in_an_earlier_one_is_corruption() {
    let tmp = tempfile::tempdir().unwrap();
    let mut records = vec![header()];
    records.extend((1..=40).map(round));
    let at = write_log(tmp.path(), &records, 300);
    let segments = at.last().unwrap().0 + 1;
    assert!(segments >= 5, "{segments} segments");
    let log = read_log(tmp.path()).unwrap();
    assert_eq!(log.records, records);
    assert_eq!(log.segments.len(), segments as usize);
    let report = verify(tmp.path());
    assert_eq!(report.status(), VerifyStatus::Intact, "{}", report.render());
    assert_eq!((report.first_round, report.last_round), (Some(1), Some(40)));
    assert_eq!(report.counts.round, 40);

    // A cut end of a segment that is not the last one is corruption, not a torn tail.
    let first = segment_path(tmp.path(), 0);
    let bytes = fs::read(&first).unwrap();
    fs::write(&first, &bytes[..bytes.len() - 3]).unwrap();
    let err = read_log(tmp.path()).unwrap_err();
    assert!(
        matches!(err, LogError::Corrupt { ref path, .. } if *path == first),
        "{err}"
    );
    fs::write(&first, &bytes).unwrap();

    // A missing segment is a gap; a bad magic is named.
    let second = segment_path(tmp.path(), 1);
    let moved = tmp.path().join("elsewhere");
    fs::rename(&second, &moved).unwrap();
    assert!(matches!(
        read_log(tmp.path()),
        Err(LogError::SegmentGap { expected: 1, .. })
    ));
    fs::rename(&moved, &second).unwrap();
    let mut bad_magic = fs::read(&second).unwrap();
    bad_magic[7] = b'2';
    fs::write(&second, &bad_magic).unwrap();
    assert!(matches!(read_log(tmp.path()), Err(LogError::BadMagic { path }) if path == second));
}

#[test]
fn header_rules_and_order_problems() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = |name: &str| -> PathBuf { tmp.path().join(name) };

    write_log(&dir("no-header"), &[round(1), round(2)], 1 << 20);
    assert!(matches!(
        read_log(dir("no-header")),
        Err(LogError::NoHeader { found: "round", .. })
    ));

    let Record::Header(mut h) = header() else {
        unreachable!()
    };
    h.version = FORMAT_VERSION + 1;
    write_log(&dir("version"), &[Record::Header(h)], 1 << 20);
    assert!(matches!(
        read_log(dir("version")),
        Err(LogError::Version { found: 2, .. })
    ));

    let unordered = [header(), round(1), round(3), round(3), round(2), header()];
    write_log(&dir("order"), &unordered, 1 << 20);
    let report = verify(dir("order"));
    assert_eq!(report.status(), VerifyStatus::NotIntact);
    assert_eq!(report.problems.len(), 3, "{:?}", report.problems);

    fs::create_dir(dir("empty")).unwrap();
    assert!(matches!(
        read_log(dir("empty")),
        Err(LogError::NoSegments { .. })
    ));
    assert_eq!(verify(dir("empty")).status(), VerifyStatus::Unreadable);
    assert_eq!(verify(dir("missing")).status(), VerifyStatus::Unreadable);

    // A last segment with only part of its magic (a crash while creating it) is torn.
    fs::create_dir(dir("new-segment")).unwrap();
    fs::write(segment_path(&dir("new-segment"), 0), &MAGIC[..3]).unwrap();
    let log = read_log(dir("new-segment")).unwrap();
    assert_eq!(log.records, []);
    assert_eq!(log.torn.map(|t| (t.offset, t.bytes)), Some((0, 3)));
}

#[test]
fn hnav_log_verify_and_show_exit_codes() {
    let tmp = tempfile::tempdir().unwrap();
    let good = tmp.path().join("good");
    let records = every_kind();
    let at = write_log(&good, &records, 1 << 20);

    let (code, out, _) = hnav(&["log", "verify", p(&good)]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("intact"), "{out}");

    let (code, out, _) = hnav(&["log", "show", p(&good)]);
    assert_eq!(code, 0);
    assert_eq!(out.lines().count(), records.len());
    assert!(
        out.contains("accept a0->[2,2] block a1 crossing (N,NE)"),
        "{out}"
    );
    assert!(out.lines().last().unwrap().contains("all-at-goal"), "{out}");

    let (code, out, _) = hnav(&["log", "show", "--json", p(&good)]);
    assert_eq!(code, 0);
    let lines: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), records.len());
    assert_eq!(lines[1]["kind"], "round");
    assert_eq!(lines[1]["round"], 1);
    assert_eq!(lines[1]["offset"], at[1].1);

    // Torn: verify 1, show 0 with a note.
    let torn = tmp.path().join("torn");
    write_log(&torn, &records, 1 << 20);
    let seg = segment_path(&torn, 0);
    let len = fs::metadata(&seg).unwrap().len();
    fs::OpenOptions::new()
        .write(true)
        .open(&seg)
        .unwrap()
        .set_len(len - 2)
        .unwrap();
    assert_eq!(hnav(&["log", "verify", p(&torn)]).0, 1);
    let (code, out, err) = hnav(&["log", "show", p(&torn)]);
    assert_eq!((code, out.lines().count()), (0, records.len() - 1));
    assert!(err.contains("torn tail"), "{err}");

    // Corrupt: both 1.
    let corrupt = tmp.path().join("corrupt");
    write_log(&corrupt, &records, 1 << 20);
    let seg = segment_path(&corrupt, 0);
    let mut bytes = fs::read(&seg).unwrap();
    bytes[at[2].1 + 9] ^= 0xFF;
    fs::write(&seg, bytes).unwrap();
    let (code, out, _) = hnav(&["log", "verify", p(&corrupt)]);
    assert_eq!(code, 1);
    assert!(out.contains(&format!("byte {}", at[2].1)), "{out}");
    let (code, out, err) = hnav(&["log", "show", p(&corrupt)]);
    assert_eq!((code, out.lines().count()), (1, 2));
    assert!(err.contains("corrupt"), "{err}");

    // Unreadable: 2.
    let missing = tmp.path().join("missing");
    assert_eq!(hnav(&["log", "verify", p(&missing)]).0, 2);
    assert_eq!(hnav(&["log", "show", p(&missing)]).0, 2);
    assert_eq!(hnav(&["log", "verify", p(tmp.path())]).0, 2);

    // Garbage in a segment never panics.
    let garbage = tmp.path().join("garbage");
    fs::create_dir(&garbage).unwrap();
    let mut junk = MAGIC.to_vec();
    junk.extend((0..4000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8));
    fs::write(segment_path(&garbage, 0), junk).unwrap();
    for args in [
        &["log", "verify"][..],
        &["log", "show"],
        &["log", "show", "--json"],
    ] {
        let mut args = args.to_vec();
        args.push(p(&garbage));
        let (code, _, err) = hnav(&args);
        assert!(code == 1 || code == 0, "{args:?}: {code} {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}
