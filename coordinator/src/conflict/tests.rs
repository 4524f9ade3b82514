//! One test per rule and kind, on small hand-made situations.

use hnav_runtime::grid::{Cell, CornerCutting, Direction, Grid};
use hnav_runtime::msg::{ConflictKind, Verdict, NO_CELL};

use super::{side_cells, AgentMode, AgentRow, Options, Outcome, Resolver};

fn c(x: u32, y: u32) -> Cell {
    Cell::new(x, y)
}

fn ask(from: Cell, to: Cell, priority: f64) -> AgentRow {
    AgentRow::at_rest(from, Some(to), priority)
}

fn moving(from: Cell, to: Cell) -> AgentRow {
    AgentRow {
        current: from,
        next: to,
        probable: None,
        priority: 1.0,
        mode: AgentMode::Active,
    }
}

fn with_mode(cell: Cell, mode: AgentMode) -> AgentRow {
    AgentRow {
        mode,
        ..AgentRow::at_rest(cell, None, 100.0)
    }
}

fn run_on(grid: &Grid, options: Options, rows: &[AgentRow]) -> Vec<Outcome> {
    let mut r = Resolver::new(grid, rows.len(), options);
    let mut out = Vec::new();
    r.resolve(rows, &mut out);
    assert_eq!(out.len(), rows.len());
    out
}

fn run(rows: &[AgentRow]) -> Vec<Outcome> {
    run_on(&Grid::new(6, 6).unwrap(), Options::default(), rows)
}

fn bit(d: Direction) -> u8 {
    1 << d.index()
}

#[track_caller]
fn expect(o: &Outcome, verdict: Verdict, kind: ConflictKind, other: Option<u32>) {
    assert_eq!(
        (o.verdict, o.kind, o.other),
        (verdict, kind, other),
        "{o:?}"
    );
}

#[test]
fn a_free_step_is_accepted() {
    let out = run(&[ask(c(1, 1), c(2, 2), 1.0), ask(c(4, 4), c(4, 3), 1.0)]);
    expect(&out[0], Verdict::Accept, ConflictKind::None, None);
    assert_eq!((out[0].cell, out[0].refused), (Some(c(2, 2)), 0));
    expect(&out[1], Verdict::Accept, ConflictKind::None, None);
}

#[test]
fn rule_1_invalid_requests() {
    let g = Grid::from_rows(&["......", "..@...", "......"]).unwrap();
    let rows = [
        ask(c(0, 0), c(2, 0), 1.0), // not a neighbour
        ask(c(5, 0), c(6, 0), 1.0), // off the grid (east)
        ask(c(1, 2), c(2, 1), 1.0), // blocked cell (north-east)
        ask(c(4, 2), c(4, 2), 1.0), // its own cell
    ];
    let out = run_on(&g, Options::default(), &rows);
    for o in &out {
        assert_eq!((o.verdict, o.kind), (Verdict::Block, ConflictKind::Invalid));
    }
    assert_eq!((out[0].refused, out[0].cell), (0, Some(c(2, 0))));
    assert_eq!((out[1].refused, out[1].cell), (bit(Direction::E), None));
    assert_eq!(out[2].refused, bit(Direction::NE));
    assert_eq!(out[3].refused, 0);
}

#[test]
fn rule_2_map_corners_follow_fig_3_7() {
    // The diagonal (0,0) -> (1,1) with one, then both, side cells blocked.
    let one = Grid::from_rows(&[".@..", "....", "...."]).unwrap();
    let two = Grid::from_rows(&[".@..", "@...", "...."]).unwrap();
    let row = [ask(c(0, 0), c(1, 1), 1.0)];
    let forbidden = Options::default();
    let allowed = Options {
        corner_cutting: CornerCutting::Allowed,
        ..Options::default()
    };
    let o = run_on(&one, forbidden, &row)[0];
    expect(&o, Verdict::Block, ConflictKind::CornerCut, None);
    assert_eq!(o.refused, bit(Direction::SE));
    expect(
        &run_on(&one, allowed, &row)[0],
        Verdict::Accept,
        ConflictKind::None,
        None,
    );
    expect(
        &run_on(&two, allowed, &row)[0],
        Verdict::Block,
        ConflictKind::CornerCut,
        None,
    );
}

