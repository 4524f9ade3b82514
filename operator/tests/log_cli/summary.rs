//! The run summary reads its per-agent numbers from the log (its `Tally`) and the goals from
//! the ground truth.

use hnav_operator::supervisor::summary::RunSummary;
use hnav_runtime::consensus_log::{
    EndReason, EndRecord, LogWriter, LoggedDecision, Record, RoundRecord,
};
use hnav_runtime::msg::{Pose, Truth, Verdict, NO_CELL};
use hnav_runtime::scenario::FsyncPolicy;

use super::fixtures::{header, round, write_log, ONE_SEGMENT};

#[test]
fn the_summary_is_the_tally_of_the_log_and_the_truth_of_the_goals() {
    let tmp = tempfile::tempdir().unwrap();
    // Agent 0 moves 11 -> 22 (diagonal) and stays, agent 1 is blocked every round for the same
    // cell (one conflict: the same refusal repeated); in round 5 agent 0 goes on to 33
    // (diagonal) and agent 1 is replanned.
    let mut records = vec![header(2)];
    records.extend((1..=4).map(|n| round(n, 2)));
    let decision = |agent, verdict: Verdict, cell| LoggedDecision {
        agent,
        verdict: verdict as u8,
        refused: 0,
        kind: 0,
        cell,
        waypoint: NO_CELL,
    };
    let fifth = RoundRecord {
        round: 5,
        candidates: 2,
        candidates_digest: 5,
        decisions: vec![
            decision(0, Verdict::Accept, 33),
            decision(1, Verdict::Replan, NO_CELL),
        ],
    };
    records.push(Record::Round(fifth));
    write_log(tmp.path(), &records, ONE_SEGMENT);

    let summary = RunSummary::from_log("t", tmp.path(), None, 1.0, 0.5, None).unwrap();
    assert_eq!(
        (summary.mode.as_str(), summary.end.as_str()),
        ("lockstep", "incomplete")
    );
    assert_eq!(summary.rounds, 5);
    let [a, b] = &summary.agents[..] else {
        panic!("two agents: {summary:?}")
    };
    assert_eq!((a.id, a.steps, a.conflicts, a.replans), (0, 5, 0, 0));
    assert_eq!(a.length, 2.0 * std::f64::consts::SQRT_2);
    assert_eq!(
        (b.id, b.steps, b.conflicts, b.waited, b.replans),
        (1, 0, 1, 0, 1)
    );
    assert_eq!(b.length, 0.0);
    assert!(!a.reached_goal && !b.reached_goal, "no truth, no goal");

    // The goals of header(2) are cells 79 = [9,7] and 78 = [8,7].
    let mut truth = Truth {
        poses: vec![Pose::default(); 2],
        collisions: 1,
        ..Truth::default()
    };
    truth.poses[0] = Pose {
        x_m: 9.5,
        y_m: 7.5,
        theta_rad: 0.0,
    };
    truth.poses[1] = Pose {
        x_m: 8.5,
        y_m: 6.5,
        theta_rad: 0.0,
    };
    {
        let (mut log, _) = LogWriter::open(tmp.path(), FsyncPolicy::None).unwrap();
        log.append(&Record::End(EndRecord {
            round: 5,
            at_goal: 1,
            reason: EndReason::TimeLimit,
        }))
        .unwrap();
    }
    let summary = RunSummary::from_log("t", tmp.path(), Some(&truth), 1.0, 0.5, None).unwrap();
    let goals: Vec<bool> = summary.agents.iter().map(|a| a.reached_goal).collect();
    assert_eq!(goals, [true, false]);
    assert_eq!(
        (summary.collisions, summary.end.as_str()),
        (1, "time-limit")
    );
    assert!(!summary.success());
}
