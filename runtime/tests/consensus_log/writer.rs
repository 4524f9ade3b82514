//! The writer: round trips across reopen under every fsync policy, the header rule, rollover,
//! a torn segment magic rewritten, corruption refused unchanged, and (ignored) append latency
//! per fsync policy. Its recovery of a cut last record is tested with the reader's view of
//! the same cuts in `format`.

use std::fs;
use std::time::Instant;

use hnav_runtime::consensus_log::{
    read_log, segment_path, EndReason, EndRecord, LogError, LogWriter, Record, WriterOptions, MAGIC,
};
use hnav_runtime::scenario::FsyncPolicy;

use super::fixtures::{assert_intact, header, read_files, round};

#[test]
fn records_survive_reopen_and_appends_continue() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("a/b/log");
    let mut expected = vec![header(3)];
    {
        let (mut log, rec) = LogWriter::open(&dir, FsyncPolicy::EveryRecord).unwrap();
        assert_eq!(rec.records, []);
        assert_eq!(rec.truncated_bytes, 0);
        assert_eq!(log.append(&expected[0]).unwrap(), MAGIC.len() as u64);
        for n in 1..=5 {
            expected.push(round(n, 3));
            log.append(&expected[n as usize]).unwrap();
        }
        assert_eq!(log.records(), 6);
        assert_eq!(log.unsynced(), 0);
    }
    for policy in [FsyncPolicy::Batched, FsyncPolicy::None] {
        let (mut log, rec) = LogWriter::open(&dir, policy).unwrap();
        assert_eq!(rec.records, expected);
        assert_eq!(rec.truncated_bytes, 0);
        let n = expected.len() as u64;
        expected.push(round(n, 3));
        let at = log.append(expected.last().unwrap()).unwrap();
        assert_eq!(at, rec.positions.last().unwrap().end());
        log.sync().unwrap();
    }
    let (mut log, rec) = LogWriter::open(&dir, FsyncPolicy::EveryRecord).unwrap();
    assert_eq!(rec.records, expected);
    log.append(&Record::End(EndRecord {
        round: 7,
        at_goal: 3,
        reason: EndReason::AllAtGoal,
    }))
    .unwrap();
    drop(log);
    assert_intact(&dir);
    assert_eq!(read_log(&dir).unwrap().records.len(), expected.len() + 1);
}

#[test]
fn the_first_record_must_be_a_header() {
    let tmp = tempfile::tempdir().unwrap();
    let (mut log, _) = LogWriter::open(tmp.path(), FsyncPolicy::None).unwrap();
    assert!(matches!(
        log.append(&round(1, 1)),
        Err(LogError::NoHeader { .. })
    ));
    let Record::Header(mut h) = header(1) else {
        unreachable!()
    };
    h.version = 99;
    assert!(matches!(
        log.append(&Record::Header(h)),
        Err(LogError::Version { found: 99, .. })
    ));
    log.append(&header(1)).unwrap();
    log.append(&round(1, 1)).unwrap();
}

