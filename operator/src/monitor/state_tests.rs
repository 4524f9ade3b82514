use super::*;
use hnav_runtime::grid::Grid;
use hnav_runtime::msg::{Commit, Truth};

/// A 4 x 2 room, cells 1 m wide, agent 0 from cell 0 to cell 2, agent 1 from 4 to 7.
fn view() -> ViewState {
    ViewState::new(RunInfo {
        run_id: "t".into(),
        mode: "lockstep".into(),
        rules: "lacam".into(),
        grid: Grid::new(4, 2).unwrap(),
        starts: vec![0, 4],
        goals: vec![2, 7],
        cell_size_m: 1.0,
        changes: Vec::new(),
        sensor_range: None,
    })
}

fn commit(round: u64, decisions: &[(u32, Verdict, ConflictKind, u32)]) -> Commit {
    let mut c = Commit {
        round,
        decisions: vec![Decision::default(); decisions.len()],
        ..Commit::default()
    };
    for (slot, &(agent, verdict, kind, cell)) in c.decisions.iter_mut().zip(decisions) {
        *slot = Decision {
            agent,
            verdict: verdict as u8,
            kind: kind as u8,
            cell,
            ..Decision::default()
        };
    }
    c
}

fn truth(period: u64, poses: &[(f64, f64)]) -> Truth {
    let mut t = Truth {
        period,
        poses: vec![Pose::default(); poses.len()],
        ..Truth::default()
    };
    for (slot, &(x_m, y_m)) in t.poses.iter_mut().zip(poses) {
        *slot = Pose {
            x_m,
            y_m,
            theta_rad: 0.0,
        };
    }
    t
}

fn states(v: &ViewState) -> Vec<AgentState> {
    v.agents.iter().map(AgentView::state).collect()
}

use ConflictKind as K;
use Verdict as V;

#[test]
fn decisions_and_ground_truth_make_the_states() {
    let mut v = view();
    let now = Instant::now();
    assert_eq!(states(&v), [AgentState::Waiting; 2]);
    v.apply(
        Update::Truth(truth(1, &[(0.5, 0.5), (0.5, 1.5)]).view()),
        now,
    );
    v.apply(
        Update::Commit(
            commit(
                1,
                &[(0, V::Accept, K::None, 1), (1, V::Block, K::HeadOn, 0)],
            )
            .view(),
        ),
        now,
    );
    assert_eq!(states(&v), [AgentState::Moving, AgentState::Blocked]);
    // Driving: "held, nothing asked" keeps a pending move moving, even with the pose still.
    v.apply(
        Update::Truth(truth(2, &[(0.5, 0.5), (0.5, 1.5)]).view()),
        now,
    );
    v.apply(
        Update::Commit(commit(2, &[(0, V::Hold, K::None, 0), (1, V::Replan, K::None, 0)]).view()),
        now,
    );
    assert_eq!(states(&v), [AgentState::Moving, AgentState::Replanning]);
    // Agent 0 arrives in cell 1 and stands there: held by a conflict now.
    v.apply(
        Update::Truth(truth(3, &[(1.5, 0.5), (0.5, 1.5)]).view()),
        now,
    );
    v.apply(
        Update::Truth(truth(4, &[(1.5, 0.5), (0.5, 1.5)]).view()),
        now,
    );
    v.apply(
        Update::Commit(
            commit(
                3,
                &[(0, V::Hold, K::Crossing, 0), (1, V::Hold, K::Reserved, 0)],
            )
            .view(),
        ),
        now,
    );
    assert_eq!(states(&v), [AgentState::Held, AgentState::Held]);
    // On to the goal: moving until ground truth is in it, then at goal.
    v.apply(
        Update::Commit(commit(4, &[(0, V::Accept, K::None, 2), (1, V::Hold, K::None, 0)]).view()),
        now,
    );
    v.apply(
        Update::Truth(truth(5, &[(1.9, 0.5), (0.5, 1.5)]).view()),
        now,
    );
    assert_eq!(v.agents[0].state(), AgentState::Moving);
    v.apply(
        Update::Truth(truth(6, &[(2.1, 0.5), (0.5, 1.5)]).view()),
        now,
    );
    v.apply(
        Update::Commit(commit(5, &[(0, V::Hold, K::None, 0), (1, V::Hold, K::None, 0)]).view()),
        now,
    );
    assert_eq!(v.agents[0].state(), AgentState::AtGoal);
    assert_eq!(v.at_goal(), 1);
}

#[test]
fn a_robot_that_moves_is_moving_even_when_its_accept_was_missed() {
    let mut v = view();
    let now = Instant::now();
    v.apply(
        Update::Commit(commit(1, &[(0, V::Hold, K::None, 0)]).view()),
        now,
    );
    v.apply(
        Update::Truth(truth(1, &[(0.5, 0.5), (0.5, 1.5)]).view()),
        now,
    );
    assert_eq!(v.agents[0].state(), AgentState::Held);
    v.apply(
        Update::Truth(truth(2, &[(0.8, 0.5), (0.5, 1.5)]).view()),
        now,
    );
    assert_eq!(v.agents[0].state(), AgentState::Moving);
    // An older period (a restarted sim's repeat) changes nothing.
    v.apply(
        Update::Truth(truth(1, &[(3.5, 0.5), (0.5, 1.5)]).view()),
        now,
    );
    assert_eq!(v.agents[0].cell, Some(0));
}

