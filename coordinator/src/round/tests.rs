//! The arbiter's round on small scenarios: missing agents, replans, the tally and its replay,
//! hostile candidates, PIBT's pushes.

use super::*;
use hnav_runtime::msg::ConflictKind;

fn scenario(text: &str) -> Scenario {
    Scenario::from_str(text, "test.toml", std::path::Path::new(".")).unwrap()
}

fn cand(s: &Scenario, agent: u32, cur: (u32, u32), prob: Option<(u32, u32)>) -> Candidate {
    let g = &s.map.grid;
    let cur = g.index(Cell::new(cur.0, cur.1)) as u32;
    Candidate {
        round: 1,
        agent,
        current: cur,
        next: cur,
        probable: prob.map_or(NO_CELL, |p| g.index(Cell::new(p.0, p.1)) as u32),
        ..Candidate::default()
    }
}

const TWO: &str = r#"
    name = "t"
    [map]
    rows = ["........", "........", "........"]
    [coordinator]
    rules = "dissertation"
    replan_after_rounds = 2
    [[agents]]
    start = [0, 1]
    goal = [7, 1]
    [[agents]]
    start = [2, 1]
    goal = [2, 0]
    speed = 0.5
"#;

#[test]
fn a_missing_agent_is_a_standing_obstacle() {
    let s = scenario(TWO);
    let mut a = Arbiter::new(&s);
    let c0 = cand(&s, 0, (1, 1), Some((2, 1)));
    let (d, _) = a.decide(1, &[Some(c0), None]);
    assert_eq!(d.len(), 1);
    assert_eq!(d[0].verdict, Verdict::Block as u8);
    assert_eq!(d[0].kind, ConflictKind::StableCell as u8);
    assert_eq!(d[0].cell, s.map.grid.index(Cell::new(2, 1)) as u32);
}

#[test]
fn waiting_too_long_gives_a_waypoint_around_the_blocker() {
    let s = scenario(TWO);
    let mut a = Arbiter::new(&s);
    let c0 = cand(&s, 0, (1, 1), Some((2, 1)));
    let c1 = cand(&s, 1, (2, 1), None);
    let (d, r) = a.decide(1, &[Some(c0), Some(c1)]);
    assert_eq!(d[0].verdict, Verdict::Hold as u8, "{d:?}");
    assert!(r.is_empty());
    let (d, r) = a.decide(2, &[Some(c0), Some(c1)]);
    assert_eq!(d[0].verdict, Verdict::Replan as u8);
    assert_eq!(r.len(), 1);
    let wp = s.map.grid.cell_at(d[0].waypoint as usize).unwrap();
    assert_ne!(wp, Cell::new(2, 1));
    // Round 1 held, round 2 replanned (as published, not also counted as held).
    assert_eq!(a.tally().agents()[0].replans, 1);
    assert_eq!(a.tally().agents()[0].conflicts, 1);
}

#[test]
fn the_tally_of_the_published_decisions_is_the_tally_of_their_replay() {
    let s = scenario(TWO);
    let mut live = Arbiter::new(&s);
    let mut replayed = Arbiter::new(&s);
    let c0 = cand(&s, 0, (1, 1), Some((2, 1)));
    let c1 = cand(&s, 1, (2, 1), Some((2, 0)));
    let c1_standing = cand(&s, 1, (2, 1), None);
    for (round, c1) in (1..).zip([c1_standing, c1_standing, c1, c1_standing]) {
        let (d, _) = live.decide(round, &[Some(c0), Some(c1)]);
        replayed.replay(&RoundRecord::new(round, &[], d));
    }
    let t = live.tally();
    assert_eq!(t, replayed.tally());
    // Agent 0: held, replanned, held (agent 1 leaving its cell), replanned.
    assert_eq!((t.conflicts(), t.replans()), (2, 2), "{t:?}");
    assert_eq!(t.agents()[1].steps, 1, "{t:?}");
}