#[test]
fn rule_2_a_diagonal_past_another_agent_is_a_corner_cut() {
    // Agent 1 stands (at rest, asking nothing) in a side cell of agent 0's diagonal.
    let out = run(&[
        ask(c(1, 1), c(2, 2), 9.0),
        AgentRow::at_rest(c(2, 1), None, 1.0),
    ]);
    expect(&out[0], Verdict::Block, ConflictKind::CornerCut, Some(1));
    assert_eq!(out[0].refused, bit(Direction::SE));
    expect(&out[1], Verdict::Hold, ConflictKind::None, None);
    // Point robots (no sweep) may pass.
    let opts = Options {
        sweep: false,
        ..Options::default()
    };
    let out = run_on(
        &Grid::new(6, 6).unwrap(),
        opts,
        &[
            ask(c(1, 1), c(2, 2), 9.0),
            AgentRow::at_rest(c(2, 1), None, 1.0),
        ],
    );
    expect(&out[0], Verdict::Accept, ConflictKind::None, None);
}

#[test]
fn rule_3_stable_cells_refuse_whatever_the_priority() {
    for mode in [AgentMode::Standing, AgentMode::Finished] {
        let out = run(&[ask(c(1, 1), c(2, 1), 1e9), with_mode(c(2, 1), mode)]);
        expect(&out[0], Verdict::Block, ConflictKind::StableCell, Some(1));
        assert_eq!(out[0].refused, bit(Direction::E));
        expect(&out[1], Verdict::Hold, ConflictKind::None, None);
    }
    // A standing agent that is still on its way (dead while driving) holds both cells.
    let dead = AgentRow {
        mode: AgentMode::Standing,
        ..moving(c(3, 3), c(3, 2))
    };
    let out = run(&[ask(c(2, 2), c(3, 2), 5.0), dead]);
    expect(&out[0], Verdict::Block, ConflictKind::StableCell, Some(1));
}

#[test]
fn rule_4_head_on_lower_yields_higher_holds() {
    let out = run(&[ask(c(1, 1), c(2, 1), 3.0), ask(c(2, 1), c(1, 1), 2.0)]);
    expect(&out[0], Verdict::Hold, ConflictKind::HeadOn, Some(1));
    assert_eq!(out[0].refused, 0);
    expect(&out[1], Verdict::Block, ConflictKind::HeadOn, Some(0));
    assert_eq!(out[1].refused, bit(Direction::W));
    assert_eq!(out[1].cell, Some(c(1, 1)));
}

#[test]
fn rule_4_head_on_equal_priorities_both_deviate() {
    let out = run(&[ask(c(1, 1), c(2, 2), 1.0), ask(c(2, 2), c(1, 1), 1.0)]);
    expect(&out[0], Verdict::Block, ConflictKind::HeadOn, Some(1));
    expect(&out[1], Verdict::Block, ConflictKind::HeadOn, Some(0));
    assert_eq!(out[0].refused, bit(Direction::SE));
    assert_eq!(out[1].refused, bit(Direction::NW));
}

#[test]
fn rule_5_cells_being_left_are_reserved() {
    // Into the cell a robot is leaving, into the cell it drives to, into a swept side cell.
    let out = run(&[
        moving(c(2, 2), c(3, 2)),
        ask(c(1, 2), c(2, 2), 9.0),
        ask(c(4, 2), c(3, 2), 9.0),
        moving(c(0, 4), c(1, 5)),
        ask(c(2, 4), c(1, 4), 9.0),
    ]);
    expect(&out[0], Verdict::Hold, ConflictKind::None, None);
    expect(&out[1], Verdict::Hold, ConflictKind::Reserved, Some(0));
    expect(&out[2], Verdict::Hold, ConflictKind::Reserved, Some(0));
    expect(&out[4], Verdict::Hold, ConflictKind::Reserved, Some(3));
    assert_eq!(out[1].refused, 0);
    // Following an agent that is itself asking to move on is still a wait.
    let out = run(&[ask(c(2, 2), c(3, 2), 1.0), ask(c(1, 2), c(2, 2), 9.0)]);
    expect(&out[0], Verdict::Accept, ConflictKind::None, None);
    expect(&out[1], Verdict::Hold, ConflictKind::Reserved, Some(0));
}