#[test]
fn down_and_lost_come_from_the_lifecycle_topic() {
    let mut v = view();
    let now = Instant::now();
    v.apply(Update::Lifecycle(&Lifecycle::down(Role::Agent, 1, 0)), now);
    assert_eq!(v.agents[1].state(), AgentState::Down);
    v.apply(
        Update::Lifecycle(&Lifecycle::restarted(Role::Agent, 1, 1)),
        now,
    );
    assert_eq!(v.agents[1].state(), AgentState::Waiting);
    v.apply(Update::Lifecycle(&Lifecycle::lost(Role::Agent, 0, 3)), now);
    assert_eq!(v.agents[0].state(), AgentState::Down);
    assert!(v.agents[0].lost());
    // The coordinator's death is a line of its own and nobody's state.
    v.apply(
        Update::Lifecycle(&Lifecycle::down(Role::Coordinator, 0, 0)),
        now,
    );
    let events: Vec<_> = v
        .events
        .iter()
        .map(|e| (e.role.name(), e.event.name()))
        .collect();
    assert_eq!(
        events,
        [
            ("agent", "down"),
            ("agent", "restarted"),
            ("agent", "lost"),
            ("coordinator", "down")
        ]
    );
    assert!(v.recent.is_empty(), "process events are not decisions");
    assert_eq!(v.ended, None);
    v.apply(
        Update::Lifecycle(&Lifecycle::stop(hnav_runtime::msg::StopReason::Requested)),
        now,
    );
    assert_eq!(v.ended, Some(RunEnd::Stopped));
}

#[test]
fn a_restart_stays_in_view_under_a_flood_of_holds() {
    let mut v = view();
    let now = Instant::now();
    v.apply(Update::Lifecycle(&Lifecycle::down(Role::Agent, 1, 0)), now);
    v.apply(
        Update::Lifecycle(&Lifecycle::restarted(Role::Agent, 1, 1)),
        now,
    );
    // lacam: both robots wait for their turn, held every round for the same cell.
    for round in 1..=500 {
        v.apply(
            Update::Commit(
                commit(
                    round,
                    &[(0, V::Hold, K::Reserved, 1), (1, V::Hold, K::Reserved, 5)],
                )
                .view(),
            ),
            now,
        );
    }
    let events: Vec<_> = v.events.iter().map(|e| e.event.name()).collect();
    assert_eq!(events, ["down", "restarted"]);
    // One line per robot's waiting request, with its latest round and count.
    let lines: Vec<(u32, u64, u32)> = v
        .recent
        .iter()
        .map(|l| (l.agent, l.round, l.times))
        .collect();
    assert_eq!(lines, [(0, 500, 500), (1, 500, 500)]);
    // Another cell asked is another line.
    v.apply(
        Update::Commit(commit(501, &[(0, V::Hold, K::Reserved, 2)]).view()),
        now,
    );
    assert_eq!(v.recent.len(), 3);
    // Drawn: the events pane keeps the restart.
    let mut t = ratatui::Terminal::new(ratatui::backend::TestBackend::new(120, 30)).unwrap();
    t.draw(|f| super::super::view::draw(f, &v, now, super::super::view::Hints::default()))
        .unwrap();
    let text: String = t
        .backend()
        .buffer()
        .content()
        .iter()
        .map(|c| c.symbol())
        .collect();
    assert!(text.contains("process events"), "{text}");
    assert!(text.contains("agent-1 restarted"), "{text}");
    assert!(text.contains("reserved x500"), "{text}");
}

#[test]
fn the_latest_records_skip_idle_holds_and_keep_ten() {
    let mut v = view();
    let now = Instant::now();
    for round in 1..=15 {
        v.apply(
            Update::Commit(
                commit(
                    round,
                    &[(0, V::Accept, K::None, 1), (1, V::Hold, K::None, 0)],
                )
                .view(),
            ),
            now,
        );
    }
    assert_eq!(v.recent.len(), RECENT);
    let rounds: Vec<u64> = v
        .recent
        .iter()
        .map(|l| {
            assert_eq!(l.agent, 0);
            l.round
        })
        .collect();
    assert_eq!(rounds, (6..=15).collect::<Vec<_>>());
}

#[test]
fn missed_and_repeated_commits_are_counted_once() {
    let mut v = view();
    let now = Instant::now();
    v.apply(Update::Commit(commit(10, &[]).view()), now);
    v.apply(Update::Commit(commit(14, &[]).view()), now);
    v.apply(Update::Commit(commit(14, &[]).view()), now);
    v.apply(Update::Commit(commit(15, &[]).view()), now);
    assert_eq!((v.round, v.missed_commits), (15, 3));
}

