//! What the verifier catches beyond damaged bytes: complete records that are gone (a round
//! removed from the middle of a segment, records cut from the end of a segment that is not
//! the last) and records out of place around the end record.

use std::fs;
use std::path::Path;

use hnav_runtime::consensus_log::{
    segment_path, verify, EndReason, EndRecord, LifecycleRecord, Record, ReplanRecord, VerifyStatus,
};

use super::fixtures::{assert_intact, header, round, write_log, ONE_SEGMENT};

/// Removes the frames of records `from..to` (indices into what `write_log` returned) from
/// their segment, which must hold all of them.
fn remove_frames(dir: &Path, at: &[(u32, usize)], from: usize, to: usize) {
    let segment = at[from].0;
    assert_eq!(
        at[to].0, segment,
        "the removed records and the next share a segment"
    );
    let path = segment_path(dir, segment);
    let mut bytes = fs::read(&path).unwrap();
    bytes.drain(at[from].1..at[to].1);
    fs::write(&path, bytes).unwrap();
}

fn problems(dir: &Path) -> String {
    let report = verify(dir);
    assert_eq!(
        report.status(),
        VerifyStatus::NotIntact,
        "{}",
        report.render()
    );
    report.problems.join("\n")
}

fn end(round: u64) -> Record {
    Record::End(EndRecord {
        round,
        at_goal: 1,
        reason: EndReason::AllAtGoal,
    })
}

fn lifecycle(round: u64) -> Record {
    Record::Lifecycle(LifecycleRecord {
        round,
        role: 3,
        index: 1,
        event: 3,
        restarts: 1,
    })
}

#[test]
fn a_round_removed_from_the_middle_of_a_segment_is_a_gap_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    let mut records = vec![header(2)];
    records.extend((1..=10).map(|n| round(n, 2)));
    records.push(end(10));
    let (one, three) = (tmp.path().join("one"), tmp.path().join("three"));
    let at = write_log(&one, &records, ONE_SEGMENT);
    write_log(&three, &records, ONE_SEGMENT);
    assert_intact(&one);

    // records[5] is round 5.
    remove_frames(&one, &at, 5, 6);
    let p = problems(&one);
    assert!(
        p.contains("round 5 is missing (round 6 follows round 4)"),
        "{p}"
    );
    remove_frames(&three, &at, 5, 8);
    let p = problems(&three);
    assert!(
        p.contains("rounds 5 to 7 are missing (round 8 follows round 4)"),
        "{p}"
    );

    // The first round is round 1.
    let late = tmp.path().join("late");
    write_log(&late, &[header(2), round(2, 2)], ONE_SEGMENT);
    assert!(problems(&late).contains("round 1 is missing"));
}

#[test]
fn rounds_cut_from_the_end_of_a_segment_that_is_not_the_last_are_found() {
    let tmp = tempfile::tempdir().unwrap();
    let mut records = vec![header(2)];
    records.extend((1..=40).map(|n| round(n, 2)));
    let at = write_log(tmp.path(), &records, 300);
    assert!(at.last().unwrap().0 >= 3, "several segments");
    assert_intact(tmp.path());

    // Cut segment 1 exactly at the start of its last record: every byte left is a complete
    // record, so only the rounds tell.
    let last_of_1 = at.iter().rposition(|&(s, _)| s == 1).unwrap();
    let path = segment_path(tmp.path(), 1);
    let bytes = fs::read(&path).unwrap();
    fs::write(&path, &bytes[..at[last_of_1].1]).unwrap();
    let missing = format!("round {last_of_1} is missing");
    let p = problems(tmp.path());
    assert!(p.contains(&missing), "{p}");
    assert!(p.contains("seg-00000001.hlog ends after"), "{p}");
}

#[test]
fn records_without_a_round_of_their_own_cut_from_a_segment_end_are_found() {
    // Only lifecycle records after round 1, all the same size: no round can go missing, the
    // segment sizes must tell.
    let tmp = tempfile::tempdir().unwrap();
    let mut records = vec![header(2), round(1, 2)];
    records.extend((0..60).map(|_| lifecycle(1)));
    let at = write_log(tmp.path(), &records, 200);
    assert!(at.last().unwrap().0 >= 3, "several segments");
    assert_intact(tmp.path());

    let last_of_2 = at.iter().rposition(|&(s, _)| s == 2).unwrap();
    let path = segment_path(tmp.path(), 2);
    let bytes = fs::read(&path).unwrap();
    fs::write(&path, &bytes[..at[last_of_2].1]).unwrap();
    let p = problems(tmp.path());
    assert!(
        p.contains("seg-00000002.hlog ends after")
            && p.contains("complete records are missing at its end"),
        "{p}"
    );
}

#[test]
fn the_end_record_closes_the_log() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = |name: &str| tmp.path().join(name);

    write_log(
        &dir("open"),
        &[header(2), round(1, 2), round(2, 2)],
        ONE_SEGMENT,
    );
    let report = verify(dir("open"));
    assert_eq!(report.status(), VerifyStatus::Intact, "{}", report.render());
    assert!(!report.has_end(), "not closed");
    assert!(report.render().contains("status     intact, not closed"));

    let after = [header(2), round(1, 2), end(1), round(2, 2), lifecycle(2)];
    write_log(&dir("after"), &after, ONE_SEGMENT);
    let p = problems(&dir("after"));
    assert!(p.contains("round record after the end record"), "{p}");
    assert!(p.contains("lifecycle record after the end record"), "{p}");

    write_log(
        &dir("early"),
        &[header(2), round(1, 2), round(2, 2), end(1)],
        ONE_SEGMENT,
    );
    let p = problems(&dir("early"));
    assert!(
        p.contains("end record for round 1, but the last round logged before it is 2"),
        "{p}"
    );
}

#[test]
fn replan_and_lifecycle_records_belong_to_their_round() {
    let tmp = tempfile::tempdir().unwrap();
    let replan = |round| {
        Record::Replan(ReplanRecord {
            round,
            agent: 1,
            planner: "lazy-theta-star".into(),
            found: true,
            waypoints: vec![12, 14],
        })
    };
    // As the coordinator writes them: a replan just before its round (twice, as after a
    // crash between the replan and the round record), lifecycle events after the last round.
    let good = [
        header(2),
        lifecycle(0),
        replan(1),
        replan(1),
        round(1, 2),
        lifecycle(1),
        replan(2),
        round(2, 2),
        end(2),
    ];
    write_log(&tmp.path().join("good"), &good, ONE_SEGMENT);
    assert_intact(&tmp.path().join("good"));

    let bad = [header(2), round(1, 2), replan(1), lifecycle(3), round(2, 2)];
    write_log(&tmp.path().join("bad"), &bad, ONE_SEGMENT);
    let p = problems(&tmp.path().join("bad"));
    assert!(p.contains("replan record for round 1, but the last round logged before it is 1 (expected round 2)"), "{p}");
    assert!(p.contains("lifecycle record for round 3"), "{p}");
}
