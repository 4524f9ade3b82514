//! The format as the reader and the verifier see it: records round-trip, a cut or damaged
//! last record is a torn tail (and the writer cuts exactly it on open), damage anywhere else
//! is corruption at its offset, segments and header rules.

use std::fs;
use std::path::{Path, PathBuf};

use hnav_runtime::consensus_log::{
    candidates_digest, encode_frame, read_log, segment_path, verify, EndReason, EndRecord,
    FrameProblem, LogError, LogWriter, LoggedDecision, Record, RoundRecord, VerifyStatus, MAGIC,
    REPLICATED_VERSION,
};
use hnav_runtime::msg::{Candidate, Decision};
use hnav_runtime::scenario::FsyncPolicy;

use super::fixtures::{assert_intact, every_kind, header, round, write_log, ONE_SEGMENT};

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
    let at = write_log(tmp.path(), &records, ONE_SEGMENT);
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

/// Cuts the log of `records` at every offset of its last record. Each cut is a torn tail the
/// reader reports without changing a byte; opening the log for writing cuts exactly it,
/// the lost record is written again, then `then`, and the log is intact.
fn cut_at_every_offset_of_the_last_record(tmp: &Path, records: &[Record], then: &[Record]) {
    let full = tmp.join("full");
    let at = write_log(&full, records, ONE_SEGMENT);
    let bytes = fs::read(segment_path(&full, 0)).unwrap();
    let last = at.last().unwrap().1;
    let (lost, kept) = records.split_last().unwrap();
    for cut in last..bytes.len() {
        let dir = tmp.join(format!("cut-{cut}"));
        fs::create_dir(&dir).unwrap();
        fs::write(segment_path(&dir, 0), &bytes[..cut]).unwrap();
        let log = read_log(&dir).unwrap_or_else(|e| panic!("cut at {cut}: {e}"));
        assert_eq!(log.records, kept, "cut at {cut}");
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
        {
            let (mut log, rec) = LogWriter::open(&dir, FsyncPolicy::EveryRecord)
                .unwrap_or_else(|e| panic!("cut at {cut}: {e}"));
            assert_eq!(rec.records, kept, "cut at {cut}");
            assert_eq!(rec.truncated_bytes, (cut - last) as u64);
            assert_eq!(rec.torn.is_some(), cut > last);
            assert_eq!(log.segment_len(), last as u64);
            // The lost record is decided again, then the run goes on.
            assert_eq!(log.append(lost).unwrap(), last as u64);
            for r in then {
                log.append(r).unwrap();
            }
        }
        assert_intact(&dir);
        let mut expected = records.to_vec();
        expected.extend_from_slice(then);
        assert_eq!(read_log(&dir).unwrap().records, expected);
        fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn a_cut_at_every_offset_of_a_final_end_record_is_a_torn_tail_cut_on_open() {
    let tmp = tempfile::tempdir().unwrap();
    cut_at_every_offset_of_the_last_record(tmp.path(), &every_kind(), &[]);
}

#[test]
fn a_cut_at_every_offset_of_a_final_round_record_is_a_torn_tail_cut_on_open() {
    let tmp = tempfile::tempdir().unwrap();
    let mut records = vec![header(4)];
    records.extend((1..=4).map(|n| round(n, 4)));
    cut_at_every_offset_of_the_last_record(tmp.path(), &records, &[round(5, 4)]);
}

#[test]
fn a_damaged_final_record_and_a_zero_filled_tail_are_torn() {
    let tmp = tempfile::tempdir().unwrap();
    let records = every_kind();
    let at = write_log(tmp.path(), &records, ONE_SEGMENT);
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
    let at = write_log(tmp.path(), &records, ONE_SEGMENT);
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
    let mut records = vec![header(2)];
    records.extend((1..=40).map(|n| round(n, 2)));
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

    // The writer refuses both logs; they are its output with the header frame removed, or
    // swapped for one of another version.
    let at = write_log(
        &dir("no-header"),
        &[header(2), round(1, 2), round(2, 2)],
        ONE_SEGMENT,
    );
    let seg = segment_path(&dir("no-header"), 0);
    let mut bytes = fs::read(&seg).unwrap();
    bytes.drain(at[0].1..at[1].1);
    fs::write(&seg, bytes).unwrap();
    assert!(matches!(
        read_log(dir("no-header")),
        Err(LogError::NoHeader { found: "round", .. })
    ));

    write_log(&dir("version"), &[header(2)], ONE_SEGMENT);
    let Record::Header(mut h) = header(2) else {
        unreachable!()
    };
    h.version = REPLICATED_VERSION + 1;
    let seg = segment_path(&dir("version"), 0);
    let mut bytes = fs::read(&seg).unwrap();
    bytes.truncate(MAGIC.len());
    encode_frame(&Record::Header(h), &mut bytes).unwrap();
    fs::write(&seg, bytes).unwrap();
    assert!(matches!(
        read_log(dir("version")),
        Err(LogError::Version { found: 3, .. })
    ));

    // The writer checks only the first record; order is the verifier's business.
    let unordered = [
        header(2),
        round(1, 2),
        round(3, 2),
        round(3, 2),
        round(2, 2),
        header(2),
    ];
    write_log(&dir("order"), &unordered, ONE_SEGMENT);
    let report = verify(dir("order"));
    assert_eq!(report.status(), VerifyStatus::NotIntact);
    // Round 3 after 1 (round 2 missing), 3 after 3, 2 after 3, a second header.
    assert_eq!(report.problems.len(), 4, "{:?}", report.problems);

    fs::create_dir(dir("empty")).unwrap();
    assert!(matches!(
        read_log(dir("empty")),
        Err(LogError::NoSegments { .. })
    ));
    assert_eq!(verify(dir("empty")).status(), VerifyStatus::Unreadable);
    assert_eq!(verify(dir("missing")).status(), VerifyStatus::Unreadable);

    // A last segment with only part of its magic (a crash while creating it) is torn.
    write_log(&dir("new-segment"), &[], ONE_SEGMENT);
    let seg = segment_path(&dir("new-segment"), 0);
    assert_eq!(fs::read(&seg).unwrap(), MAGIC, "a new log is its magic");
    fs::OpenOptions::new()
        .write(true)
        .open(&seg)
        .unwrap()
        .set_len(3)
        .unwrap();
    let log = read_log(dir("new-segment")).unwrap();
    assert_eq!(log.records, []);
    assert_eq!(log.torn.map(|t| (t.offset, t.bytes)), Some((0, 3)));
}