#[test]
fn rule_6_crossing_same_cell_priority_and_ties() {
    let out = run(&[ask(c(1, 1), c(2, 2), 1.0), ask(c(3, 3), c(2, 2), 2.0)]);
    expect(&out[0], Verdict::Block, ConflictKind::Crossing, Some(1));
    assert_eq!(out[0].refused, bit(Direction::SE));
    expect(&out[1], Verdict::Accept, ConflictKind::None, None);
    // Equal: all refused, whatever the order (a revoked request still stops its equals).
    let out = run(&[
        ask(c(1, 2), c(2, 2), 1.0),
        ask(c(3, 2), c(2, 2), 1.0),
        ask(c(2, 3), c(2, 2), 1.0),
    ]);
    for o in &out {
        assert_eq!(
            (o.verdict, o.kind),
            (Verdict::Block, ConflictKind::Crossing)
        );
    }
}

#[test]
fn rule_6_crossing_diagonals_sweep_each_other() {
    // A: (0,1) -> (1,2) sweeps (1,1) and (0,2); B: (2,2) -> (1,1) sweeps (1,2) and (2,1).
    let out = run(&[ask(c(0, 1), c(1, 2), 2.0), ask(c(2, 2), c(1, 1), 1.0)]);
    expect(&out[0], Verdict::Accept, ConflictKind::None, None);
    expect(&out[1], Verdict::Block, ConflictKind::Crossing, Some(0));
    // Two diagonals sharing only a side cell: (1,1) -> (2,2) sweeps (2,1) and (1,2);
    // (2,0) -> (3,1) sweeps (3,0) and (2,1).
    let out = run(&[ask(c(1, 1), c(2, 2), 1.0), ask(c(2, 0), c(3, 1), 1.0)]);
    expect(&out[0], Verdict::Block, ConflictKind::Crossing, Some(1));
    expect(&out[1], Verdict::Block, ConflictKind::Crossing, Some(0));
}

#[test]
fn rule_6_no_cascade_through_refused_requests() {
    // 0 (high) and 1 (middle) want the same cell, so 1 is refused.
    let out = run(&[
        ask(c(2, 1), c(2, 2), 3.0),
        ask(c(1, 3), c(2, 2), 2.0), // NE, sweeps (2,3) and (1,2)
        ask(c(0, 3), c(1, 2), 1.0), // NE, sweeps (1,3) and (0,2)
    ]);
    expect(&out[0], Verdict::Accept, ConflictKind::None, None);
    expect(&out[1], Verdict::Block, ConflictKind::Crossing, Some(0));
    // Agent 2's side cell (1,3) is agent 1's current cell: a corner cut, not a crossing.
    expect(&out[2], Verdict::Block, ConflictKind::CornerCut, Some(1));
    // 2 conflicts only with 1, which is refused, so 2 goes.
    let out = run(&[
        ask(c(2, 1), c(2, 2), 3.0),
        ask(c(3, 3), c(2, 2), 2.0), // NW, sweeps (2,3) and (3,2)
        ask(c(1, 3), c(2, 3), 1.0), // E into (2,3): meets only agent 1's footprint
    ]);
    expect(&out[0], Verdict::Accept, ConflictKind::None, None);
    expect(&out[1], Verdict::Block, ConflictKind::Crossing, Some(0));
    expect(&out[2], Verdict::Accept, ConflictKind::None, None);
}