#[test]
fn a_torn_segment_magic_is_rewritten_and_corruption_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let opts = WriterOptions {
        fsync: FsyncPolicy::EveryRecord,
        segment_bytes: 200,
    };
    let mut records = vec![header(2)];
    records.extend((1..=20).map(|n| round(n, 2)));
    {
        let (mut log, _) = LogWriter::open_with(tmp.path(), opts).unwrap();
        for r in &records {
            log.append(r).unwrap();
        }
        assert!(log.segment() >= 3, "rolled over: segment {}", log.segment());
    }
    let log = read_log(tmp.path()).unwrap();
    assert_eq!(log.records, records);
    assert!(log
        .segments
        .iter()
        .all(|s| fs::metadata(s).unwrap().len() <= 200));
    assert_intact(tmp.path());

    // A crash right after creating the next segment leaves it (nearly) empty: the writer
    // removes it and goes on in the segment before, which still has room for the record
    // appended after the restart.
    let last = segment_path(tmp.path(), log.segments.len() as u32 - 1);
    let last_len = fs::metadata(&last).unwrap().len();
    let next = segment_path(tmp.path(), log.segments.len() as u32);
    fs::write(&next, &MAGIC[..5]).unwrap();
    {
        let (mut w, rec) = LogWriter::open_with(tmp.path(), opts).unwrap();
        assert_eq!((rec.records.len(), rec.truncated_bytes), (records.len(), 5));
        w.append(&round(21, 2)).unwrap();
        assert_eq!(w.segment() as usize, log.segments.len() - 1);
    }
    assert_intact(tmp.path());
    assert!(!next.exists(), "the empty segment is gone");
    assert!(fs::metadata(&last).unwrap().len() > last_len);

    // Only the magic (the crash came after it was written): the same.
    fs::write(&next, MAGIC).unwrap();
    let (_, rec) = LogWriter::open_with(tmp.path(), opts).unwrap();
    assert_eq!(rec.records.len(), records.len() + 1);
    assert!(!next.exists(), "the empty segment is gone");

    // Damage before the last complete record: open fails and changes nothing.
    let first = segment_path(tmp.path(), 0);
    let mut bytes = fs::read(&first).unwrap();
    bytes[20] ^= 1;
    fs::write(&first, &bytes).unwrap();
    let before = read_files(tmp.path());
    let err = LogWriter::open_with(tmp.path(), opts).unwrap_err();
    assert!(
        matches!(err, LogError::Corrupt { ref path, .. } if *path == first),
        "{err}"
    );
    assert_eq!(read_files(tmp.path()), before);
}

/// `cargo test -p hnav-runtime --release --test consensus_log -- --ignored --nocapture`
#[test]
#[ignore = "measurement; prints append latency per fsync policy"]
fn append_latency_per_policy() {
    // On the target's disk, not a tmpfs /tmp, so that fsync means something.
    let base = env!("CARGO_TARGET_TMPDIR");
    for (policy, n) in [
        (FsyncPolicy::None, 20_000u64),
        (FsyncPolicy::Batched, 20_000),
        (FsyncPolicy::EveryRecord, 2_000),
    ] {
        let tmp = tempfile::tempdir_in(base).unwrap();
        let (mut log, _) = LogWriter::open(tmp.path(), policy).unwrap();
        log.append(&header(16)).unwrap();
        let records: Vec<Record> = (1..=n).map(|r| round(r, 16)).collect();
        let mut lat = Vec::with_capacity(n as usize);
        let t0 = Instant::now();
        for r in &records {
            let t = Instant::now();
            log.append(r).unwrap();
            lat.push(t.elapsed().as_secs_f64() * 1e6);
        }
        let total = t0.elapsed().as_secs_f64() * 1e6 / n as f64;
        lat.sort_by(f64::total_cmp);
        let q = |f: f64| lat[((lat.len() - 1) as f64 * f) as usize];
        println!(
            "{policy:?}: {n} round records of 16 decisions ({} bytes): mean {total:.2} us/record, p50 {:.2}, p99 {:.2}, max {:.2}",
            log.segment_len() / n,
            q(0.5),
            q(0.99),
            q(1.0)
        );
    }
}

/// Two writers on one log would interleave their records (issue 11: two coordinators in one
/// `--out` directory): the second `open` is refused while the first writer lives, and the
/// log can be opened again once it is gone.
#[test]
fn a_second_writer_of_one_log_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("log");
    let (mut first, _) = LogWriter::open(&dir, FsyncPolicy::EveryRecord).unwrap();
    first.append(&header(2)).unwrap();
    let err = LogWriter::open(&dir, FsyncPolicy::EveryRecord).unwrap_err();
    assert!(matches!(err, LogError::Locked { .. }), "{err}");
    let text = err.to_string();
    assert!(
        text.contains(&dir.display().to_string())
            && text.contains(&format!("pid {}", std::process::id())),
        "{text}"
    );
    first.append(&round(1, 2)).unwrap();
    drop(first);
    let (mut again, rec) = LogWriter::open(&dir, FsyncPolicy::EveryRecord).unwrap();
    assert_eq!(rec.records.len(), 2);
    again.append(&round(2, 2)).unwrap();
    drop(again);
    assert_intact(&dir);
}