#[test]
fn progress_ends_the_run_with_its_reason() {
    let mut v = view();
    let now = Instant::now();
    v.apply(
        Update::Progress(&Progress {
            round: 7,
            ..Progress::default()
        }),
        now,
    );
    assert_eq!((v.round, v.ended), (7, None));
    let done = Progress {
        round: 9,
        done: Progress::ALL_AT_GOAL,
        ..Progress::default()
    };
    v.apply(Update::Progress(&done), now);
    assert_eq!(v.ended, Some(RunEnd::AllAtGoal));
    // The first reason stays.
    v.apply(Update::Ended(RunEnd::SupervisorGone), now);
    assert_eq!(v.ended, Some(RunEnd::AllAtGoal));
    assert_eq!(v.rounds_per_s(now), 0.0);
}

#[test]
fn the_rate_is_rounds_over_the_last_second() {
    let mut m = RateMeter::default();
    let t0 = Instant::now();
    assert_eq!(m.rate(t0), 0.0);
    // 100 rounds every 100 ms for 3 s: 1000 rounds/s.
    for i in 0..=30u64 {
        m.note(t0 + Duration::from_millis(100 * i), 100 * i);
    }
    let end = t0 + Duration::from_secs(3);
    assert!((m.rate(end) - 1000.0).abs() < 1e-6, "{}", m.rate(end));
    // Half a second without a round: half the rate.
    let later = end + Duration::from_millis(500);
    assert!((m.rate(later) - 500.0).abs() < 1.0, "{}", m.rate(later));
    // Only the last second is kept.
    assert!(m.samples.len() <= 12, "{}", m.samples.len());
    // A young meter measures what it has.
    let mut young = RateMeter::default();
    young.note(t0, 0);
    young.note(t0 + Duration::from_millis(200), 50);
    let r = young.rate(t0 + Duration::from_millis(200));
    assert!((r - 250.0).abs() < 1e-6, "{r}");
}

#[test]
fn the_map_follows_the_worlds_closes_and_opens_as_sim_time_passes_them() {
    let mut v = view();
    v.info.changes = vec![
        super::super::feed::WorldStep {
            at_ns: 1_000,
            cells: vec![5, 6],
            closed: true,
        },
        super::super::feed::WorldStep {
            at_ns: 3_000,
            cells: vec![6],
            closed: false,
        },
    ];
    let blocked =
        |v: &ViewState| -> Vec<usize> { (0..8).filter(|&i| v.info.grid.blocked()[i]).collect() };
    let at = |period: u64, ns: u64| Truth {
        sim_time_ns: ns,
        ..truth(period, &[(0.5, 0.5), (0.5, 1.5)])
    };
    let now = Instant::now();
    v.apply(Update::Truth(at(1, 999).view()), now);
    assert!(blocked(&v).is_empty());
    v.apply(Update::Truth(at(2, 1_000).view()), now);
    assert_eq!(blocked(&v), [5, 6]);
    v.apply(Update::Truth(at(3, 5_000).view()), now);
    assert_eq!(blocked(&v), [5]);
}

#[test]
fn the_sensed_cells_are_each_robots_latest_view() {
    let mut v = view();
    let now = Instant::now();
    assert!(v.sensed().iter().all(|s| !s));
    let mut seen = View {
        agent: 1,
        ..View::default()
    };
    seen.reset(0, 1, 2);
    seen.mark(0, 1, false);
    seen.mark(1, 1, true);
    v.apply(Update::View(&seen), now);
    let cells = |v: &ViewState| -> Vec<usize> { (0..8).filter(|&i| v.sensed()[i]).collect() };
    assert_eq!(cells(&v), [4, 5]);
    seen.reset(2, 0, 2);
    seen.mark(3, 0, false);
    v.apply(Update::View(&seen), now);
    assert_eq!(cells(&v), [3], "the latest view replaces the one before");
    let stranger = View { agent: 7, ..seen };
    v.apply(Update::View(&stranger), now);
    assert_eq!(
        cells(&v),
        [3],
        "a view of a robot not in the run is ignored"
    );
}

#[test]
fn movers_replace_the_last_and_are_placed_on_their_cells() {
    let mut v = view();
    assert_eq!(v.mover_cells().count(), 0);
    let at = |x_m, y_m| MoverPlace {
        mover: 0,
        reserved: 0,
        pose: Pose {
            x_m,
            y_m,
            theta_rad: 0.0,
        },
    };
    v.apply(
        Update::Movers(&[at(1.5, 0.5), at(3.5, 1.5)]),
        Instant::now(),
    );
    assert_eq!(v.mover_cells().collect::<Vec<_>>(), [1, 7]);
    // Off the map is nowhere; a later sample replaces the whole picture.
    v.apply(Update::Movers(&[at(9.0, 0.5)]), Instant::now());
    assert_eq!(v.mover_cells().count(), 0);
    assert_eq!(v.movers.len(), 1);
}