#[test]
fn combined_head_on_and_crossing() {
    // Diagonal head-on between 0 and 1; agent 2 wants (1,0), a side cell of both diagonals.
    let out = run(&[
        ask(c(0, 0), c(1, 1), 1.0),
        ask(c(1, 1), c(0, 0), 2.0),
        ask(c(2, 0), c(1, 0), 3.0),
    ]);
    expect(&out[0], Verdict::Block, ConflictKind::Combined, Some(1));
    expect(&out[1], Verdict::Hold, ConflictKind::Combined, Some(0));
    expect(&out[2], Verdict::Accept, ConflictKind::None, None);
}

#[test]
fn rule_7_nothing_asked_or_not_allowed_to_ask() {
    let out = run(&[
        AgentRow::at_rest(c(0, 0), None, 1.0),
        AgentRow {
            probable: Some(c(4, 3)),
            ..moving(c(4, 4), c(3, 4))
        },
        AgentRow {
            probable: Some(c(1, 5)),
            ..with_mode(c(1, 4), AgentMode::Finished)
        },
    ]);
    for o in &out {
        assert_eq!(*o, Outcome::default());
    }
}

#[test]
fn decisions_encode_the_outcome() {
    let g = Grid::new(6, 6).unwrap();
    let out = run(&[ask(c(1, 1), c(2, 2), 1.0), ask(c(3, 3), c(2, 2), 2.0)]);
    let d = out[1].decision(1, &g);
    assert_eq!((d.agent, d.verdict, d.kind), (1, Verdict::Accept as u8, 0));
    assert_eq!(d.cell as usize, g.index(c(2, 2)));
    let d = out[0].decision(0, &g);
    assert_eq!(d.verdict, Verdict::Block as u8);
    assert_eq!(d.kind, ConflictKind::Crossing as u8);
    assert_eq!(d.refused, bit(Direction::SE));
    assert_eq!((d.cell, d.waypoint), (NO_CELL, NO_CELL));
}

#[test]
fn held_cells_and_side_cells() {
    assert_eq!(side_cells(c(1, 1), c(2, 2)), Some([c(2, 1), c(1, 2)]));
    assert_eq!(side_cells(c(1, 1), c(2, 1)), None);
    assert_eq!(side_cells(c(1, 1), c(3, 3)), None);
    let row = moving(c(1, 1), c(0, 2));
    let opts = Options::default();
    assert_eq!(
        row.held(&opts),
        [Some(c(1, 1)), Some(c(0, 2)), Some(c(0, 1)), Some(c(1, 2))]
    );
    let points = Options {
        sweep: false,
        ..opts
    };
    assert_eq!(
        row.held(&points),
        [Some(c(1, 1)), Some(c(0, 2)), None, None]
    );
}

#[test]
fn buffers_are_reused_and_rounds_independent() {
    let g = Grid::new(6, 6).unwrap();
    let mut r = Resolver::new(&g, 2, Options::default());
    let mut out = Vec::with_capacity(8);
    let rows = [ask(c(1, 1), c(2, 2), 1.0), ask(c(3, 3), c(2, 2), 2.0)];
    r.resolve(&rows, &mut out);
    let first = out.clone();
    for _ in 0..1000 {
        r.resolve(&[ask(c(0, 0), c(1, 0), 1.0)], &mut out);
        r.resolve(&rows, &mut out);
        assert_eq!(out, first);
    }
    assert_eq!(out.capacity(), 8);
    // More rows than announced: the buffers grow once and it still works.
    let many: Vec<AgentRow> = (0..6).map(|x| ask(c(x, 0), c(x, 1), 1.0)).collect();
    r.resolve(&many, &mut out);
    assert!(out.iter().all(Outcome::accepted));
    // A changed map.
    let mut g2 = g.clone();
    g2.set_blocked(c(2, 2), true);
    r.set_map(&g2);
    r.resolve(&rows, &mut out);
    assert_eq!(out[1].kind, ConflictKind::Invalid);
}