#[test]
fn each_hostile_candidate_is_put_in_its_class() {
    let s = scenario(TWO);
    let a = Arbiter::new(&s);
    let g = &s.map.grid;
    let at = |x, y| g.index(Cell::new(x, y)) as u32;
    let good = Candidate {
        priority: 1.0,
        speed: 1.0,
        ..cand(&s, 0, (1, 1), Some((2, 1)))
    };
    assert_eq!(a.check(&good), Ok(()));
    let moving = Candidate {
        next: at(2, 2),
        probable: NO_CELL,
        ..good
    };
    assert_eq!(a.check(&moving), Ok(()));
    let bad: [(Candidate, Rejected); 12] = [
        (Candidate { agent: 2, ..good }, Rejected::Agent),
        (
            Candidate {
                agent: u32::MAX,
                ..good
            },
            Rejected::Agent,
        ),
        (
            Candidate {
                flags: 1 << 5,
                ..good
            },
            Rejected::Flags,
        ),
        (
            Candidate {
                reserved: 7,
                ..good
            },
            Rejected::Flags,
        ),
        (
            Candidate {
                priority: f32::NAN,
                ..good
            },
            Rejected::PrioritySpeed,
        ),
        (
            Candidate {
                speed: f32::INFINITY,
                ..good
            },
            Rejected::PrioritySpeed,
        ),
        (
            Candidate {
                priority: -1.0,
                ..good
            },
            Rejected::PrioritySpeed,
        ),
        (
            Candidate {
                priority: 2.0,
                ..good
            },
            Rejected::PrioritySpeed,
        ),
        (
            Candidate {
                current: 24,
                ..good
            },
            Rejected::Cell,
        ),
        (
            Candidate {
                next: at(3, 1),
                ..good
            },
            Rejected::Cell,
        ),
        (
            Candidate {
                probable: at(5, 1),
                ..good
            },
            Rejected::Cell,
        ),
        (
            Candidate {
                probable: 24,
                ..good
            },
            Rejected::Cell,
        ),
    ];
    for (c, class) in bad {
        assert_eq!(a.check(&c), Err(class), "{c:?}");
    }
}

#[test]
fn pibt_moves_an_agent_that_asked_nothing_and_replans_nobody() {
    let s = scenario(
        r#"
        name = "t"
        [map]
        rows = ["........", "........", "........"]
        [coordinator]
        rules = "pibt"
        replan_after_rounds = 2
        [[agents]]
        start = [0, 1]
        goal = [7, 1]
        [[agents]]
        start = [1, 1]
        goal = [1, 1]
    "#,
    );
    let mut a = Arbiter::new(&s);
    let g = &s.map.grid;
    let c0 = cand(&s, 0, (0, 1), Some((1, 1)));
    let c1 = Candidate {
        flags: CandidateFlags::AT_GOAL | CandidateFlags::STANDING,
        ..cand(&s, 1, (1, 1), None)
    };
    let (d, r) = a.decide(1, &[Some(c0), Some(c1)]);
    assert!(r.is_empty(), "no replans in pibt mode");
    // Agent 0 pushes agent 1 off its goal and waits for the cell.
    assert_eq!(d.len(), 2, "{d:?}");
    assert_eq!(d[0].verdict, Verdict::Hold as u8);
    assert_eq!(d[0].kind, ConflictKind::Reserved as u8);
    assert_eq!(d[1].verdict, Verdict::Accept as u8);
    assert_eq!(d[1].kind, ConflictKind::Pushed as u8);
    let to = g.cell_at(d[1].cell as usize).unwrap();
    assert!(Direction::between(Cell::new(1, 1), to).is_some());
    assert_ne!(to, Cell::new(0, 1));
    let cell = d[1].cell;
    // Agent 0 keeps waiting while agent 1 drives out, past replan_after_rounds = 2, and
    // is never replanned; agent 1, driving, gets no decision.
    for round in 2..=4 {
        let moving = Candidate {
            next: cell,
            flags: 0,
            ..c1
        };
        let (d, r) = a.decide(round, &[Some(c0), Some(moving)]);
        assert!(r.is_empty(), "no replans in pibt mode");
        assert_eq!(d.len(), 1, "{d:?}");
        assert_eq!(d[0].verdict, Verdict::Hold as u8);
    }
    // A push is a step; four holds for the same cell are one conflict and four rounds waited.
    assert_eq!(a.tally().agents()[1].steps, 1, "{:?}", a.tally());
    let t = a.tally().agents()[0];
    assert_eq!((t.conflicts, t.waited), (1, 4), "{t:?}");
}

/// Agent 0 drives west along row 2, agent 1 south down column 2, across its lane (the chaos
/// campaign's robots 2 and 5). Agent 0 is accepted into (3, 2), then, at rest there, into
/// (2, 2); agent 1 reaches (2, 1) and waits. Returns the arbiter that decided the two
/// rounds and their records, as the consensus log holds them.
fn agent_0_accepted_into_the_crossing(s: &Scenario) -> (Arbiter, Vec<RoundRecord>) {
    let mut a = Arbiter::new(s);
    let mut records = Vec::new();
    let rounds = [
        [
            cand(s, 0, (4, 2), Some((3, 2))),
            cand(s, 1, (2, 0), Some((2, 1))),
        ],
        [cand(s, 0, (3, 2), Some((2, 2))), cand(s, 1, (2, 1), None)],
    ];
    for (round, [c0, c1]) in (1..).zip(rounds) {
        let (d, _) = a.decide(round, &[Some(c0), Some(c1)]);
        assert!(
            d.iter().all(|d| d.verdict == Verdict::Accept as u8),
            "{d:?}"
        );
        records.push(RoundRecord::new(round, &[], d));
    }
    (a, records)
}

const CROSSING: &str = r#"
    name = "t"
    [map]
    rows = ["......", "......", "......", "......", "......"]
    [coordinator]
    rules = "dissertation"
    [[agents]]
    start = [4, 2]
    goal = [1, 2]
    [[agents]]
    start = [2, 0]
    goal = [2, 4]
"#;

/// Agent 1 asks for (2, 2) in round 3 while agent 0, committed to it in round 2, is silent
/// (killed on its way: its robot stands somewhere between (3, 2) and (2, 2)).
fn agent_1_asks_for_the_crossing(s: &Scenario, a: &mut Arbiter) -> Decision {
    let c1 = cand(s, 1, (2, 1), Some((2, 2)));
    let (d, _) = a.decide(3, &[None, Some(c1)]);
    assert_eq!(d.len(), 1, "{d:?}");
    d[0]
}

#[test]
fn a_silent_agent_keeps_the_cell_it_was_accepted_into() {
    let s = scenario(CROSSING);
    let (mut live, _) = agent_0_accepted_into_the_crossing(&s);
    let d = agent_1_asks_for_the_crossing(&s, &mut live);
    assert_eq!(d.verdict, Verdict::Block as u8, "{d:?}");
    assert_eq!(d.kind, ConflictKind::StableCell as u8, "{d:?}");
}

/// A coordinator restarted while agent 0 is down too (plans 3 and 11 of `hnav-bench chaos
/// --class kill-mix --seed 21`): it knows the robots only from its log, and must hold the
/// cells the log committed agent 0 to, not its start.
#[test]
fn a_restarted_arbiter_holds_the_logged_cells_of_a_silent_agent() {
    let s = scenario(CROSSING);
    let (_, records) = agent_0_accepted_into_the_crossing(&s);
    let mut restarted = Arbiter::new(&s);
    for r in &records {
        restarted.replay(r);
    }
    let d = agent_1_asks_for_the_crossing(&s, &mut restarted);
    assert_eq!(d.verdict, Verdict::Block as u8, "{d:?}");
    assert_eq!(d.kind, ConflictKind::StableCell as u8, "{d:?}");
}

/// A replica that starts from a snapshot has only the tally: a silent agent stands on the
/// cell of its last accepted move, not on its start.
#[test]
fn a_restored_tally_puts_a_silent_agent_on_its_last_accepted_cell() {
    let s = scenario(CROSSING);
    let (live, _) = agent_0_accepted_into_the_crossing(&s);
    let mut restored = Arbiter::new(&s);
    restored.restore_tally(live.tally().clone());
    let d = agent_1_asks_for_the_crossing(&s, &mut restored);
    assert_eq!(d.verdict, Verdict::Block as u8, "{d:?}");
}
